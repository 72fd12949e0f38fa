/// \file ConfigParser.cpp
/// One schema table (section, key, member of MdConfig, type) drives parsing, unknown-key messages,
/// toToml and flatten, so the four cannot disagree about which keys exist or their order.
#include "md/config/ConfigParser.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string_view>
#include <variant>

#include "common/Csv.h"
#include "common/Strings.h"
#include "md/potentials/ContactModels.h"

namespace granagg::md {
namespace {

// ---------------------------------------------------------------------------------------------
// Schema

using IntRef = int& (*)(MdConfig&);
using LongRef = long& (*)(MdConfig&);
using SeedRef = std::uint64_t& (*)(MdConfig&);
using RealRef = double& (*)(MdConfig&);
using BoolRef = bool& (*)(MdConfig&);
using StringRef = std::string& (*)(MdConfig&);
using Ref = std::variant<IntRef, LongRef, SeedRef, RealRef, BoolRef, StringRef>;

struct Key {
  std::string name;
  Ref ref;
  bool auto_allowed = false;  ///< real key where the string "auto" means 0.0
};

struct Section {
  std::string name;
  std::vector<Key> keys;
};

// A captureless lambda returning a reference to the member, converted to a function pointer.
// clang-format off
#define GRANAGG_KEY(section, field) \
  Key{#field, +[](MdConfig& c) -> decltype((c.section.field)) { return c.section.field; }}
// clang-format on

const std::vector<Section>& schema() {
  static const std::vector<Section> s = {
      {"input", {Key{"version", +[](MdConfig& c) -> int& { return c.input_version; }}}},
      {"system",
       {GRANAGG_KEY(system, N), GRANAGG_KEY(system, phi), GRANAGG_KEY(system, seed),
        GRANAGG_KEY(system, temperature), GRANAGG_KEY(system, initial),
        Key{"initial_max_overlap",
            +[](MdConfig& c) -> double& { return c.system.initial_max_overlap; }, true}}},
      {"contact",
       {GRANAGG_KEY(contact, model), GRANAGG_KEY(contact, E), GRANAGG_KEY(contact, D),
        GRANAGG_KEY(contact, clamp), GRANAGG_KEY(contact, stiffness),
        GRANAGG_KEY(contact, restitution)}},
      {"integrator",
       {Key{"dt", +[](MdConfig& c) -> double& { return c.integrator.dt; }, true},
        GRANAGG_KEY(integrator, steps_per_contact),
        Key{"impact_speed_max",
            +[](MdConfig& c) -> double& { return c.integrator.impact_speed_max; }, true}}},
      {"neighbor", {Key{"skin", +[](MdConfig& c) -> double& { return c.neighbor.skin; }, true}}},
      {"charging",
       {GRANAGG_KEY(charging, mode), GRANAGG_KEY(charging, initial), GRANAGG_KEY(charging, q0),
        GRANAGG_KEY(charging, Q), GRANAGG_KEY(charging, kappa), GRANAGG_KEY(charging, psi1_min),
        GRANAGG_KEY(charging, psi1_max), GRANAGG_KEY(charging, psi2_fraction)}},
      {"coulomb",
       {GRANAGG_KEY(coulomb, K), GRANAGG_KEY(coulomb, method), GRANAGG_KEY(coulomb, accuracy),
        Key{"r_cut", +[](MdConfig& c) -> double& { return c.coulomb.r_cut; }, true},
        Key{"mesh", +[](MdConfig& c) -> int& { return c.coulomb.mesh; }, true},
        Key{"order", +[](MdConfig& c) -> int& { return c.coulomb.order; }, true},
        Key{"every", +[](MdConfig& c) -> int& { return c.coulomb.every; }, true},
        Key{"every_max", +[](MdConfig& c) -> int& { return c.coulomb.every_max; }, true},
        Key{"skin", +[](MdConfig& c) -> double& { return c.coulomb.skin; }, true},
        Key{"r_fast", +[](MdConfig& c) -> double& { return c.coulomb.r_fast; }, true}}},
      {"run", {GRANAGG_KEY(run, t_end), GRANAGG_KEY(run, max_overlap)}},
      {"output",
       {GRANAGG_KEY(output, frames_per_decade), GRANAGG_KEY(output, frame_interval),
        GRANAGG_KEY(output, observable_interval), GRANAGG_KEY(output, checkpoint_interval),
        GRANAGG_KEY(output, checkpoint_wall_seconds), GRANAGG_KEY(output, write_velocities),
        GRANAGG_KEY(output, write_forces), GRANAGG_KEY(output, trajectory),
        GRANAGG_KEY(output, analyze)}},
  };
  return s;
}
#undef GRANAGG_KEY

const Section* findSection(std::string_view name) {
  for (const auto& s : schema())
    if (s.name == name) return &s;
  return nullptr;
}

const Key* findKey(const Section& section, std::string_view name) {
  for (const auto& k : section.keys)
    if (k.name == name) return &k;
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Messages

std::string lower(std::string s) {
  for (auto& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

// Case-insensitive Levenshtein distance, for "did you mean" hints.
std::size_t editDistance(const std::string& a0, const std::string& b0) {
  const std::string a = lower(a0), b = lower(b0);
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// "; did you mean 'x'?" for the closest candidate within 2 edits (and closer than the word's
// length, so that one-letter typos do not match everything), or "".
std::string suggestion(const std::string& word, const std::vector<std::string>& candidates) {
  std::size_t best = std::numeric_limits<std::size_t>::max();
  std::string best_name;
  for (const auto& c : candidates) {
    const std::size_t d = editDistance(word, c);
    if (d < best) best = d, best_name = c;
  }
  if (best <= 2 && best < std::max<std::size_t>(word.size(), 1))
    return "; did you mean '" + best_name + "'?";
  return "";
}

/// The section md stores as TOML text without reading it (MdConfig::analysis).
constexpr const char* OPAQUE_SECTION = "analysis";

std::string sectionList() {
  std::string out;
  for (const auto& s : schema()) out += (out.empty() ? "" : ", ") + s.name;
  return out + ", " + OPAQUE_SECTION;
}

std::string keyList(const Section& section) {
  std::string out;
  for (const auto& k : section.keys) out += (out.empty() ? "" : ", ") + k.name;
  return out;
}

std::string unknownKeyMessage(const std::string& section, const std::string& key) {
  if (section.empty()) {
    // A key outside any section: suggest "section.key" if the name exists somewhere.
    for (const auto& s : schema())
      for (const auto& k : s.keys)
        if (lower(k.name) == lower(key))
          return "unknown key '" + key +
                 "' at top level (keys belong in a section; known sections: " + sectionList() +
                 "); did you mean '" + s.name + "." + k.name + "'?";
    return "unknown key '" + key +
           "' at top level (keys belong in a section; known sections: " + sectionList() + ")";
  }
  const Section* s = findSection(section);
  if (!s) {
    std::vector<std::string> names;
    for (const auto& sec : schema()) names.push_back(sec.name);
    return "unknown section '" + section + "' (known sections: " + sectionList() + ")" +
           suggestion(section, names);
  }
  std::vector<std::string> names;
  for (const auto& k : s->keys) names.push_back(k.name);
  std::string hint = suggestion(key, names);
  if (!hint.empty()) hint = "; did you mean '" + section + "." + hint.substr(hint.find('\'') + 1);
  return "unknown key '" + section + "." + key + "' (known keys in [" + section +
         "]: " + keyList(*s) + ")" + hint;
}

// TOML basic string with escapes (also used to quote strings in messages).
std::string quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char ch : s) {
    switch (ch) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\f':
        out += "\\f";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (ch < 0x20 || ch == 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04X", ch);
          out += buf;
        } else {
          out += static_cast<char>(ch);
        }
    }
  }
  return out + "\"";
}

// A real as a TOML float literal: shortest round-trip digits, always with '.' or an exponent so
// that it reads back as a float (20000 -> 20000.0); inf and nan are TOML literals too.
std::string tomlReal(double x) {
  std::string s = common::formatReal(x);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

// What a TOML node holds, for type errors: "float 2000.5", "string \"abc\"", "table".
std::string describe(const toml::node& node) {
  if (auto v = node.as_integer()) return "integer " + std::to_string(v->get());
  if (auto v = node.as_floating_point()) return "float " + common::formatReal(v->get());
  if (auto v = node.as_boolean()) return std::string("boolean ") + (v->get() ? "true" : "false");
  if (auto v = node.as_string()) return "string " + quote(v->get());
  if (node.is_table()) return "a table";
  if (node.is_array()) return "an array";
  if (node.is_date()) return "a date";
  if (node.is_time()) return "a time";
  if (node.is_date_time()) return "a date-time";
  return "an unknown value";
}

std::string where(const toml::source_region& r, const std::string& fallback) {
  std::string path = r.path ? *r.path : fallback;
  if (!r.begin) return path;
  return path + ":" + std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column);
}

// An error found while reading (before validation): position for sorting, message, key.
struct Issue {
  std::uint64_t line = 0, column = 0;
  std::string message;
  std::string key;
};

[[noreturn]] void invalid(const std::string& key, const std::string& value,
                          const std::string& rule) {
  throw ConfigError(key + " = " + value + " is invalid: must " + rule, key);
}

// ---------------------------------------------------------------------------------------------
// Assigning one TOML value to one key

// Sets the member of `config` named by `key` from `node`; returns "" or an error message (without
// location). `full` is "section.key".
std::string assign(const Key& key, const std::string& full, const toml::node& node,
                   MdConfig& config) {
  const std::string got = ", got " + describe(node);
  if (auto r = std::get_if<IntRef>(&key.ref)) {
    if (auto str = node.as_string(); str && key.auto_allowed && str->get() == "auto") {
      (*r)(config) = 0;  // zero is how "auto" is stored
      return "";
    }
    auto v = node.as_integer();
    if (!v)
      return full + (key.auto_allowed ? " must be an integer or \"auto\"" : " must be an integer") +
             got;
    if (key.auto_allowed && v->get() <= 0)
      return full + " = " + std::to_string(v->get()) + " is invalid: must be > 0 or \"auto\"";
    if (v->get() < std::numeric_limits<int>::min() || v->get() > std::numeric_limits<int>::max())
      return full + " = " + std::to_string(v->get()) + " is out of range for a 32-bit integer";
    (*r)(config) = static_cast<int>(v->get());
  } else if (auto r = std::get_if<LongRef>(&key.ref)) {
    auto v = node.as_integer();
    if (!v) return full + " must be an integer" + got;
    if (v->get() < std::numeric_limits<long>::min() || v->get() > std::numeric_limits<long>::max())
      return full + " = " + std::to_string(v->get()) + " is out of range for a long integer";
    (*r)(config) = static_cast<long>(v->get());
  } else if (auto r = std::get_if<SeedRef>(&key.ref)) {
    // TOML integers are signed 64-bit; seeds beyond 2^63 - 1 are written as decimal strings.
    if (auto v = node.as_integer()) {
      if (v->get() < 0)
        return full + " must be a non-negative integer, got integer " + std::to_string(v->get());
      (*r)(config) = static_cast<std::uint64_t>(v->get());
    } else if (auto s = node.as_string()) {
      const std::string& t = s->get();
      const bool digits =
          !t.empty() && t.size() <= 20 &&
          std::all_of(t.begin(), t.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
      errno = 0;
      char* end = nullptr;
      const unsigned long long u = digits ? std::strtoull(t.c_str(), &end, 10) : 0;
      if (!digits || errno == ERANGE)
        return full + " must be a non-negative integer (below 2^64)" + got;
      (*r)(config) = static_cast<std::uint64_t>(u);
    } else {
      return full + " must be a non-negative integer" + got;
    }
  } else if (auto r = std::get_if<RealRef>(&key.ref)) {
    const bool time_step = full == "integrator.dt";
    if (time_step) config.integrator.adaptive = false;
    if (auto s = node.as_string(); s && time_step && s->get() == "adaptive") {
      (*r)(config) = 0.0;  // starts at the "auto" step
      config.integrator.adaptive = true;
      return "";
    }
    double x = 0.0;
    if (auto v = node.as_floating_point()) {
      x = v->get();
    } else if (auto v = node.as_integer()) {
      x = static_cast<double>(v->get());
    } else if (auto s = node.as_string(); s && key.auto_allowed && s->get() == "auto") {
      (*r)(config) = 0.0;
      return "";
    } else {
      const char* what = time_step            ? " must be a number, \"auto\" or \"adaptive\""
                         : key.auto_allowed ? " must be a number or \"auto\""
                                            : " must be a number";
      return full + what + got;
    }
    // Zero is how "auto" is stored, so an explicit value must be positive.
    if (key.auto_allowed && !(x > 0.0))
      return full + " = " + common::formatReal(x) + " is invalid: must be > 0" +
             (time_step ? ", \"auto\" or \"adaptive\"" : " or \"auto\"");
    (*r)(config) = x;
  } else if (auto r = std::get_if<BoolRef>(&key.ref)) {
    auto v = node.as_boolean();
    if (!v) return full + " must be a boolean (true or false)" + got;
    (*r)(config) = v->get();
  } else if (auto r = std::get_if<StringRef>(&key.ref)) {
    auto v = node.as_string();
    if (!v) return full + " must be a string" + got;
    (*r)(config) = v->get();
  }
  return "";
}

// A value of the opaque section as TOML text: a number, a boolean, a string or an array of
// numbers (what the options of granagg analyze take); returns "" or an error message.
std::string opaqueText(const std::string& full, const toml::node& node, std::string& text) {
  if (auto v = node.as_integer()) {
    text = std::to_string(v->get());
  } else if (auto v = node.as_floating_point()) {
    text = tomlReal(v->get());
  } else if (auto v = node.as_boolean()) {
    text = v->get() ? "true" : "false";
  } else if (auto v = node.as_string()) {
    text = quote(v->get());
  } else if (auto a = node.as_array()) {
    text = "[";
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::node& e = *a->get(i);
      std::string item;
      if (e.is_array() || e.is_table() || !opaqueText(full, e, item).empty())
        return full + " must be a number, a boolean, a string or an array of numbers, got an "
                      "array holding " + describe(e);
      text += (i ? ", " : "") + item;
    }
    text += "]";
  } else {
    return full + " must be a number, a boolean, a string or an array of numbers, got " +
           describe(node);
  }
  return "";
}

toml::table parseToml(const std::string& text, const std::string& source_name) {
#if TOML_EXCEPTIONS
  try {
    return toml::parse(std::string_view(text), std::string_view(source_name));
  } catch (const toml::parse_error& e) {
    throw ConfigError(
        where(e.source(), source_name) + ": invalid TOML: " + std::string(e.description()), "");
  }
#else
  toml::parse_result res = toml::parse(std::string_view(text), std::string_view(source_name));
  if (!res)
    throw ConfigError(where(res.error().source(), source_name) +
                          ": invalid TOML: " + std::string(res.error().description()),
                      "");
  return std::move(res).table();
#endif
}

// Reads every section of `root` into `config`; records where each key was set.
void readTable(const toml::table& root, const std::string& source_name, MdConfig& config,
               std::map<std::string, std::string>& origin) {
  std::vector<Issue> issues;
  auto report = [&](const toml::source_region& r, std::string message, std::string key) {
    issues.push_back(
        {r.begin.line, r.begin.column, where(r, source_name) + ": " + message, std::move(key)});
  };
  for (auto&& [skey, snode] : root) {
    const std::string sname(skey.str());
    if (sname == OPAQUE_SECTION) {
      const toml::table* table = snode.as_table();
      if (!table) {
        report(skey.source(), "'" + sname + "' must be a table ([" + sname + "]), got " +
                                  describe(snode), sname);
        continue;
      }
      for (auto&& [kkey, knode] : *table) {
        const std::string full = sname + "." + std::string(kkey.str());
        std::string text;
        const std::string error = opaqueText(full, knode, text);
        if (!error.empty()) {
          report(knode.source(), error, full);
          continue;
        }
        config.analysis[std::string(kkey.str())] = text;
        origin[full] = where(knode.source(), source_name);
      }
      continue;
    }
    const Section* section = findSection(sname);
    if (!section) {
      report(skey.source(),
             snode.is_table() ? unknownKeyMessage(sname, "") : unknownKeyMessage("", sname), sname);
      continue;
    }
    const toml::table* table = snode.as_table();
    if (!table) {
      report(skey.source(),
             "'" + sname + "' must be a table ([" + sname + "]), got " + describe(snode), sname);
      continue;
    }
    for (auto&& [kkey, knode] : *table) {
      const std::string kname(kkey.str());
      const std::string full = sname + "." + kname;
      const Key* key = findKey(*section, kname);
      if (!key) {
        report(kkey.source(), unknownKeyMessage(sname, kname), full);
        continue;
      }
      std::string error = assign(*key, full, knode, config);
      if (!error.empty()) {
        report(knode.source(), error, full);
        continue;
      }
      origin[full] = where(knode.source(), source_name);
    }
  }
  if (issues.empty()) return;
  // toml::table iterates in key order; report in file order, all at once.
  std::stable_sort(issues.begin(), issues.end(), [](const Issue& a, const Issue& b) {
    return a.line != b.line ? a.line < b.line : a.column < b.column;
  });
  // One line per issue, at most MAX_REPORTED: a file that is not a config at all (a binary, a
  // different format) would otherwise print a line for every word in it.
  constexpr std::size_t MAX_REPORTED = 10;
  std::string message;
  for (std::size_t k = 0; k < issues.size() && k < MAX_REPORTED; ++k)
    message += (message.empty() ? "" : "\n") + issues[k].message;
  if (issues.size() > MAX_REPORTED)
    message += "\n(and " + std::to_string(issues.size() - MAX_REPORTED) + " more errors in " +
               source_name + ")";
  throw ConfigError(message, issues.size() == 1 ? issues.front().key : "");
}

// Applies one "section.key=value" override.
void applyOverride(const std::string& raw, MdConfig& config,
                   std::map<std::string, std::string>& origin) {
  const std::string prefix = "--set " + raw + ": ";
  const auto eq = raw.find('=');
  if (eq == std::string::npos) throw ConfigError(prefix + "expected section.key=value", "");
  const std::string full = common::trim(raw.substr(0, eq));
  const std::string text = common::trim(raw.substr(eq + 1));
  if (text.find_first_of("\r\n") != std::string::npos)
    throw ConfigError(prefix + "the value must be on one line", full);
  const auto dot = full.find('.');
  if (dot == std::string::npos) throw ConfigError(prefix + unknownKeyMessage("", full), full);
  const std::string sname = full.substr(0, dot), kname = full.substr(dot + 1);
  if (sname == OPAQUE_SECTION) {  // stored as TOML text: a bare word becomes a string
    toml::table parsed;
    const std::string value_doc = "v = " + text;
#if TOML_EXCEPTIONS
    try {
      parsed = toml::parse(std::string_view(value_doc), std::string_view("--set"));
    } catch (const toml::parse_error&) {
      parsed = toml::table{};
    }
#else
    if (auto res = toml::parse(std::string_view(value_doc), std::string_view("--set")))
      parsed = std::move(res).table();
#endif
    const toml::node* node = parsed.get("v");
    toml::value<std::string> as_text(text);
    if (!node || node->is_date() || node->is_time() || node->is_date_time()) node = &as_text;
    std::string stored;
    const std::string error = kname.empty() ? full + ": a key is missing after 'analysis.'"
                                            : opaqueText(full, *node, stored);
    if (!error.empty()) throw ConfigError(prefix + error, full);
    config.analysis[kname] = stored;
    origin[full] = "--set " + raw;
    return;
  }
  const Section* section = findSection(sname);
  if (!section) throw ConfigError(prefix + unknownKeyMessage(sname, ""), full);
  const Key* key = findKey(*section, kname);
  if (!key) throw ConfigError(prefix + unknownKeyMessage(sname, kname), full);

  // The value as TOML; what is not valid TOML (a bare word, a path) or is a date/time is text.
  // A string key takes unquoted text literally, so initial=2024-01-01.h5 or model=1 stay strings.
  const bool quoted = !text.empty() && (text.front() == '"' || text.front() == '\'');
  toml::table parsed;
  const toml::node* node = nullptr;
  toml::value<std::string> as_text(text);
  if (!std::holds_alternative<StringRef>(key->ref) || quoted) {
    const std::string value_doc = "v = " + text;
#if TOML_EXCEPTIONS
    try {
      parsed = toml::parse(std::string_view(value_doc), std::string_view("--set"));
    } catch (const toml::parse_error&) {
      parsed = toml::table{};
    }
#else
    if (auto res = toml::parse(std::string_view(value_doc), std::string_view("--set")))
      parsed = std::move(res).table();
#endif
    node = parsed.get("v");
    if (node && (node->is_date() || node->is_time() || node->is_date_time())) node = nullptr;
  }
  if (!node) node = &as_text;
  const std::string error = assign(*key, full, *node, config);
  if (!error.empty()) throw ConfigError(prefix + error, full);
  origin[full] = "--set " + raw;
}

MdConfig parseImpl(const std::string& text, const std::string& source_name,
                   const std::vector<std::string>& overrides) {
  MdConfig config;
  std::map<std::string, std::string> origin;
  readTable(parseToml(text, source_name), source_name, config, origin);
  for (const auto& o : overrides) applyOverride(o, config, origin);
  try {
    validateConfig(config);
  } catch (const ConfigError& e) {
    auto it = origin.find(e.key());
    if (it == origin.end()) throw;
    throw ConfigError(it->second + ": " + e.what(), e.key());
  }
  config.origin = std::move(origin);
  return config;
}

// One value as text: TOML literal (toml = true) or plain provenance text.
std::string valueText(const Key& key, const MdConfig& config, bool toml) {
  MdConfig& c = const_cast<MdConfig&>(config);  // the accessors only read here
  if (auto r = std::get_if<IntRef>(&key.ref)) {
    if (key.auto_allowed && (*r)(c) == 0) return toml ? "\"auto\"" : "auto";
    return std::to_string((*r)(c));
  }
  if (auto r = std::get_if<LongRef>(&key.ref)) return std::to_string((*r)(c));
  if (auto r = std::get_if<SeedRef>(&key.ref)) {
    const std::uint64_t s = (*r)(c);
    const std::string digits = std::to_string(s);
    const bool fits = s <= static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
    return (toml && !fits) ? quote(digits) : digits;
  }
  if (auto r = std::get_if<RealRef>(&key.ref)) {
    const double x = (*r)(c);
    if (&(*r)(c) == &c.integrator.dt && c.integrator.adaptive)
      return toml ? "\"adaptive\"" : "adaptive";
    if (key.auto_allowed && x == 0.0) return toml ? "\"auto\"" : "auto";
    return toml ? tomlReal(x) : common::formatReal(x);
  }
  if (auto r = std::get_if<BoolRef>(&key.ref)) return (*r)(c) ? "true" : "false";
  if (auto r = std::get_if<StringRef>(&key.ref)) return toml ? quote((*r)(c)) : (*r)(c);
  return "";
}

bool finite(double x) { return std::isfinite(x); }

}  // namespace

MdConfig parseConfigString(const std::string& text, const std::string& source_name,
                           const std::vector<std::string>& overrides) {
  return parseImpl(text, source_name, overrides);
}

MdConfig parseConfigFile(const std::string& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))  // (an ifstream opens a directory and reads "")
    throw ConfigError("config file '" + path + "' is a directory, not a TOML file", "");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError("cannot open config file '" + path + "'", "");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError("cannot read config file '" + path + "'", "");
  return parseImpl(text.str(), path, overrides);
}

void validateConfig(const MdConfig& c) {
  using common::formatReal;
  if (c.input_version != CONFIG_VERSION)
    throw ConfigError("input.version = " + std::to_string(c.input_version) +
                          " is not supported: this granagg reads version " +
                          std::to_string(CONFIG_VERSION),
                      "input.version");

  const SystemConfig& s = c.system;
  if (s.N < 2) invalid("system.N", std::to_string(s.N), "be >= 2");
  if (!(s.phi > 0.0 && s.phi < 0.6)) invalid("system.phi", formatReal(s.phi), "lie in (0, 0.6)");
  if (!(s.temperature > 0.0 && finite(s.temperature)))
    invalid("system.temperature", formatReal(s.temperature), "be > 0 and finite");
  if (s.initial.empty())
    invalid("system.initial", quote(s.initial), "be \"random\" or a file path");
  if (!(s.initial_max_overlap >= 0.0 && s.initial_max_overlap < 1.0))  // 0: "auto"
    invalid("system.initial_max_overlap", formatReal(s.initial_max_overlap),
            "lie in (0, 1) or be \"auto\" (run.max_overlap)");

  const ContactConfig& k = c.contact;
  if (!isContactModel(k.model))
    invalid("contact.model", quote(k.model),
            "be one of " + contactModelNames() + " (unknown contact model)");
  if (!(k.E >= 0.0 && finite(k.E))) invalid("contact.E", formatReal(k.E), "be >= 0 and finite");
  if (!(k.D >= 0.0 && finite(k.D))) invalid("contact.D", formatReal(k.D), "be >= 0 and finite");
  if (!(k.stiffness > 0.0 && finite(k.stiffness)))
    invalid("contact.stiffness", formatReal(k.stiffness), "be > 0 and finite");
  if (!(k.restitution > 0.0 && k.restitution <= 1.0))
    invalid("contact.restitution", formatReal(k.restitution), "lie in (0, 1]");

  const IntegratorConfig& g = c.integrator;
  if (!(g.dt >= 0.0 && finite(g.dt)))
    invalid("integrator.dt", formatReal(g.dt), "be > 0, \"auto\" or \"adaptive\"");
  if (!(g.steps_per_contact >= 5.0 && finite(g.steps_per_contact)))
    invalid("integrator.steps_per_contact", formatReal(g.steps_per_contact), "be >= 5 and finite");
  if (!(g.impact_speed_max >= 0.0 && finite(g.impact_speed_max)))
    invalid("integrator.impact_speed_max", formatReal(g.impact_speed_max), "be > 0 or \"auto\"");

  if (!(c.neighbor.skin >= 0.0 && c.neighbor.skin <= 2.0))  // 0: "auto"
    invalid("neighbor.skin", formatReal(c.neighbor.skin), "lie in (0, 2] or be \"auto\"");

  const ChargingConfig& q = c.charging;
  if (q.mode != "exchange" && q.mode != "fixed")
    invalid("charging.mode", quote(q.mode), "be one of \"exchange\", \"fixed\"");
  if (q.initial != "neutral" && q.initial != "monopolar" && q.initial != "bipolar" &&
      q.initial != "file")
    invalid("charging.initial", quote(q.initial),
            "be one of \"neutral\", \"monopolar\", \"bipolar\", \"file\"");
  if (q.initial == "file" && s.initial == "random")
    invalid("charging.initial", quote(q.initial),
            "be used with system.initial = a file that holds charges");
  if (!(q.q0 > 0.0 && finite(q.q0))) invalid("charging.q0", formatReal(q.q0), "be > 0 and finite");
  if (!(q.Q >= 0.0 && finite(q.Q))) invalid("charging.Q", formatReal(q.Q), "be >= 0 and finite");
  if (!(q.kappa > 0.0 && finite(q.kappa)))
    invalid("charging.kappa", formatReal(q.kappa), "be > 0 and finite");
  if (!(q.psi1_min > 0.0 && q.psi1_max >= q.psi1_min && finite(q.psi1_max)))
    invalid("charging.psi1_min", formatReal(q.psi1_min),
            "be > 0 and <= charging.psi1_max (" + formatReal(q.psi1_max) + ")");
  if (!(q.psi2_fraction >= 0.0 && q.psi2_fraction < 1.0))
    invalid("charging.psi2_fraction", formatReal(q.psi2_fraction), "lie in [0, 1)");

  const CoulombConfig& e = c.coulomb;
  if (!(e.K >= 0.0 && finite(e.K))) invalid("coulomb.K", formatReal(e.K), "be >= 0 and finite");
  if (e.method != "pppm" && e.method != "ewald")
    invalid("coulomb.method", quote(e.method), "be one of \"pppm\", \"ewald\"");
  if (!(e.accuracy > 0.0 && e.accuracy < 0.1))
    invalid("coulomb.accuracy", formatReal(e.accuracy),
            "lie in (0, 0.1) (relative RMS force error)");
  if (!(e.r_cut >= 0.0 && finite(e.r_cut)))
    invalid("coulomb.r_cut", formatReal(e.r_cut), "be > 0 or \"auto\"");
  if (e.mesh < 0) invalid("coulomb.mesh", std::to_string(e.mesh), "be > 0 or \"auto\"");
  if (e.order < 0 || e.order == 1 || e.order > 7)
    invalid("coulomb.order", std::to_string(e.order), "lie in 2..7 or be \"auto\"");
  if (e.every < 0 || e.every > 100)
    invalid("coulomb.every", std::to_string(e.every),
            "lie in 1..100 (steps between Coulomb evaluations) or be \"auto\"");
  if (e.every_max < 0 || e.every_max > 1000)
    invalid("coulomb.every_max", std::to_string(e.every_max),
            "lie in 1..1000 (the longest slow interval in steps; <= coulomb.every keeps it "
            "fixed) or be \"auto\" (4 x coulomb.every)");
  if (!(e.skin >= 0.0 && e.skin <= 5.0))
    invalid("coulomb.skin", formatReal(e.skin), "lie in (0, 5] or be \"auto\"");
  if (!(e.r_fast == 0.0 || (e.r_fast >= 2.0 && finite(e.r_fast))))
    invalid("coulomb.r_fast", formatReal(e.r_fast),
            "be >= 2 (the switch [r_fast - 1, r_fast] starts beyond contact) or \"auto\"");

  if (!(c.run.t_end > 0.0 && finite(c.run.t_end)))
    invalid("run.t_end", formatReal(c.run.t_end), "be > 0 and finite");
  // Overlap 1 means coinciding centres; MdConfig's default 0.6 is a loose blow-up guard.
  if (!(c.run.max_overlap > 0.0 && c.run.max_overlap < 1.0))
    invalid("run.max_overlap", formatReal(c.run.max_overlap), "lie in (0, 1)");

  const OutputConfig& o = c.output;
  if (o.frames_per_decade < 0)
    invalid("output.frames_per_decade", std::to_string(o.frames_per_decade), "be >= 0");
  if (!(o.frame_interval >= 0.0 && finite(o.frame_interval)))
    invalid("output.frame_interval", formatReal(o.frame_interval), "be >= 0 and finite");
  if (o.observable_interval < 1)
    invalid("output.observable_interval", std::to_string(o.observable_interval), "be >= 1");
  if (o.checkpoint_interval < 0)
    invalid("output.checkpoint_interval", std::to_string(o.checkpoint_interval), "be >= 0");
  if (!(o.checkpoint_wall_seconds >= 0.0 && finite(o.checkpoint_wall_seconds)))
    invalid("output.checkpoint_wall_seconds", formatReal(o.checkpoint_wall_seconds),
            "be >= 0 and finite");
}

double boxLength(const SystemConfig& system) {
  if (system.N < 1 || !(system.phi > 0.0))
    throw std::invalid_argument(
        "boxLength needs system.N >= 1 and system.phi > 0 (got N = " + std::to_string(system.N) +
        ", phi = " + common::formatReal(system.phi) + ")");
  return std::cbrt(static_cast<double>(system.N) * M_PI / (6.0 * system.phi));
}

std::string toToml(const MdConfig& config) {
  std::string out =
      "# granagg md configuration, every key resolved (docs/config.md); reduced units d = m = T0 = "
      "1\n";
  for (const auto& s : schema()) {
    out += "\n[" + s.name + "]\n";
    for (const auto& k : s.keys) out += k.name + " = " + valueText(k, config, true) + "\n";
  }
  if (!config.analysis.empty()) {
    out += std::string("\n[") + OPAQUE_SECTION + "]\n";
    for (const auto& [key, text] : config.analysis) out += key + " = " + text + "\n";
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> flatten(const MdConfig& config) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& s : schema())
    for (const auto& k : s.keys)
      out.emplace_back(s.name + "." + k.name, valueText(k, config, false));
  for (const auto& [key, text] : config.analysis)
    out.emplace_back(std::string(OPAQUE_SECTION) + "." + key, text);
  return out;
}

}  // namespace granagg::md
