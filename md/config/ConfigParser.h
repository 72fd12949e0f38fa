#pragma once
/// \file ConfigParser.h
/// Reads, checks and writes the TOML configuration of an MD run (md/config/MdConfig.h; every key
/// with its default, units and range is documented in docs/config.md).
///
///     MdConfig c = parseConfigFile("run.toml", {"system.N=2000", "integrator.dt=auto"});
///     std::string text = toToml(c);      // stored in /parameters of every output
///     assert(flatten(parseConfigString(text, "stored")) == flatten(c));   // exact round trip
///
/// All errors are std::invalid_argument (ConfigError), one line per problem, each starting with
/// where the value came from: "run.toml:4:1: unknown key 'system.Nn' (known keys in [system]: N,
/// phi, seed, temperature, initial, initial_max_overlap)", or "--set system.N=1: system.N = 1 is
/// invalid: must be >= 2".
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "md/config/MdConfig.h"

namespace granagg::md {

/// The configuration format version this build reads and writes ([input] version).
inline constexpr int CONFIG_VERSION = 1;

/// A configuration error. what() is the full message; key() names the offending key
/// ("system.phi") when the error concerns one key, and is empty otherwise (syntax errors, a file
/// that cannot be read, several errors reported together).
class ConfigError : public std::invalid_argument {
 public:
  ConfigError(const std::string& message, std::string key)
      : std::invalid_argument(message), m_key(std::move(key)) {}
  /// "section.key", or "" when the error is not about a single key.
  const std::string& key() const noexcept { return m_key; }

 private:
  std::string m_key;
};

/// Parses the TOML file at `path`, then applies `overrides` ("--set" strings, see
/// parseConfigString), then validates (validateConfig). Throws ConfigError if the file cannot be
/// read, is not valid TOML, has unknown sections or keys, values of the wrong type, or values out
/// of range; messages start with "path:line:column: " (or "--set key=value: " for an override).
MdConfig parseConfigFile(const std::string& path, const std::vector<std::string>& overrides = {});

/// Same as parseConfigFile for TOML `text`; `source_name` is the file name used in messages.
/// Both record in MdConfig::origin where each key given in the text or an override was set.
///
/// Rules:
/// - Every section and key is optional (defaults of MdConfig.h); unknown ones are errors that list
///   the known keys. `[input] version` defaults to 1 and no other version is accepted.
/// - Integer keys need TOML integers; real keys accept integers or floats; `integrator.dt` and
///   `integrator.impact_speed_max` accept "auto" (stored as 0.0) or a number > 0, and
///   `integrator.dt` also "adaptive" (stored as 0.0 with IntegratorConfig::adaptive).
/// - Each override is "section.key=value", applied after the file in the given order. The value is
///   read as a TOML value (2000, 0.1, 1e-3, true, "text"); a value that is not valid TOML, such as
///   a bare word (auto, spring_dashpot, data/start.csv), is taken as a string, and string keys
///   always take the unquoted text as it is. Overrides get the same checks as the file.
MdConfig parseConfigString(const std::string& text, const std::string& source_name,
                           const std::vector<std::string>& overrides = {});

/// Throws ConfigError (an std::invalid_argument) naming the first key whose value is unphysical
/// or unusable, its value and the allowed range, e.g. "system.phi = 0.7 is invalid: must lie in
/// (0, 0.6)". Keys are checked in the order of toToml. Non-finite reals are always rejected.
void validateConfig(const MdConfig& config);

/// Edge length of the periodic cube, L = (N pi / (6 phi))^(1/3), in particle diameters.
/// Throws std::invalid_argument unless N >= 1 and phi > 0.
double boxLength(const SystemConfig& system);

/// The complete configuration as TOML text: every section and key, in the order of
/// docs/config.md, reals with round-trip precision, "auto" where integrator.dt or
/// integrator.impact_speed_max is 0 ("adaptive" for an adaptive dt). parseConfigString(toToml(c),
/// ...) gives back exactly c (for any c that passes validateConfig).
std::string toToml(const MdConfig& config);

/// The configuration as ("section.key", value) pairs in the order of toToml, for provenance
/// (CSV headers, HDF5 attributes): integers in decimal, reals via common::formatReal (shortest
/// round-trip form), booleans "true"/"false", strings unquoted, "auto" for a zero
/// integrator.dt or integrator.impact_speed_max ("adaptive" for an adaptive dt). Includes
/// "input.version".
std::vector<std::pair<std::string, std::string>> flatten(const MdConfig& config);

}  // namespace granagg::md
