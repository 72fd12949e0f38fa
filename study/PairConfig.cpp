/// \file PairConfig.cpp
/// The pair study's configuration: schema, reader, writer and checks (PairConfig.h).
#include "study/PairConfig.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/Csv.h"

namespace granagg::study {
namespace fs = std::filesystem;
using common::formatReal;

namespace {

std::string where(const toml::source_region& r, const std::string& file) {
  return file + ":" + std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column);
}

}  // namespace

namespace {

/// A parsed pair-study TOML file and the typed readers of its keys: an absent key leaves the
/// default, a key of the wrong type is an error at its file:line:column.
struct PairToml {
  std::string path;
  toml::table doc;

  explicit PairToml(const std::string& file) : path(file) {
    if (!fs::exists(path)) throw std::invalid_argument("--config: no such file '" + path + "'");
    try {
      doc = toml::parse_file(path);
    } catch (const toml::parse_error& e) {
      throw std::invalid_argument(where(e.source(), path) +
                                  ": invalid TOML: " + std::string(e.description()));
    }
  }
  [[noreturn]] void fail(const toml::node& n, const std::string& msg) const {
    throw std::invalid_argument(where(n.source(), path) + ": " + msg);
  }
  const toml::node* node(const char* sec, const char* key) const {
    return doc.at_path(std::string(sec) + "." + key).node();
  }

  /// Every section and key must be one of `known` (a typo is an error, not a silent default).
  void checkKnown(const std::map<std::string, std::set<std::string>>& known) const {
    for (auto&& [skey, snode] : doc) {
      const std::string s(skey.str());
      auto it = known.find(s);
      if (it == known.end() || !snode.is_table()) {
        std::string list;
        for (const auto& [k, v] : known) list += (list.empty() ? "" : ", ") + k;
        fail(snode, "unknown section '" + s + "' (known sections: " + list + ")");
      }
      for (auto&& [kkey, knode] : *snode.as_table()) {
        const std::string k(kkey.str());
        if (!it->second.count(k)) {
          std::string list;
          for (const auto& x : it->second) list += (list.empty() ? "" : ", ") + x;
          fail(knode,
               "unknown key '" + s + "." + k + "' (known keys in [" + s + "]: " + list + ")");
        }
      }
    }
  }

  void number(const char* sec, const char* key, double& out) const {
    const toml::node* n = node(sec, key);
    if (!n) return;
    if (auto v = n->value<double>())
      out = *v;
    else
      fail(*n, std::string(sec) + "." + key + " must be a number");
  }
  void integer(const char* sec, const char* key, long long& out) const {
    const toml::node* n = node(sec, key);
    if (!n) return;
    if (auto v = n->as_integer())
      out = v->get();
    else
      fail(*n, std::string(sec) + "." + key + " must be an integer");
  }
  void string(const char* sec, const char* key, std::string& out) const {
    const toml::node* n = node(sec, key);
    if (!n) return;
    if (auto v = n->as_string())
      out = v->get();
    else
      fail(*n, std::string(sec) + "." + key + " must be a string");
  }
  void strings(const char* sec, const char* key, std::vector<std::string>& out) const {
    const toml::node* n = node(sec, key);
    if (!n) return;
    const toml::array* a = n->as_array();
    if (!a) fail(*n, std::string(sec) + "." + key + " must be an array of strings");
    out.clear();
    for (const auto& e : *a) {
      if (auto v = e.as_string())
        out.push_back(v->get());
      else
        fail(e, std::string(sec) + "." + key + " must hold strings only");
    }
  }
  void numbers(const char* sec, const char* key, std::vector<double>& out) const {
    const toml::node* n = node(sec, key);
    if (!n) return;
    const toml::array* a = n->as_array();
    if (!a) fail(*n, std::string(sec) + "." + key + " must be an array of numbers");
    out.clear();
    for (const auto& e : *a) {
      if (auto v = e.value<double>())
        out.push_back(*v);
      else
        fail(e, std::string(sec) + "." + key + " must hold numbers only");
    }
  }
  /// A lammps.* count: beyond int is refused here, with its position; validate() checks those
  /// within int.
  int count(const char* key, long long n) const {
    const toml::node* nd = node("lammps", key);
    if (nd && n != static_cast<int>(n))
      fail(*nd, std::string("lammps.") + key + " must lie in 1.." + std::to_string(MAX_RANKS) +
                    " (got " + std::to_string(n) + ")");
    return static_cast<int>(n);
  }
};

}  // namespace

PairConfig parsePairConfig(const std::string& path) {
  const PairToml t(path);
  t.checkKnown({{"input", {"version"}},
                {"pair", {"name", "K", "runs", "seed"}},
                {"md", {"preset", "config", "set", "engine"}},
                {"charged", {"Q", "set"}},
                {"analysis", {"args"}},
                {"meanfield", {"beta", "t_end", "s_end", "zbeta_min", "zbeta_max", "zbeta_count"}},
                {"fit", {"window", "column"}},
                {"lammps", {"launcher", "ranks", "slurm_launcher", "nodes", "tasks_per_node"}}});
  PairConfig c;
  c.source = fs::absolute(path).string();
  long long version = 1, runs = c.runs, zcount = c.zbeta_count, ranks = c.lammps_ranks,
            nodes = c.lammps_nodes, tasks_per_node = c.lammps_tasks_per_node;
  t.integer("input", "version", version);
  if (version != 1)
    throw std::invalid_argument(path + ": [input] version = " + std::to_string(version) +
                                " is not supported (only 1)");
  t.string("pair", "name", c.name);
  t.numbers("pair", "K", c.K);
  t.integer("pair", "runs", runs);
  t.integer("pair", "seed", c.seed);
  t.string("md", "preset", c.md_preset);
  t.string("md", "config", c.md_config);
  t.strings("md", "set", c.md_set);
  t.string("md", "engine", c.md_engine);
  t.number("charged", "Q", c.charged_Q);
  t.strings("charged", "set", c.charged_set);
  t.strings("analysis", "args", c.analysis_args);
  t.numbers("meanfield", "beta", c.betas);
  t.number("meanfield", "t_end", c.mf_t_end);
  t.number("meanfield", "s_end", c.mf_s_end);
  t.number("meanfield", "zbeta_min", c.zbeta_min);
  t.number("meanfield", "zbeta_max", c.zbeta_max);
  t.integer("meanfield", "zbeta_count", zcount);
  t.numbers("fit", "window", c.fit_window);
  t.string("fit", "column", c.fit_column);
  t.string("lammps", "launcher", c.lammps_launcher);
  t.integer("lammps", "ranks", ranks);
  t.string("lammps", "slurm_launcher", c.lammps_slurm_launcher);
  t.integer("lammps", "nodes", nodes);
  t.integer("lammps", "tasks_per_node", tasks_per_node);
  c.runs = static_cast<int>(std::clamp<long long>(runs, -1, MAX_RUNS + 1));
  c.lammps_ranks = t.count("ranks", ranks);
  c.lammps_nodes = t.count("nodes", nodes);
  c.lammps_tasks_per_node = t.count("tasks_per_node", tasks_per_node);
  c.zbeta_count = static_cast<int>(std::clamp<long long>(zcount, -1, 100000));
  if (c.md_preset.empty() == c.md_config.empty())
    throw std::invalid_argument(
        path + ": [md] needs exactly one of preset = \"name\" or config = \"file.toml\"");
  if (!c.md_config.empty() && fs::path(c.md_config).is_relative())
    c.md_config = (fs::path(c.source).parent_path() / c.md_config).lexically_normal().string();
  return c;
}

namespace {

template <class T>
toml::array tomlArray(const std::vector<T>& v) {
  toml::array a;
  for (const T& x : v) a.push_back(x);
  return a;
}

}  // namespace

std::string toToml(const PairConfig& c) {
  toml::table md{{"set", tomlArray(c.md_set)}, {"engine", c.md_engine}};
  if (c.md_preset.empty())
    md.insert("config", c.md_config);
  else
    md.insert("preset", c.md_preset);
  const toml::table doc{
      {"input", toml::table{{"version", 1}}},
      {"pair", toml::table{{"name", c.name},
                           {"K", tomlArray(c.K)},
                           {"runs", c.runs},
                           {"seed", static_cast<std::int64_t>(c.seed)}}},
      {"md", md},
      {"charged", toml::table{{"Q", c.charged_Q}, {"set", tomlArray(c.charged_set)}}},
      {"analysis", toml::table{{"args", tomlArray(c.analysis_args)}}},
      {"meanfield", toml::table{{"beta", tomlArray(c.betas)},
                                {"t_end", c.mf_t_end},
                                {"s_end", c.mf_s_end},
                                {"zbeta_min", c.zbeta_min},
                                {"zbeta_max", c.zbeta_max},
                                {"zbeta_count", c.zbeta_count}}},
      {"fit", toml::table{{"window", tomlArray(c.fit_window)}, {"column", c.fit_column}}},
      {"lammps", toml::table{{"launcher", c.lammps_launcher},
                             {"ranks", c.lammps_ranks},
                             {"slurm_launcher", c.lammps_slurm_launcher},
                             {"nodes", c.lammps_nodes},
                             {"tasks_per_node", c.lammps_tasks_per_node}}}};
  std::ostringstream o;
  o << "# granagg pair configuration, resolved from " << c.source
    << " and the command line (docs/pair.md)\n"
    << doc << "\n";
  return o.str();
}

std::vector<double> parseKList(const std::string& s) {
  std::vector<double> K;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double k = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0' || !std::isfinite(k) || k < 0)
      throw std::invalid_argument(
          "--K takes comma-separated Coulomb constants >= 0, e.g. --K 0,5 (got '" + s + "')");
    K.push_back(k);
  }
  if (K.empty())
    throw std::invalid_argument(
        "--K takes comma-separated Coulomb constants >= 0, e.g. --K 0,5 (got '" + s + "')");
  return K;
}

void validate(const PairConfig& c) {
  const std::string src = c.source + ": ";
  if (c.K.empty())
    throw std::invalid_argument(src + "pair.K must list at least one Coulomb constant");
  std::set<std::string> seen;
  for (double k : c.K) {
    if (!(k >= 0) || !std::isfinite(k))
      throw std::invalid_argument("K = " + formatReal(k) +
                                  " is invalid: Coulomb constants must be >= 0 (--K, pair.K)");
    if (!seen.insert(formatReal(k)).second)
      throw std::invalid_argument("K = " + formatReal(k) + " is listed twice (--K, pair.K)");
  }
  if (c.runs < 1 || c.runs > MAX_RUNS)
    throw std::invalid_argument(src + "pair.runs must lie in 1.." + std::to_string(MAX_RUNS) +
                                " (got " + std::to_string(c.runs) + ")");
  if (c.seed < 0) throw std::invalid_argument(src + "pair.seed must be >= 0");
  if (!(c.charged_Q > 0) || !std::isfinite(c.charged_Q))
    throw std::invalid_argument(src + "charged.Q must be > 0");
  if (c.betas.empty())
    throw std::invalid_argument(src + "meanfield.beta must list at least one beta");
  for (double b : c.betas)
    if (!(b > 0))
      throw std::invalid_argument(src + "meanfield.beta = " + formatReal(b) +
                                  " is invalid: must be > 0");
  if (!(c.mf_t_end > 0) || !(c.mf_s_end > 1))
    throw std::invalid_argument(src + "meanfield.t_end must be > 0 and s_end > 1");
  if (!(c.zbeta_min > 0) || !(c.zbeta_max >= c.zbeta_min) || c.zbeta_count < 1)
    throw std::invalid_argument(
        src + "meanfield.zbeta_min/zbeta_max/zbeta_count must satisfy 0 < min <= max, count >= 1");
  if (!c.fit_window.empty() &&
      (c.fit_window.size() != 2 || !(c.fit_window[1] > c.fit_window[0]) || !(c.fit_window[0] >= 0)))
    throw std::invalid_argument(src + "fit.window must be [] or [T0, T1] with 0 <= T0 < T1");
  if (std::find(std::begin(MD_ENGINES), std::end(MD_ENGINES), c.md_engine) == std::end(MD_ENGINES))
    throw std::invalid_argument(src + "md.engine = \"" + c.md_engine +
                                "\" is not known (allowed: \"granagg\", \"lammps\")");
  const auto in_range = [&](const char* key, int n) {
    if (n < 1 || n > MAX_RANKS)
      throw std::invalid_argument(src + key + " must lie in 1.." + std::to_string(MAX_RANKS) +
                                  " (got " + std::to_string(n) + ")");
  };
  in_range("lammps.ranks", c.lammps_ranks);
  in_range("lammps.nodes", c.lammps_nodes);
  in_range("lammps.tasks_per_node", c.lammps_tasks_per_node);
  launcherWords(c.lammps_launcher, c.lammps_ranks, src + "lammps.launcher");
  launcherWords(c.lammps_slurm_launcher, 1LL * c.lammps_nodes * c.lammps_tasks_per_node,
                src + "lammps.slurm_launcher");
}

std::vector<std::string> launcherWords(const std::string& launcher, long long ranks,
                                       const std::string& key) {
  std::vector<std::string> words;
  std::istringstream in(launcher);
  for (std::string w; in >> w;) {
    for (std::size_t at; (at = w.find("{ranks}")) != std::string::npos;)
      w.replace(at, 7, std::to_string(ranks));
    words.push_back(w);
  }
  if (words.empty())
    throw std::invalid_argument(key +
                                " is empty: give the command that starts MPI ranks, e.g. "
                                "\"mpirun -np {ranks}\"");
  for (const auto& w : words)
    if (w.find_first_of("{}'\"\\$`;|&<>") != std::string::npos)
      throw std::invalid_argument(key + " = \"" + launcher + "\": '" + w +
                                  "' holds a character the launcher's words cannot (no shell "
                                  "runs them: words are split at blanks, {ranks} is the one "
                                  "placeholder)");
  return words;
}

std::string kName(double K) { return "K" + formatReal(K); }

}  // namespace granagg::study
