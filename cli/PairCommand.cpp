/// `granagg pair`: paired MD / mean-field study (issue 6, docs/pair.md). Runs the MD ensembles
/// (one `granagg md` process per run, up to --jobs at a time, resumable), analyses each ensemble
/// (`granagg analyze`), solves the mean field (`granagg smol`, `granagg kinetic`), fits beta
/// (`granagg fit-beta`), draws the figures (scripts/plot_figures.py) and the report
/// (scripts/make_report.py), and writes summary.json. Every step is a subprocess of this same
/// binary, with its output in DIR/logs/ and its command line in DIR/commands.txt.
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "analysis/stats/GrowthMarkers.h"
#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"

namespace granagg::cli {
namespace fs = std::filesystem;
using common::formatReal;

namespace {

// ----------------------------------------------------------------------------------------------
// Options and the pair configuration (data/pair/*.toml, docs/pair.md)

/// Runs per K at most: a study of 2 x 10000 runs is far beyond any this code is for, and the
/// bound keeps a typo from allocating the study's bookkeeping until the machine runs out.
constexpr int MAX_RUNS = 10000;

struct PairArgs {
  std::string preset, config, K, out, emit_batch;
  int runs = 0;        // used when given on the command line
  int jobs = 0;        // 0: one per core
  int threads = 0;     // 0: max(1, cores / jobs)
  int run_index = -1;  // batch array task: run only this run
  bool force = false, quiet = false, no_figures = false;
};

struct PairConfig {
  std::string source;  ///< the file it was read from
  std::string name = "custom";
  std::vector<double> K{0.0, 5.0};
  int runs = 3;
  long long seed = 1;
  std::string md_preset, md_config;  ///< exactly one is set (md_config absolute)
  std::vector<std::string> md_set;
  double charged_Q = 0.05;  // docs/validation.md: the largest stable value of its Q scan at K = 5
  std::vector<std::string> charged_set;
  std::vector<std::string> analysis_args;
  std::vector<double> betas{2.0, 3.0};
  double mf_t_end = 1e7, mf_s_end = 1e6;
  double zbeta_min = 2.0, zbeta_max = 4.0;
  int zbeta_count = 5;
  std::vector<double> fit_window;
  std::string fit_column;
};

/// scripts/ of the source tree: GRANAGG_SCRIPTS, else GRANAGG_DATA_DIR/../scripts.
fs::path scriptsDir() {
  if (const char* env = std::getenv("GRANAGG_SCRIPTS")) return env;
  return fs::path(GRANAGG_DATA_DIR).parent_path() / "scripts";
}

std::string python() {
  if (const char* env = std::getenv("GRANAGG_PYTHON")) return env;
  return fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
}

std::string where(const toml::source_region& r, const std::string& file) {
  return file + ":" + std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column);
}

PairConfig parsePairConfig(const std::string& path) {
  if (!fs::exists(path)) throw std::invalid_argument("--config: no such file '" + path + "'");
  toml::table doc;
  try {
    doc = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw std::invalid_argument(where(e.source(), path) +
                                ": invalid TOML: " + std::string(e.description()));
  }
  PairConfig c;
  c.source = fs::absolute(path).string();
  const std::map<std::string, std::set<std::string>> known{
      {"input", {"version"}},
      {"pair", {"name", "K", "runs", "seed"}},
      {"md", {"preset", "config", "set"}},
      {"charged", {"Q", "set"}},
      {"analysis", {"args"}},
      {"meanfield", {"beta", "t_end", "s_end", "zbeta_min", "zbeta_max", "zbeta_count"}},
      {"fit", {"window", "column"}}};
  auto fail = [&](const toml::node& n, const std::string& msg) -> void {
    throw std::invalid_argument(where(n.source(), path) + ": " + msg);
  };
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
        fail(knode, "unknown key '" + s + "." + k + "' (known keys in [" + s + "]: " + list + ")");
      }
    }
  }
  auto number = [&](const char* sec, const char* key, double& out) {
    const toml::node* n = doc.at_path(std::string(sec) + "." + key).node();
    if (!n) return;
    if (auto v = n->value<double>())
      out = *v;
    else
      fail(*n, std::string(sec) + "." + key + " must be a number");
  };
  auto integer = [&](const char* sec, const char* key, long long& out) {
    const toml::node* n = doc.at_path(std::string(sec) + "." + key).node();
    if (!n) return;
    if (auto v = n->as_integer())
      out = v->get();
    else
      fail(*n, std::string(sec) + "." + key + " must be an integer");
  };
  auto string = [&](const char* sec, const char* key, std::string& out) {
    const toml::node* n = doc.at_path(std::string(sec) + "." + key).node();
    if (!n) return;
    if (auto v = n->as_string())
      out = v->get();
    else
      fail(*n, std::string(sec) + "." + key + " must be a string");
  };
  auto strings = [&](const char* sec, const char* key, std::vector<std::string>& out) {
    const toml::node* n = doc.at_path(std::string(sec) + "." + key).node();
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
  };
  auto numbers = [&](const char* sec, const char* key, std::vector<double>& out) {
    const toml::node* n = doc.at_path(std::string(sec) + "." + key).node();
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
  };
  long long version = 1, runs = c.runs, zcount = c.zbeta_count;
  integer("input", "version", version);
  if (version != 1)
    throw std::invalid_argument(path + ": [input] version = " + std::to_string(version) +
                                " is not supported (only 1)");
  string("pair", "name", c.name);
  numbers("pair", "K", c.K);
  integer("pair", "runs", runs);
  integer("pair", "seed", c.seed);
  string("md", "preset", c.md_preset);
  string("md", "config", c.md_config);
  strings("md", "set", c.md_set);
  number("charged", "Q", c.charged_Q);
  strings("charged", "set", c.charged_set);
  strings("analysis", "args", c.analysis_args);
  numbers("meanfield", "beta", c.betas);
  number("meanfield", "t_end", c.mf_t_end);
  number("meanfield", "s_end", c.mf_s_end);
  number("meanfield", "zbeta_min", c.zbeta_min);
  number("meanfield", "zbeta_max", c.zbeta_max);
  integer("meanfield", "zbeta_count", zcount);
  numbers("fit", "window", c.fit_window);
  string("fit", "column", c.fit_column);
  c.runs = static_cast<int>(std::clamp<long long>(runs, -1, MAX_RUNS + 1));
  c.zbeta_count = static_cast<int>(std::clamp<long long>(zcount, -1, 100000));
  if (c.md_preset.empty() == c.md_config.empty())
    throw std::invalid_argument(
        path + ": [md] needs exactly one of preset = \"name\" or config = \"file.toml\"");
  if (!c.md_config.empty() && fs::path(c.md_config).is_relative())
    c.md_config = (fs::path(c.source).parent_path() / c.md_config).lexically_normal().string();
  return c;
}

std::string tomlString(const std::string& s) {
  std::string o = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') o += '\\';
    o += ch;
  }
  return o + "\"";
}

template <class T, class F>
std::string tomlArray(const std::vector<T>& v, F f) {
  std::string o = "[";
  for (std::size_t i = 0; i < v.size(); ++i) o += (i ? ", " : "") + f(v[i]);
  return o + "]";
}

std::string realToml(double x) {
  std::string s = formatReal(x);
  if (s.find_first_of(".eEni") == std::string::npos) s += ".0";
  return s;
}

/// The resolved configuration as TOML (DIR/config/pair.toml): what resume and batch jobs read.
std::string toToml(const PairConfig& c) {
  std::ostringstream o;
  o << "# granagg pair configuration, resolved from " << c.source
    << " and the command line (docs/pair.md)\n"
    << "[input]\nversion = 1\n\n[pair]\nname = " << tomlString(c.name)
    << "\nK = " << tomlArray(c.K, realToml) << "\nruns = " << c.runs << "\nseed = " << c.seed
    << "\n\n[md]\n"
    << (c.md_preset.empty() ? "config = " + tomlString(c.md_config)
                            : "preset = " + tomlString(c.md_preset))
    << "\nset = " << tomlArray(c.md_set, tomlString)
    << "\n\n[charged]\nQ = " << realToml(c.charged_Q)
    << "\nset = " << tomlArray(c.charged_set, tomlString)
    << "\n\n[analysis]\nargs = " << tomlArray(c.analysis_args, tomlString)
    << "\n\n[meanfield]\nbeta = " << tomlArray(c.betas, realToml)
    << "\nt_end = " << realToml(c.mf_t_end) << "\ns_end = " << realToml(c.mf_s_end)
    << "\nzbeta_min = " << realToml(c.zbeta_min) << "\nzbeta_max = " << realToml(c.zbeta_max)
    << "\nzbeta_count = " << c.zbeta_count
    << "\n\n[fit]\nwindow = " << tomlArray(c.fit_window, realToml)
    << "\ncolumn = " << tomlString(c.fit_column) << "\n";
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
}

std::string kName(double K) { return "K" + formatReal(K); }

// ----------------------------------------------------------------------------------------------
// Small helpers: files, hashing, JSON

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const fs::path& p, const std::string& text) {
  const fs::path tmp = p.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, p);  // atomic: a marker is either complete or absent
}

void appendText(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::app);
  out << text;
}

std::string fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char ch : s) {
    h ^= ch;
    h *= 1099511628211ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string jsonString(const std::string& s) {
  std::string o = "\"";
  for (char ch : s) {
    switch (ch) {
      case '"':
        o += "\\\"";
        break;
      case '\\':
        o += "\\\\";
        break;
      case '\n':
        o += "\\n";
        break;
      case '\t':
        o += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20) {
          char b[8];
          std::snprintf(b, sizeof b, "\\u%04x", ch);
          o += b;
        } else {
          o += ch;
        }
    }
  }
  return o + "\"";
}

std::string jsonNumber(double x) { return std::isfinite(x) ? formatReal(x) : "null"; }

/// Reads `"key": number` from a flat JSON object (fit_beta.json); NaN when absent or null.
double jsonValue(const std::string& text, const std::string& key, std::size_t index = 0) {
  const std::string pat = "\"" + key + "\"";
  std::size_t pos = 0;
  while ((pos = text.find(pat, pos)) != std::string::npos) {
    std::size_t p = pos + pat.size();
    while (p < text.size() && std::isspace(static_cast<unsigned char>(text[p]))) ++p;
    if (p < text.size() && text[p] == ':') {
      ++p;
      while (p < text.size() &&
             (std::isspace(static_cast<unsigned char>(text[p])) || text[p] == '['))
        ++p;
      for (std::size_t k = 0; k < index; ++k) {
        p = text.find(',', p);
        if (p == std::string::npos) return std::nan("");
        ++p;
      }
      const char* b = text.c_str() + p;
      char* e = nullptr;
      const double v = std::strtod(b, &e);
      return e == b ? std::nan("") : v;
    }
    pos = p;
  }
  return std::nan("");
}

/// Reads `"key": "text"` from a JSON object (simple escapes only); "" when absent or not a string.
std::string jsonText(const std::string& text, const std::string& key) {
  const std::string pat = "\"" + key + "\"";
  const std::size_t pos = text.find(pat);
  if (pos == std::string::npos) return "";
  std::size_t p = text.find_first_not_of(" \t\r\n", pos + pat.size());
  if (p == std::string::npos || text[p] != ':') return "";
  p = text.find_first_not_of(" \t\r\n", p + 1);
  if (p == std::string::npos || text[p] != '"') return "";
  std::string out;
  for (++p; p < text.size() && text[p] != '"'; ++p) {
    if (text[p] == '\\' && p + 1 < text.size()) ++p;
    out += text[p];
  }
  return out;
}

std::string nowUtc() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

int availableCores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

std::string selfExe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("granagg") : p.string();
}

std::string shellQuote(const std::string& a) {
  if (!a.empty() &&
      a.find_first_not_of(
          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=/.,:@%") ==
          std::string::npos)
    return a;
  std::string o = "'";
  for (char ch : a) o += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return o + "'";
}

std::string joinCommand(const std::vector<std::string>& argv) {
  std::string s;
  for (const auto& a : argv) s += (s.empty() ? "" : " ") + shellQuote(a);
  return s;
}

// ----------------------------------------------------------------------------------------------
// Subprocesses

/// fork + exec with stdout and stderr into `log` (appended); the child dies with its parent.
pid_t spawn(const std::vector<std::string>& argv, const fs::path& log) {
  std::vector<char*> a;
  for (const auto& s : argv) a.push_back(const_cast<char*>(s.c_str()));
  a.push_back(nullptr);
  const std::string logpath = log.string();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed: " + std::string(std::strerror(errno)));
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    const int fd = ::open(logpath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    const int nul = ::open("/dev/null", O_RDONLY);
    if (nul >= 0) ::dup2(nul, 0);
    ::execvp(a[0], a.data());
    std::fprintf(stderr, "cannot run %s: %s\n", a[0], std::strerror(errno));
    ::_exit(127);
  }
  return pid;
}

std::string lastLine(const fs::path& log) {
  const std::string t = readText(log);
  std::size_t end = t.find_last_not_of("\n\r ");
  if (end == std::string::npos) return "";
  std::size_t begin = t.find_last_of('\n', end);
  std::string l = t.substr(begin == std::string::npos ? 0 : begin + 1,
                           end - (begin == std::string::npos ? 0 : begin + 1) + 1);
  if (const auto cr = l.find_last_of('\r'); cr != std::string::npos) l = l.substr(cr + 1);
  return l;
}

// ----------------------------------------------------------------------------------------------
// The study

struct RunJob {
  double K = 0;
  int r = 0;
  long long seed = 0;
  int index = 0;  ///< k * runs + r: the batch array index
  fs::path dir, config, log;
  std::string spec;
  double cost = 0;  ///< particle-steps, x100 with Coulomb: longest first
  bool restart = false;
};

class Pair {
 public:
  Pair(const PairArgs& a, PairConfig c, const CliContext& ctx, bool fit_available)
      : m_a(a),
        m_c(std::move(c)),
        m_ctx(ctx),
        m_fit_available(fit_available),
        m_exe(selfExe()),
        m_out(fs::absolute(a.out.empty() ? fs::path("pair-" + m_c.name) : fs::path(a.out))
                  .lexically_normal()),
        m_cores(availableCores()),
        m_start(clock::now()) {}

  void run();

 private:
  using clock = std::chrono::steady_clock;
  void prepareFolder();
  void resolveMd();
  void say(const std::string& line, bool terminal = true);
  std::string batchArgs() const;
  void emitSlurm();
  void runMd(std::vector<RunJob> jobs);
  int runStep(const std::string& label, std::vector<std::string> argv, const std::string& logname,
              bool quiet_failure = false);
  bool stageDone(const fs::path& marker, const std::string& spec) const;
  void analyse();
  void meanField();
  void fitBeta();
  void writeSummary();
  void printSummary();
  double seconds() const { return std::chrono::duration<double>(clock::now() - m_start).count(); }

  const PairArgs& m_a;
  PairConfig m_c;
  const CliContext& m_ctx;
  bool m_fit_available;
  std::string m_exe;
  fs::path m_out;
  int m_cores;
  clock::time_point m_start;
  std::map<std::string, md::MdConfig> m_md;      ///< per K name
  std::map<std::string, std::string> m_md_hash;  ///< per K name: hash of the resolved MD TOML
  std::map<std::string, std::string> m_md_text;  ///< path -> resolved MD TOML to write
  std::vector<RunJob> m_runs;                    ///< every run of the study
  std::set<std::string> m_changed_k;             ///< K names with a run (re)done now
  std::map<std::string, double> m_timing;
  std::map<std::string, std::string> m_status;    ///< step -> done / skipped: ... / failed: ...
  std::map<std::string, std::string> m_fit_note;  ///< K name -> why fit-beta gave no result
  int m_failures = 0;
};

void Pair::say(const std::string& line, bool terminal) {
  appendText(m_out / "pair.log", "[" + nowUtc() + "] " + line + "\n");
  if (terminal && !m_a.quiet) {
    std::fprintf(stderr, "pair: %s\n", line.c_str());
  }
}

void Pair::prepareFolder() {
  const bool exists = fs::exists(m_out);
  if (exists && !fs::is_directory(m_out))
    throw std::invalid_argument("--out '" + m_out.string() + "' exists and is not a folder");
  const bool is_pair = fs::exists(m_out / "config" / "pair.toml");
  if (exists && !fs::is_empty(m_out) && !is_pair && !m_a.force)
    throw std::invalid_argument(
        "output folder '" + m_out.string() +
        "' exists, is not empty and holds no pair study; choose another --out or pass --force");
  if (is_pair && m_a.force && m_a.run_index < 0) {
    // --force: start over (keep nothing this command made before).
    for (const char* sub : {"runs", "analysis", "meanfield", "fit", "figures", "logs", "config"})
      fs::remove_all(m_out / sub);
    for (const char* f : {"summary.json", "report.html", "commands.txt", "batch.slurm", "pair.log"})
      fs::remove(m_out / f);
  }
  fs::create_directories(m_out / "config");
  fs::create_directories(m_out / "logs");
}

void Pair::resolveMd() {
  const std::string base =
      m_c.md_preset.empty() ? m_c.md_config : findPreset("presets", m_c.md_preset, "[md] preset");
  for (std::size_t k = 0; k < m_c.K.size(); ++k) {
    const double K = m_c.K[k];
    std::vector<std::string> set = m_c.md_set;
    set.push_back("coulomb.K=" + formatReal(K));
    if (K > 0) {
      set.push_back("charging.Q=" + formatReal(m_c.charged_Q));
      set.insert(set.end(), m_c.charged_set.begin(), m_c.charged_set.end());
    }
    md::MdConfig cfg = md::parseConfigFile(base, set);
    cfg.system.seed = 0;  // set per run with --seed
    md::validateConfig(cfg);
    const std::string text = md::toToml(cfg);
    const std::string name = kName(K);
    const fs::path path = m_out / "config" / ("md_" + name + ".toml");
    m_md[name] = cfg;
    m_md_hash[name] = fnv1a(text);
    const std::string header = "# granagg md configuration of the K = " + formatReal(K) +
                               " runs of pair study '" + m_c.name + "' (resolved from " + base +
                               "; every run sets its own --seed)\n";
    m_md_text[path.string()] = header + text;  // written once the folder is prepared
    const double dt = md::Engine::chooseTimeStep(cfg);
    const double steps = std::ceil(cfg.run.t_end / dt);
    for (int r = 0; r < m_c.runs; ++r) {
      RunJob j;
      j.K = K;
      j.r = r;
      j.seed = m_c.seed + r;
      j.index = static_cast<int>(k) * m_c.runs + r;
      j.dir = m_out / "runs" / name / ("run" + std::to_string(r));
      j.config = path;
      j.log = m_out / "logs" / ("md-" + name + "-run" + std::to_string(r) + ".log");
      j.spec = "md_config_fnv1a=" + m_md_hash[name] + " seed=" + std::to_string(j.seed);
      j.cost = cfg.system.N * steps * (K > 0 ? 100.0 : 1.0);
      m_runs.push_back(j);
    }
  }
}

std::string Pair::batchArgs() const {
  return shellQuote(m_exe) + " pair --config " +
         shellQuote((m_out / "config" / "pair.toml").string()) + " --out " +
         shellQuote(m_out.string());
}

void Pair::emitSlurm() {
  int threads = m_a.threads > 0 ? m_a.threads : 4;
  const fs::path path = m_out / "batch.slurm";
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# granagg pair study '" << m_c.name << "': " << m_runs.size() << " MD runs ("
    << m_c.K.size() << " values of K x " << m_c.runs
    << " runs) as a Slurm job array, then the analysis, mean field, fit, figures and report as a\n"
    << "# follow-up job that starts once every array task succeeded. Written by: "
    << m_ctx.command_line << "\n#\n"
    << "#   bash " << path.string() << "      submits both jobs (array + dependent follow-up)\n"
    << "#   sbatch " << path.string() << "    submits the array only\n#\n"
    << "# Each task runs one MD run into " << (m_out / "runs").string()
    << "/K<K>/run<r>/ and marks it done; a task whose\n"
    << "# run is already done returns at once, so resubmitting the array after a failure redoes "
       "only what is missing.\n"
    << "# Adjust the #SBATCH lines (partition, account, time, GPUs: --gres=gpu:1 for a CUDA build) "
       "to your cluster.\n"
    << "#SBATCH --job-name=granagg-" << m_c.name << "\n"
    << "#SBATCH --array=0-" << (m_runs.size() - 1) << "\n"
    << "#SBATCH --cpus-per-task=" << threads << "\n"
    << "#SBATCH --time=24:00:00\n"
    << "# SIGTERM to the task 5 minutes before its time limit: the run stops with a checkpoint\n"
    << "# (granagg md handles the signal), and resubmitting continues it from there.\n"
    << "#SBATCH --signal=B:TERM@300\n"
    << "#SBATCH --output=" << (m_out / "logs").string() << "/slurm-%A_%a.out\n"
    << "set -euo pipefail\n"
    << "if [ -z \"${SLURM_JOB_ID:-}\" ]; then\n"
    << "  jid=$(sbatch --parsable \"$0\")\n"
    << "  sbatch --dependency=afterok:${jid%%;*} --job-name=granagg-" << m_c.name
    << "-post --cpus-per-task=" << threads
    << " --time=04:00:00 --output=" << (m_out / "logs").string()
    << "/slurm-post-%j.out --wrap=" << shellQuote(batchArgs()) << "\n"
    << "  echo \"submitted array job $jid and its follow-up\"\n"
    << "  exit 0\n"
    << "fi\n"
    << "# task index = k * " << m_c.runs << " + r for K index k (K = " << tomlArray(m_c.K, realToml)
    << ") and run r\n"
    << "exec " << batchArgs()
    << " --run-index \"$SLURM_ARRAY_TASK_ID\" --threads \"${SLURM_CPUS_PER_TASK:-" << threads
    << "}\" -q\n";
  writeText(path, s.str());
  fs::permissions(path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
  say("wrote " + path.string() + " (" + std::to_string(m_runs.size()) +
      " array tasks + a follow-up job); submit with: bash " + path.string());
}

void Pair::runMd(std::vector<RunJob> all) {
  // Which runs are finished (done.json with the same spec), which can restart from a checkpoint.
  std::vector<RunJob> todo;
  int done = 0;
  for (RunJob& j : all) {
    const fs::path marker = j.dir / "done.json";
    if (fs::exists(marker)) {
      const std::string m = readText(marker);
      if (m.find(jsonString(j.spec)) != std::string::npos) {
        ++done;
        say("md " + kName(j.K) + " run " + std::to_string(j.r) + ": finished already, skipped",
            false);
        continue;
      }
      if (!m_a.force)
        throw std::invalid_argument("run folder '" + j.dir.string() +
                                    "' holds a run made with another configuration; choose another "
                                    "--out or pass --force to redo it");
    }
    j.restart = fs::exists(j.dir / "checkpoint.h5") && fs::exists(j.dir / "traj.h5") &&
                fs::exists(j.dir / "run.json") &&
                readText(j.dir / "run.json").find(jsonString(j.spec)) != std::string::npos;
    todo.push_back(j);
  }
  if (todo.empty()) {
    if (m_a.run_index < 0) say("md: all " + std::to_string(all.size()) + " runs finished already");
    return;
  }
  if (m_a.run_index < 0)
    say("md: " + std::to_string(todo.size()) + " of " + std::to_string(all.size()) + " runs to do" +
        (done ? " (" + std::to_string(done) + " finished already)" : ""));
  std::stable_sort(todo.begin(), todo.end(),
                   [](const RunJob& a, const RunJob& b) { return a.cost > b.cost; });

  // Default: two OpenMP threads per run. The engine's one-thread path is currently several times
  // slower per core than its two-thread path (measured 2026-11-23: N = 500 neutral, 1.9e5 vs
  // 1.2e6 particle-steps/s), so one run per core loses on a 2-core machine.
  const int default_jobs = std::max(1, m_cores / 2);
  const int jobs = std::max(
      1, std::min<int>(m_a.jobs > 0 ? m_a.jobs : default_jobs, static_cast<int>(todo.size())));
  const int threads = m_a.threads > 0 ? m_a.threads : std::max(1, m_cores / jobs);
  struct Running {
    RunJob job;
    clock::time_point start;
  };
  std::deque<RunJob> pending(todo.begin(), todo.end());
  std::map<pid_t, Running> running;
  std::vector<std::string> failed;
  const bool tty = !m_a.quiet && ::isatty(2);
  const auto t0 = clock::now();
  std::size_t finished = 0;
  auto progress = [&]() {
    if (!tty) return;
    std::fprintf(stderr,
                 "\rpair: md %zu/%zu runs done, %zu running (%d jobs x %d threads), %.0f s   ",
                 finished, todo.size(), running.size(), jobs, threads,
                 std::chrono::duration<double>(clock::now() - t0).count());
    std::fflush(stderr);
  };
  auto start = [&](RunJob j) {
    fs::create_directories(j.dir);
    std::vector<std::string> argv{m_exe, "md"};
    if (j.restart) {
      argv.insert(argv.end(), {"--restart", j.dir.string()});
    } else {
      // A fresh start: clear what an interrupted attempt left behind.
      for (const char* f : {"traj.h5", "traj.xdmf", "checkpoint.h5", "done.json"})
        fs::remove(j.dir / f);
      writeText(j.dir / "run.json", "{\n  \"spec\": " + jsonString(j.spec) + ",\n  \"K\": " +
                                        jsonNumber(j.K) + ",\n  \"run\": " + std::to_string(j.r) +
                                        ",\n  \"seed\": " + std::to_string(j.seed) +
                                        ",\n  \"config\": " + jsonString(j.config.string()) +
                                        ",\n  \"started\": " + jsonString(nowUtc()) + "\n}\n");
      argv.insert(argv.end(), {"--config", j.config.string(), "--seed", std::to_string(j.seed),
                               "--out", j.dir.string(), "--force"});
    }
    argv.insert(argv.end(), {"--threads", std::to_string(threads), "-q"});
    appendText(m_out / "commands.txt", joinCommand(argv) + "\n");
    appendText(j.log, "# " + nowUtc() + ": " + joinCommand(argv) + "\n");
    say("md " + kName(j.K) + " run " + std::to_string(j.r) + ": " +
            (j.restart ? "restarting from its checkpoint" : "started") + " (seed " +
            std::to_string(j.seed) + ")",
        !tty);
    const pid_t pid = spawn(argv, j.log);
    running[pid] = {j, clock::now()};
  };

  while (!pending.empty() || !running.empty()) {
    while (!*stopSignal() && static_cast<int>(running.size()) < jobs && !pending.empty()) {
      start(pending.front());
      pending.pop_front();
    }
    progress();
    int st = 0;
    const pid_t pid = ::waitpid(-1, &st, WNOHANG);
    if (*stopSignal()) {
      // each run stops at the end of its chunk of steps with a checkpoint (granagg md handles
      // the signal); the next pair resumes it from there (RunJob::restart)
      const int sig = *stopSignal();
      for (auto& [p, r] : running) ::kill(p, SIGTERM);
      if (tty) std::fprintf(stderr, "\n");
      for (auto& [p, r] : running) {
        int child = 0;
        while (::waitpid(p, &child, 0) < 0 && errno == EINTR) {
        }
        say("md " + kName(r.job.K) + " run " + std::to_string(r.job.r) + ": stopped (" +
            lastLine(r.job.log) + ")");
      }
      say("interrupted (signal " + std::to_string(sig) +
          "): finished runs are kept, stopped runs continue from their checkpoints; run the "
          "same command again to resume");
      throw Interrupted("pair: interrupted; run the same command again to resume", sig);
    }
    if (pid == 0 || (pid < 0 && errno == EINTR)) {
      ::usleep(200000);
      continue;
    }
    if (pid < 0) throw std::runtime_error("waitpid failed: " + std::string(std::strerror(errno)));
    auto it = running.find(pid);
    if (it == running.end()) continue;
    Running r = it->second;
    running.erase(it);
    const double wall = std::chrono::duration<double>(clock::now() - r.start).count();
    const bool ok = WIFEXITED(st) && WEXITSTATUS(st) == 0;
    const std::string name = kName(r.job.K) + " run " + std::to_string(r.job.r);
    if (ok) {
      writeText(r.job.dir / "done.json",
                "{\n  \"spec\": " + jsonString(r.job.spec) + ",\n  \"K\": " + jsonNumber(r.job.K) +
                    ",\n  \"run\": " + std::to_string(r.job.r) +
                    ",\n  \"seed\": " + std::to_string(r.job.seed) +
                    ",\n  \"config\": " + jsonString(r.job.config.string()) +
                    ",\n  \"wall_seconds\": " + jsonNumber(wall) +
                    ",\n  \"threads\": " + std::to_string(threads) +
                    ",\n  \"restarted\": " + (r.job.restart ? "true" : "false") +
                    ",\n  \"finished\": " + jsonString(nowUtc()) +
                    ",\n  \"granagg\": " + jsonString(common::versionString()) + "\n}\n");
      ++finished;
      m_changed_k.insert(kName(r.job.K));
      if (tty) std::fprintf(stderr, "\r%100s\r", "");
      say("md " + name + ": done in " + formatReal(std::round(wall * 10) / 10) + " s" +
          (r.job.restart ? " (restarted)" : ""));
    } else if (r.job.restart) {
      // The checkpoint could not be continued (e.g. a trajectory cut by a kill): start afresh.
      say("md " + name + ": restart failed (" + lastLine(r.job.log) + "); starting it afresh",
          !tty);
      r.job.restart = false;
      pending.push_front(r.job);
    } else {
      ++finished;
      const std::string why = WIFEXITED(st) ? "exit status " + std::to_string(WEXITSTATUS(st))
                                            : "killed by signal " + std::to_string(WTERMSIG(st));
      failed.push_back(name);
      if (tty) std::fprintf(stderr, "\r%100s\r", "");
      say("md " + name + ": FAILED (" + why + "): " + lastLine(r.job.log) +
          " [log: " + r.job.log.string() + "]");
    }
  }
  if (tty) std::fprintf(stderr, "\r%100s\r", "");
  m_timing["md"] += std::chrono::duration<double>(clock::now() - t0).count();
  if (!failed.empty()) {
    std::string list;
    for (const auto& f : failed) list += (list.empty() ? "" : ", ") + f;
    throw std::runtime_error(
        std::to_string(failed.size()) + " MD run(s) failed (" + list + "; logs in " +
        (m_out / "logs").string() +
        "); finished runs are kept: run the same command again to retry the others");
  }
}

/// Runs one post-processing command (blocking); returns its exit status (127: could not run).
int Pair::runStep(const std::string& label, std::vector<std::string> argv,
                  const std::string& logname, bool quiet_failure) {
  const fs::path log = m_out / "logs" / (logname + ".log");
  appendText(m_out / "commands.txt", joinCommand(argv) + "\n");
  appendText(log, "# " + nowUtc() + ": " + joinCommand(argv) + "\n");
  if (!m_a.quiet && ::isatty(2)) {
    std::fprintf(stderr, "\rpair: %s ...%40s\r", label.c_str(), "");
    std::fflush(stderr);
  }
  const pid_t pid = spawn(argv, log);
  int st = 0;
  while (::waitpid(pid, &st, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("waitpid failed");
    if (*stopSignal()) {
      ::kill(pid, SIGTERM);
      ::waitpid(pid, nullptr, 0);
      throw Interrupted(
          "pair: interrupted during " + label + "; run the same command again to resume",
          *stopSignal());
    }
  }
  if (!m_a.quiet && ::isatty(2)) std::fprintf(stderr, "\r%100s\r", "");
  const int rc = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  if (rc != 0 && !quiet_failure)
    say(label + ": FAILED (exit status " + std::to_string(rc) + "): " + lastLine(log) +
        " [log: " + log.string() + "]");
  return rc;
}

bool Pair::stageDone(const fs::path& marker, const std::string& spec) const {
  return fs::exists(marker) && readText(marker) == spec;
}

void Pair::analyse() {
  const auto t0 = clock::now();
  for (double K : m_c.K) {
    const std::string name = kName(K);
    const fs::path dir = m_out / "analysis" / name, marker = m_out / "analysis" / (name + ".done");
    std::vector<std::string> argv{m_exe, "analyze"};
    std::string spec = "analyze";
    for (const RunJob& j : m_runs)
      if (j.K == K) {
        argv.push_back(j.dir.string());
        spec += " " + j.spec;
      }
    argv.insert(argv.end(), m_c.analysis_args.begin(), m_c.analysis_args.end());
    for (const auto& x : m_c.analysis_args) spec += " " + x;
    spec += "\n";
    if (!m_changed_k.count(name) && stageDone(marker, spec) && fs::exists(dir / "S_t.csv")) {
      say("analysis " + name + ": up to date, skipped", false);
      continue;
    }
    fs::remove(marker);
    fs::remove_all(dir);
    argv.insert(argv.end(), {"--out", dir.string(), "--threads", std::to_string(m_cores), "-q"});
    if (runStep("analysis " + name, argv, "analyze-" + name) == 0) {
      writeText(marker, spec);
      m_changed_k.insert(name);
      say("analysis " + name + ": done (" + dir.string() + ")");
    } else {
      ++m_failures;
      m_status["analysis " + name] = "failed";
    }
  }
  m_timing["analysis"] += std::chrono::duration<double>(clock::now() - t0).count();
}

void Pair::meanField() {
  const auto t0 = clock::now();
  const fs::path dir = m_out / "meanfield";
  fs::create_directories(dir);
  // Kinetic theory with the neutral runs' contact parameters (or the first K's).
  const md::MdConfig& ref =
      m_md.count(kName(0.0)) ? m_md.at(kName(0.0)) : m_md.at(kName(m_c.K.front()));
  double kappa = ref.charging.kappa;
  for (double K : m_c.K)
    if (K > 0) kappa = m_md.at(kName(K)).charging.kappa;
  double t_md = 0;
  for (const auto& [n, cfg] : m_md) t_md = std::max(t_md, cfg.run.t_end);
  struct Step {
    std::string label, file;
    std::vector<std::string> args;
  };
  std::vector<Step> steps;
  for (double b : m_c.betas)
    steps.push_back({"mean field S(t), beta = " + formatReal(b),
                     "S_beta" + formatReal(b) + ".csv",
                     {"smol", "--beta", formatReal(b), "--method", "sectional", "--t-end",
                      formatReal(m_c.mf_t_end), "--s-end", formatReal(m_c.mf_s_end)}});
  steps.push_back({"mean field z(beta)",
                   "zbeta.csv",
                   {"smol", "zbeta", "--beta-min", formatReal(m_c.zbeta_min), "--beta-max",
                    formatReal(m_c.zbeta_max), "--count", std::to_string(m_c.zbeta_count)}});
  steps.push_back(
      {"kinetic theory: cooling",
       "cooling.csv",
       {"kinetic", "cooling", "--phi", formatReal(ref.system.phi), "--E", formatReal(ref.contact.E),
        "--D", formatReal(ref.contact.D), "--t-end", formatReal(std::max(t_md, 1.0))}});
  steps.push_back({"kinetic theory: charging rate",
                   "charging.csv",
                   {"kinetic", "charging", "--kappa", formatReal(kappa)}});
  int ok = 0;
  for (const Step& s : steps) {
    const fs::path out = dir / s.file, marker = dir / (s.file + ".done");
    std::string spec;
    for (const auto& x : s.args) spec += x + " ";
    spec += "\n";
    if (stageDone(marker, spec) && fs::exists(out)) {
      ++ok;
      continue;
    }
    fs::remove(marker);
    std::vector<std::string> argv{m_exe};
    argv.insert(argv.end(), s.args.begin(), s.args.end());
    argv.insert(argv.end(), {"--out", out.string(), "--force"});
    if (s.args[0] == "smol" && s.args[1] != "zbeta") argv.push_back("-q");
    if (runStep(s.label, argv, "meanfield") == 0) {
      writeText(marker, spec);
      ++ok;
    } else {
      ++m_failures;
    }
  }
  m_status["meanfield"] =
      ok == static_cast<int>(steps.size()) ? "done" : "failed (see logs/meanfield.log)";
  say("mean field: " + m_status["meanfield"] + " (" + dir.string() + ")");
  m_timing["meanfield"] += std::chrono::duration<double>(clock::now() - t0).count();
}

void Pair::fitBeta() {
  const auto t0 = clock::now();
  if (!m_fit_available) {
    m_status["fit"] = "skipped: this granagg has no fit-beta subcommand";
    say("fit: skipped (this granagg build has no `fit-beta` subcommand; no beta is reported)");
    return;
  }
  int ok = 0;
  for (double K : m_c.K) {
    const std::string name = kName(K);
    const fs::path in = m_out / "analysis" / name, dir = m_out / "fit" / name,
                   marker = m_out / "fit" / (name + ".done");
    if (!fs::exists(in / "S_t.csv")) continue;
    std::vector<std::string> argv{m_exe, "fit-beta", in.string()};
    if (!m_c.fit_column.empty()) argv.insert(argv.end(), {"--column", m_c.fit_column});
    if (!m_c.fit_window.empty())
      argv.insert(argv.end(),
                  {"--window", formatReal(m_c.fit_window[0]), formatReal(m_c.fit_window[1])});
    const std::string spec = joinCommand(std::vector<std::string>(argv.begin() + 1, argv.end())) +
                             " " + readText(m_out / "analysis" / (name + ".done"));
    if (!m_changed_k.count(name) && stageDone(marker, spec) && fs::exists(dir / "fit_beta.json")) {
      ++ok;
      say("fit " + name + ": up to date, skipped", false);
      continue;
    }
    fs::remove(marker);
    fs::remove_all(dir);
    fs::create_directories(dir.parent_path());
    argv.insert(argv.end(), {"--out", dir.string(), "-q"});
    const int rc = runStep("fit " + name, argv, "fit-" + name, /*quiet_failure=*/true);
    if (rc == 0) {
      writeText(marker, spec);
      ++ok;
      say("fit " + name + ": done (" + dir.string() + ")");
    } else if (rc == 2) {
      // fit-beta's "these data cannot be fitted" (e.g. S(t) that does not grow in a short run): a
      // result to report, not a failure of the study.
      std::string why = lastLine(m_out / "logs" / ("fit-" + name + ".log"));
      if (why.rfind("granagg: error: ", 0) == 0) why = why.substr(16);
      m_fit_note[name] = "not possible for these data: " + why;
      say("fit " + name + ": not possible for these data (" + why + ")");
    } else {
      ++m_failures;
      say("fit " + name + ": FAILED (exit status " + std::to_string(rc) +
          ", log: " + (m_out / "logs" / ("fit-" + name + ".log")).string() + ")");
    }
  }
  const std::size_t fitted = static_cast<std::size_t>(ok), nK = m_c.K.size();
  m_status["fit"] = fitted == nK                      ? "done"
                    : fitted + m_fit_note.size() < nK ? "failed for some K (see logs/fit-*.log)"
                    : fitted > 0
                        ? "done where the data allow a fit"
                        : "not possible for these data (see each ensemble's fit_beta note)";
  m_timing["fit"] += std::chrono::duration<double>(clock::now() - t0).count();
}

/// Per-K numbers for the summary (NaN where a table is missing).
struct KResult {
  double K = 0;
  double z = NAN, z_low = NAN, z_high = NAN, fit_t_min = NAN, fit_t_max = NAN, runs = NAN;
  double fz = NAN, fz_low = NAN, fz_high = NAN, bz = NAN, bz_low = NAN, bz_high = NAN;
  double bf = NAN, bf_low = NAN, bf_high = NAN, S_c = NAN, tau_c = NAN, w0 = NAN, w1 = NAN;
  double ba = NAN, ba_low = NAN, ba_high = NAN;  ///< beta from the asymptotic law 3 z / (3 - z)
  bool bf_determined = true;                     ///< false when the curve fit ended at a bound
  double onset = NAN, onset_err = NAN;           ///< onset time of S_grid (analyze's fits.csv)
  granagg::analysis::GrowthRegime regime;        ///< of the ensemble-mean S_grid (S_t.csv)
  bool has_fit = false;
  std::string notes;  ///< fit-beta's notes on beta (clamped, no beta, at a bound)
};

/// The validation study's result for this K (data/validation/verdict.csv, written by
/// scripts/validation_report.py, described in docs/validation.md): one sentence, or "" when the
/// study has no row for K.
std::string validationLine(double K) {
  for (const auto& d : dataDirs()) {
    const fs::path p = fs::path(d) / "validation" / "verdict.csv";
    if (!fs::exists(p)) continue;
    try {
      const common::CsvTable t = common::readCsv(p.string());
      for (const auto& row : t.rows) {
        if (std::abs(row[t.column("K")] - K) > 1e-12 || row[t.column("quantity_id")] != 1.0)
          continue;
        char buf[600];
        std::snprintf(buf, sizeof buf,
                      "validation study (docs/validation.md; N = %.0f, %.0f runs to t = %.0f): z = "
                      "%.2f [%.2f, %.2f] over "
                      "t = %.0f..%.0f, onset t_c = %.0f, growth x%.0f; local slope %.2f..%.2f over "
                      "the last half "
                      "decade%s",
                      row[t.column("N")], row[t.column("runs")], row[t.column("t_end")],
                      row[t.column("value")], row[t.column("low")], row[t.column("high")],
                      row[t.column("t0")], row[t.column("t1")], row[t.column("onset")],
                      row[t.column("growth_factor")], row[t.column("zloc_min")],
                      row[t.column("zloc_max")],
                      row[t.column("zloc_max")] - row[t.column("zloc_min")] >
                              granagg::analysis::FLAT_SLOPE_TOLERANCE * 0.5 *
                                  (row[t.column("zloc_max")] + row[t.column("zloc_min")])
                          ? ": not a power law"
                          : "");
        return buf;
      }
    } catch (const std::exception&) {
    }
  }
  return "";
}

KResult readK(const fs::path& out, double K) {
  KResult r;
  r.K = K;
  const fs::path fits = out / "analysis" / kName(K) / "fits.csv";
  if (fs::exists(fits)) {
    try {
      const common::CsvTable t = common::readCsv(fits.string());
      if (!t.rows.empty()) {
        const auto& row = t.rows.front();
        r.z = row[t.column("z_grid")];
        r.z_low = row[t.column("z_grid_low")];
        r.z_high = row[t.column("z_grid_high")];
        r.fit_t_min = row[t.column("fit_t_min")];
        r.fit_t_max = row[t.column("fit_t_max")];
        r.runs = row[t.column("runs")];
        if (t.hasColumn("onset_time_grid")) {
          r.onset = row[t.column("onset_time_grid")];
          r.onset_err = row[t.column("onset_time_grid_err")];
        }
      }
    } catch (const std::exception&) {
    }
  }
  const fs::path st = out / "analysis" / kName(K) / "S_t.csv";
  r.regime.regime = "unknown";
  if (fs::exists(st)) {
    try {
      const common::CsvTable t = common::readCsv(st.string());
      std::vector<double> tt, S, z;
      for (const auto& row : t.rows) {
        tt.push_back(row[t.column("t")]);
        S.push_back(row[t.column("S_grid_mean")]);
        z.push_back(row[t.column(t.hasColumn("z_local_grid_of_mean") ? "z_local_grid_of_mean"
                                                                     : "z_local_grid")]);
      }
      r.regime = granagg::analysis::classifyGrowth(tt, S, z);
    } catch (const std::exception&) {
    }
  }
  const fs::path fj = out / "fit" / kName(K) / "fit_beta.json";
  if (fs::exists(fj)) {
    const std::string j = readText(fj);
    r.has_fit = true;
    r.fz = jsonValue(j, "z");
    r.fz_low = jsonValue(j, "z_low");
    r.fz_high = jsonValue(j, "z_high");
    r.bz = jsonValue(j, "beta_from_z");
    r.bz_low = jsonValue(j, "beta_from_z_low");
    r.bz_high = jsonValue(j, "beta_from_z_high");
    r.bf = jsonValue(j, "beta_fit");
    r.bf_low = jsonValue(j, "beta_fit_low");
    r.bf_high = jsonValue(j, "beta_fit_high");
    r.ba = jsonValue(j, "beta_asymptotic");
    r.ba_low = jsonValue(j, "beta_asymptotic_low");
    r.ba_high = jsonValue(j, "beta_asymptotic_high");
    r.bf_determined = j.find("\"beta_fit_determined\": false") == std::string::npos;
    r.S_c = jsonValue(j, "S_c");
    r.tau_c = jsonValue(j, "tau_c");
    r.w0 = jsonValue(j, "t0");
    r.w1 = jsonValue(j, "t1");
    if (!std::isfinite(r.w0)) {  // an array "window": [t0, t1]
      r.w0 = jsonValue(j, "window", 0);
      r.w1 = jsonValue(j, "window", 1);
    }
    for (const char* key : {"beta_from_z_note", "beta_asymptotic_note", "curve_fit_note"}) {
      const std::string n = jsonText(j, key);
      if (!n.empty()) r.notes += (r.notes.empty() ? "" : " ") + n;
    }
  }
  return r;
}

/// Local slope z of a mean-field S(t) table where S first reaches `S_target` (NaN if never).
double localSlopeAt(const fs::path& csv, double S_target) {
  if (!fs::exists(csv)) return NAN;
  try {
    const common::CsvTable t = common::readCsv(csv.string());
    const std::size_t cs = t.column("S"), cz = t.column("z_local");
    for (const auto& row : t.rows)
      if (row[cs] >= S_target) return row[cz];
  } catch (const std::exception&) {
  }
  return NAN;
}

std::string interval(double v, double lo, double hi) {
  return "{\"value\": " + jsonNumber(v) + ", \"low\": " + jsonNumber(lo) +
         ", \"high\": " + jsonNumber(hi) + "}";
}

void Pair::writeSummary() {
  std::ostringstream s;
  s << "{\n  \"granagg\": " << jsonString(common::versionString())
    << ",\n  \"study\": " << jsonString(m_c.name)
    << ",\n  \"config\": " << jsonString((m_out / "config" / "pair.toml").string())
    << ",\n  \"source_config\": " << jsonString(m_c.source)
    << ",\n  \"out\": " << jsonString(m_out.string())
    << ",\n  \"command\": " << jsonString(m_ctx.command_line)
    << ",\n  \"written\": " << jsonString(nowUtc()) << ",\n  \"cores\": " << m_cores
    << ",\n  \"backend\": " << jsonString(md::Engine::backendDescription()) << ",\n";
  const common::PaperValues& paper = paperValues();
  s << "  \"paper\": {\"reference\": " << jsonString(paper.reference)
    << ", \"z_neutral\": " << jsonNumber(paper.z_neutral)
    << ", \"z_neutral_pm\": " << jsonNumber(paper.z_neutral_pm)
    << ", \"z_charged\": " << jsonNumber(paper.z_charged)
    << ", \"z_charged_pm\": " << jsonNumber(paper.z_charged_pm)
    << ", \"z_meanfield_beta2\": " << jsonNumber(paper.z_meanfield_beta2)
    << ", \"z_meanfield_beta3\": " << jsonNumber(paper.z_meanfield_beta3) << "},\n";
  s << "  \"ensembles\": [\n";
  for (std::size_t k = 0; k < m_c.K.size(); ++k) {
    const double K = m_c.K[k];
    const KResult r = readK(m_out, K);
    const md::MdConfig& cfg = m_md.at(kName(K));
    s << "    {\"K\": " << jsonNumber(K) << ", \"name\": " << jsonString(kName(K))
      << ", \"runs\": " << m_c.runs << ", \"N\": " << cfg.system.N
      << ", \"phi\": " << jsonNumber(cfg.system.phi) << ", \"t_end\": " << jsonNumber(cfg.run.t_end)
      << ", \"charging_Q\": " << jsonNumber(cfg.charging.Q) << ",\n"
      << "     \"z_analyze\": " << interval(r.z, r.z_low, r.z_high) << ", \"z_analyze_window\": ["
      << jsonNumber(r.fit_t_min) << ", " << jsonNumber(r.fit_t_max)
      << "], \"z_analyze_method\": \"grid clusters, least squares of ln S on ln t, 95% "
      << (m_c.runs > 1 ? "bootstrap over runs" : "Student t") << "\",\n"
      << "     \"fit_beta\": "
      << (r.has_fit ? "\"done\""
                    : jsonString(m_fit_note.count(kName(K)) ? m_fit_note.at(kName(K))
                                 : m_status.count("fit")    ? m_status.at("fit")
                                                            : "not run"))
      << ", \"z\": " << interval(r.fz, r.fz_low, r.fz_high) << ", \"fit_window\": ["
      << jsonNumber(r.w0) << ", " << jsonNumber(r.w1)
      << "],\n     \"beta_from_z\": " << interval(r.bz, r.bz_low, r.bz_high)
      << ", \"beta_asymptotic\": " << interval(r.ba, r.ba_low, r.ba_high)
      << ", \"beta_asymptotic_applicable\": " << (r.regime.regime == "scaling" ? "true" : "false")
      << ", \"beta_fit\": " << interval(r.bf, r.bf_low, r.bf_high)
      << ", \"beta_fit_determined\": " << (r.bf_determined ? "true" : "false")
      << ", \"S_c\": " << jsonNumber(r.S_c) << ", \"tau_c\": " << jsonNumber(r.tau_c)
      << ", \"fit_notes\": " << jsonString(r.notes) << ",\n"
      << "     \"growth_factor\": " << jsonNumber(r.regime.growth_factor)
      << ", \"onset_time\": " << jsonNumber(r.onset)
      << ", \"onset_time_se\": " << jsonNumber(r.onset_err)
      << ", \"regime\": " << jsonString(r.regime.regime)
      << ", \"regime_reason\": " << jsonString(r.regime.reason)
      << ", \"validation\": " << jsonString(validationLine(K))
      << ",\n     \"paper_z\": " << jsonNumber(K == 0 ? paper.z_neutral : paper.z_charged)
      << ", \"paper_z_pm\": " << jsonNumber(K == 0 ? paper.z_neutral_pm : paper.z_charged_pm)
      << (K == 0 ? "" : ", \"paper_note\": \"the paper's charged value (K = 5)\"") << "}"
      << (k + 1 < m_c.K.size() ? "," : "") << "\n";
  }
  s << "  ],\n  \"meanfield\": [\n";
  const common::CsvTable* zb = nullptr;
  common::CsvTable zbt;
  if (fs::exists(m_out / "meanfield" / "zbeta.csv")) {
    try {
      zbt = common::readCsv((m_out / "meanfield" / "zbeta.csv").string());
      zb = &zbt;
    } catch (const std::exception&) {
    }
  }
  for (std::size_t k = 0; k < m_c.betas.size(); ++k) {
    const double b = m_c.betas[k];
    double zinf = NAN;
    if (zb)
      for (const auto& row : zb->rows)
        if (std::abs(row[zb->column("beta")] - b) < 1e-9) zinf = row[zb->column("z_asymptotic")];
    const fs::path csv = m_out / "meanfield" / ("S_beta" + formatReal(b) + ".csv");
    s << "    {\"beta\": " << jsonNumber(b) << ", \"z_scaling\": " << jsonNumber(3 * b / (b + 3))
      << ", \"z_asymptotic\": " << jsonNumber(zinf)
      << ", \"z_local_S250\": " << jsonNumber(localSlopeAt(csv, paper.S_beta2))
      << ", \"z_local_S1650\": " << jsonNumber(localSlopeAt(csv, paper.S_beta3))
      << ", \"paper_z\": "
      << (b == 2   ? jsonNumber(paper.z_meanfield_beta2)
          : b == 3 ? jsonNumber(paper.z_meanfield_beta3)
                   : std::string("null"))
      << "}" << (k + 1 < m_c.betas.size() ? "," : "") << "\n";
  }
  s << "  ],\n  \"steps\": {";
  bool first = true;
  for (const auto& [k, v] : m_status) {
    s << (first ? "" : ", ") << jsonString(k) << ": " << jsonString(v);
    first = false;
  }
  s << "},\n  \"timings_s\": {";
  first = true;
  for (const auto& [k, v] : m_timing) {
    s << (first ? "" : ", ") << jsonString(k) << ": " << jsonNumber(std::round(v * 100) / 100);
    first = false;
  }
  s << (first ? "" : ", ") << "\"total\": " << jsonNumber(std::round(seconds() * 100) / 100)
    << "},\n  \"commands\": [";
  std::istringstream cmds(readText(m_out / "commands.txt"));
  std::string line;
  first = true;
  s << "\n    " << jsonString(m_ctx.command_line);
  while (std::getline(cmds, line))
    if (!line.empty()) s << ",\n    " << jsonString(line);
  s << "\n  ]\n}\n";
  writeText(m_out / "summary.json", s.str());
}

std::string fmt(double v, int prec = 3) {
  if (!std::isfinite(v)) return "n/a";
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

void Pair::printSummary() {
  if (m_a.quiet) return;
  const common::PaperValues& paper = paperValues();
  std::fprintf(stderr, "pair: ---- summary (%s) ----\n", (m_out / "summary.json").c_str());
  for (double K : m_c.K) {
    const KResult r = readK(m_out, K);
    std::fprintf(stderr, "pair: K = %-5s z = %s [%s, %s] (analyze, grid, t in [%s, %s])",
                 formatReal(K).c_str(), fmt(r.z).c_str(), fmt(r.z_low).c_str(),
                 fmt(r.z_high).c_str(), fmt(r.fit_t_min, 3).c_str(), fmt(r.fit_t_max, 3).c_str());
    std::fprintf(stderr, "   paper: %s +- %s%s\n",
                 formatReal(K == 0 ? paper.z_neutral : paper.z_charged).c_str(),
                 formatReal(K == 0 ? paper.z_neutral_pm : paper.z_charged_pm).c_str(),
                 K == 0 ? "" : " (K = 5)");
    std::fprintf(stderr, "pair:           regime: %s (%s)\n", r.regime.regime.c_str(),
                 r.regime.reason.c_str());
    const std::string v = validationLine(K);
    if (!v.empty()) std::fprintf(stderr, "pair:           %s\n", v.c_str());
    if (r.has_fit)
      std::fprintf(
          stderr,
          "pair:           fit-beta: z = %s [%s, %s], beta from z at the data's S %s, asymptotic "
          "beta %s, "
          "full-curve beta = %s\n",
          fmt(r.fz).c_str(), fmt(r.fz_low).c_str(), fmt(r.fz_high).c_str(),
          (std::isfinite(r.bz)
               ? "= " + fmt(r.bz, 2) + " [" + fmt(r.bz_low, 2) + ", " + fmt(r.bz_high, 2) + "]"
               : std::string("n/a (z outside the mean field's range there)"))
              .c_str(),
          (r.regime.regime == "scaling"
               ? "= " + fmt(r.ba, 2) + " [" + fmt(r.ba_low, 2) + ", " + fmt(r.ba_high, 2) + "]"
               : "not applicable (no scaling regime; 3z/(3-z) would give " + fmt(r.ba, 2) + ")")
              .c_str(),
          r.bf_determined
              ? (fmt(r.bf, 2) + " [" + fmt(r.bf_low, 2) + ", " + fmt(r.bf_high, 2) + "]").c_str()
              : "not determined (at the bound of its range)");
    if (r.has_fit && !r.notes.empty())
      std::fprintf(stderr, "pair:           fit-beta note: %.200s%s\n", r.notes.c_str(),
                   r.notes.size() > 200 ? "..." : "");
    if (!r.has_fit)
      std::fprintf(stderr, "pair:           fit-beta: %s\n",
                   m_fit_note.count(kName(K)) ? m_fit_note.at(kName(K)).c_str()
                   : m_status.count("fit")    ? m_status.at("fit").c_str()
                                              : "not run");
  }
  for (double b : m_c.betas) {
    const fs::path csv = m_out / "meanfield" / ("S_beta" + formatReal(b) + ".csv");
    const double S_paper = b == 2 ? paper.S_beta2 : paper.S_beta3;
    const std::string paper_z = b == 2   ? "   paper: " + formatReal(paper.z_meanfield_beta2)
                                : b == 3 ? "   paper: " + formatReal(paper.z_meanfield_beta3)
                                         : "";
    std::fprintf(stderr,
                 "pair: mean field beta = %s: z(S ~ %g) = %s, asymptotic 3 beta/(beta+3) = %s%s\n",
                 formatReal(b).c_str(), S_paper, fmt(localSlopeAt(csv, S_paper)).c_str(),
                 fmt(3 * b / (b + 3)).c_str(), paper_z.c_str());
  }
  std::fprintf(stderr, "pair: wrote %s (summary.json%s) in %.0f s\n", m_out.c_str(),
               fs::exists(m_out / "report.html") ? ", report.html, figures/" : "", seconds());
}

void Pair::run() {
  resolveMd();  // every configuration error (exit 2) before anything is written
  prepareFolder();
  for (const auto& [path, text] : m_md_text)
    if (!fs::exists(path) || readText(path) != text) writeText(path, text);
  const std::string resolved = toToml(m_c);
  const fs::path cfgpath = m_out / "config" / "pair.toml";
  if (m_a.run_index < 0 && (!fs::exists(cfgpath) || readText(cfgpath) != resolved))
    writeText(cfgpath, resolved);
  if (m_a.run_index >= 0 && !fs::exists(cfgpath)) writeText(cfgpath, resolved);

  if (m_a.emit_batch == "slurm") {
    emitSlurm();
    return;
  }
  if (m_a.run_index >= 0) {  // one array task of a batch job
    if (m_a.run_index >= static_cast<int>(m_runs.size()))
      throw std::invalid_argument(
          "--run-index " + std::to_string(m_a.run_index) + " is out of range (the study has " +
          std::to_string(m_runs.size()) + " runs: 0.." + std::to_string(m_runs.size() - 1) + ")");
    runMd({m_runs[static_cast<std::size_t>(m_a.run_index)]});
    return;
  }
  say("study '" + m_c.name + "' -> " + m_out.string() + " (" + common::versionString() +
      "; K = " + tomlArray(m_c.K, realToml) + ", " + std::to_string(m_c.runs) + " runs each, " +
      std::to_string(m_cores) + " cores)");
  runMd(m_runs);
  analyse();
  meanField();
  fitBeta();
  m_status["md"] = "done";
  writeSummary();
  if (!m_a.no_figures) {
    const auto t0 = clock::now();
    const fs::path plot = scriptsDir() / "plot_figures.py",
                   report = scriptsDir() / "make_report.py";
    if (!fs::exists(plot)) {
      m_status["figures"] = "skipped: " + plot.string() + " not found (set GRANAGG_SCRIPTS)";
      say("figures: " + m_status["figures"]);
    } else if (runStep("figures", {python(), plot.string(), m_out.string()}, "figures") == 0) {
      m_status["figures"] = "done";
      say("figures: done (" + (m_out / "figures").string() + ")");
    } else {
      m_status["figures"] = "failed (see logs/figures.log)";
      ++m_failures;
    }
    m_timing["figures"] = std::chrono::duration<double>(clock::now() - t0).count();
    writeSummary();
    const auto t1 = clock::now();
    if (!fs::exists(report)) {
      m_status["report"] = "skipped: " + report.string() + " not found (set GRANAGG_SCRIPTS)";
      say("report: " + m_status["report"]);
    } else if (runStep("report", {python(), report.string(), m_out.string()}, "report") == 0) {
      m_status["report"] = "done";
      say("report: done (" + (m_out / "report.html").string() + ")");
    } else {
      m_status["report"] = "failed (see logs/report.log)";
      ++m_failures;
    }
    m_timing["report"] = std::chrono::duration<double>(clock::now() - t1).count();
  } else {
    m_status["figures"] = m_status["report"] = "skipped (--no-figures)";
  }
  writeSummary();
  printSummary();
  if (m_failures > 0)
    throw std::runtime_error(std::to_string(m_failures) + " post-processing step(s) failed (see " +
                             (m_out / "pair.log").string() +
                             "); run the same command again to retry them");
}

void runPair(const PairArgs& a, const CliContext& ctx, const CLI::App* root, bool runs_given,
             bool K_given) {
  if (a.preset.empty() == a.config.empty())
    throw std::invalid_argument("give exactly one of --preset NAME or --config FILE");
  if (a.jobs < 0)
    throw std::invalid_argument("--jobs must be >= 1 (got " + std::to_string(a.jobs) + ")");
  if (a.threads < 0)
    throw std::invalid_argument("--threads must be >= 1 (got " + std::to_string(a.threads) + ")");
  if (!a.emit_batch.empty() && a.emit_batch != "slurm")
    throw std::invalid_argument("--emit-batch supports only 'slurm' (got '" + a.emit_batch + "')");
  PairConfig c =
      parsePairConfig(a.config.empty() ? findPreset("pair", a.preset, "--preset") : a.config);
  if (K_given) c.K = parseKList(a.K);  // (--K "" is refused there, not ignored)
  if (runs_given) c.runs = a.runs;
  validate(c);
  bool fit = false;
  for (const CLI::App* sub : root->get_subcommands({})) fit |= sub->get_name() == "fit-beta";
  Pair pair(a, c, ctx, fit);
  catchStopSignals();  // forwarded to the runs, which stop with a checkpoint
  pair.run();
}

}  // namespace

void registerPairCommand(CLI::App& app, const CliContext& ctx) {
  auto a = std::make_shared<PairArgs>();
  CLI::App* c = app.add_subcommand(
      "pair",
      "Paired MD / mean-field study (docs/pair.md): MD ensembles for "
      "each Coulomb constant K (run r has seed pair.seed + r for every K, up to\n"
      "--jobs runs at a time), their analysis, the mean field "
      "(Smoluchowski S(t) for beta = 2, 3 and z(beta)), the\n"
      "beta fit, the paper's figures and report.html, and "
      "summary.json. An interrupted study resumes: run the same\n"
      "command again and finished runs are not redone.");
  c->add_option("--preset", a->preset,
                "Pair preset from data/pair: tiny, quick, paper, validate-neutral, "
                "validate-charged, validate-box");
  c->add_option("-c,--config", a->config, "Pair configuration TOML (keys: docs/pair.md)");
  c->add_option("--K", a->K, "Comma-separated Coulomb constants, e.g. 0,5 (overrides pair.K)");
  // bounded: --runs 1e9 grew to 24 GB before failing; 1e5 wrote a 2e5-task Slurm array
  c->add_option("--runs", a->runs, "Runs per K (1..10000; overrides pair.runs)")
      ->check(CLI::Range(1, MAX_RUNS));
  c->add_option("--jobs", a->jobs, "MD runs at a time, 1..1024 (default: max(1, cores / 2))")
      ->check(CLI::Range(1, 1024));
  c->add_option("--threads", a->threads,
                "OpenMP threads per MD run, 1..4096 (default: max(1, cores / jobs))")
      ->check(CLI::Range(1, 4096));
  c->add_option("-o,--out", a->out,
                "Output folder (default pair-<preset>); an existing study there is resumed");
  c->add_flag("--force", a->force, "Start over in an existing output folder (redo every run)");
  c->add_option("--emit-batch", a->emit_batch,
                "Write DIR/batch.slurm (a Slurm job array + follow-up job) instead of running");
  c->add_option("--run-index", a->run_index,
                "Run only the run with this index (k * runs + r); what batch array tasks call")
      ->group("");
  c->add_flag("--no-figures", a->no_figures, "Skip the figures and the report");
  c->add_flag("-q,--quiet", a->quiet, "No progress line or summary");
  const CLI::App* root = &app;
  c->callback([a, ctx, root, c]() {
    if (c->count("--run-index") > 0 && a->run_index < 0)  // -1 would start the whole study
      throw std::invalid_argument("--run-index must be >= 0 (got " +
                                  std::to_string(a->run_index) + ")");
    runPair(*a, ctx, root, c->count("--runs") > 0, c->count("--K") > 0);
  });
}

}  // namespace granagg::cli
