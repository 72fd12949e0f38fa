/// Fuzz harness: the TOML configuration and its --set overrides (md/config/ConfigParser.h). The
/// input is the TOML text, then optionally a line "%%" and one override "section.key=value" per
/// line. A configuration that parses and validates must also survive its own round trip: the
/// TOML that granagg writes into every output (toToml) reads back to the same keys and values.
#include <string>
#include <vector>

#include "FuzzTarget.h"
#include "md/config/ConfigParser.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  std::string text = input;
  std::vector<std::string> overrides;
  if (const auto sep = input.find("\n%%\n"); sep != std::string::npos) {
    text = input.substr(0, sep);
    std::string rest = input.substr(sep + 4);
    std::size_t start = 0;
    while (start <= rest.size() && overrides.size() < 16) {
      const std::size_t end = rest.find('\n', start);
      overrides.push_back(rest.substr(start, end == std::string::npos ? end : end - start));
      if (end == std::string::npos) break;
      start = end + 1;
    }
  }
  granagg::fuzz::guarded([&] {
    using namespace granagg::md;
    const MdConfig c = parseConfigString(text, "fuzz.toml", overrides);
    validateConfig(c);
    const MdConfig back = parseConfigString(toToml(c), "round-trip.toml");
    if (flatten(back) != flatten(c))
      granagg::fuzz::defect("round trip", "toToml(c) does not read back to c");
  });
  return 0;
}
