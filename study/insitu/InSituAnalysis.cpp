/// \file InSituAnalysis.cpp
/// The analysis during an MD run (InSituAnalysis.h).
#include "study/insitu/InSituAnalysis.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <regex>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "analysis/io/TrajectoryReader.h"
#include "analysis/pipeline/AnalysisFolder.h"
#include "analysis/pipeline/AnalyzeSettings.h"
#include "common/Box.h"
#include "common/Csv.h"
#include "md/config/ConfigParser.h"
#include "md/engine/RunEngine.h"
#include "md/io/Checkpoint.h"
#include "md/run/OutputReporters.h"

namespace granagg::insitu {
namespace fs = std::filesystem;
namespace an = granagg::analysis;

namespace {

// ---- [analysis] -> AnalyzeSettings -------------------------------------------------------------

using RealRef = double an::AnalyzeSettings::*;
using IntRef = int an::AnalyzeSettings::*;
using SizeRef = std::size_t an::AnalyzeSettings::*;
using LongRef = long long an::AnalyzeSettings::*;
using BoolRef = bool an::AnalyzeSettings::*;
using TextRef = std::string an::AnalyzeSettings::*;
using PairRef = std::vector<double> an::AnalyzeSettings::*;
using Ref = std::variant<RealRef, IntRef, SizeRef, LongRef, BoolRef, TextRef, PairRef>;

/// The keys in the order of `granagg analyze --help` (AnalyzeCommand.cpp), each the option's name
/// with '_' for '-'.
const std::vector<std::pair<std::string, Ref>>& table() {
  using S = an::AnalyzeSettings;
  static const std::vector<std::pair<std::string, Ref>> t = {
      {"grid_spacing", &S::grid_spacing},
      {"grid_min_fill", &S::grid_min_fill},
      {"grid_min_count", &S::grid_min_count},
      {"grid_assign", &S::grid_assign},
      {"no_grid", &S::no_grid},
      {"tolerance", &S::tolerance},
      {"no_particle", &S::no_particle},
      {"no_structure_factor", &S::no_structure},
      {"structure_kcut", &S::structure_k_cut},
      {"slope_ratio", &S::slope_ratio},
      {"fit_window", &S::fit_window},
      {"charge_fit_window", &S::charge_fit_window},
      {"mle_min_tail", &S::mle_min_tail},
      {"speed_max", &S::speed_max},
      {"speed_bins", &S::speed_bins},
      {"msd_origins", &S::msd_origins},
      {"msd_max_memory", &S::msd_max_memory_mib},
      {"kappa", &S::kappa},
      {"track", &S::track},
      {"bootstrap", &S::bootstrap},
      {"seed", &S::seed},
      {"onset_factor", &S::onset_factor},
      {"onset_baseline", &S::onset_baseline},
      {"fisher_bin_ratio", &S::fisher_bin_ratio},
  };
  return t;
}

std::string keyList() {
  std::string out;
  for (const auto& [k, ref] : table()) out += (out.empty() ? "" : ", ") + k;
  return out;
}

/// Where a key was set ("run.toml:12:1: " or "--set analysis.x=1: "), or "".
std::string originOf(const md::MdConfig& c, const std::string& key) {
  const auto it = c.origin.find("analysis." + key);
  return it == c.origin.end() ? std::string() : it->second + ": ";
}

[[noreturn]] void refuse(const md::MdConfig& c, const std::string& key, const std::string& what) {
  throw md::ConfigError(originOf(c, key) + "analysis." + key + " " + what, "analysis." + key);
}

/// Assigns one key from its TOML text; the value's type must be the option's.
void assign(const md::MdConfig& c, const std::string& key, const Ref& ref, const std::string& text,
            an::AnalyzeSettings& s) {
  toml::table doc;
  const std::string source = "v = " + text;
#if TOML_EXCEPTIONS
  try {
    doc = toml::parse(std::string_view(source));
  } catch (const toml::parse_error&) {
    refuse(c, key, "= " + text + " is not a TOML value");
  }
#else
  auto res = toml::parse(std::string_view(source));
  if (!res) refuse(c, key, "= " + text + " is not a TOML value");
  doc = std::move(res).table();
#endif
  const toml::node& v = *doc.get("v");
  const std::string got = " (got " + text + ")";
  auto real = [&](const toml::node& n, double& out) {
    if (auto f = n.as_floating_point()) return out = f->get(), true;
    if (auto i = n.as_integer()) return out = static_cast<double>(i->get()), true;
    return false;
  };
  if (auto r = std::get_if<RealRef>(&ref)) {
    if (!real(v, s.*(*r))) refuse(c, key, "must be a number" + got);
  } else if (auto r = std::get_if<IntRef>(&ref)) {
    auto i = v.as_integer();
    if (!i || i->get() < -2147483647 || i->get() > 2147483647)
      refuse(c, key, "must be an integer" + got);
    s.*(*r) = static_cast<int>(i->get());
  } else if (auto r = std::get_if<SizeRef>(&ref)) {
    auto i = v.as_integer();
    if (!i || i->get() < 0) refuse(c, key, "must be an integer >= 0" + got);
    s.*(*r) = static_cast<std::size_t>(i->get());
  } else if (auto r = std::get_if<LongRef>(&ref)) {
    auto i = v.as_integer();
    if (!i) refuse(c, key, "must be an integer" + got);
    s.*(*r) = static_cast<long long>(i->get());
  } else if (auto r = std::get_if<BoolRef>(&ref)) {
    auto b = v.as_boolean();
    if (!b) refuse(c, key, "must be true or false" + got);
    s.*(*r) = b->get();
  } else if (auto r = std::get_if<TextRef>(&ref)) {
    auto t = v.as_string();
    if (!t) refuse(c, key, "must be a string" + got);
    s.*(*r) = t->get();
  } else if (auto r = std::get_if<PairRef>(&ref)) {
    auto a = v.as_array();
    double lo = 0, hi = 0;
    if (!a || a->size() != 2 || !real(*a->get(0), lo) || !real(*a->get(1), hi))
      refuse(c, key, "must be two times [T_MIN, T_MAX]" + got);
    s.*(*r) = {lo, hi};
  }
}

}  // namespace

const std::vector<std::string>& analysisKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k;
    for (const auto& [name, ref] : table()) k.push_back(name);
    return k;
  }();
  return keys;
}

an::AnalysisOptions analysisOptions(const md::MdConfig& c) {
  an::AnalyzeSettings s;
  for (const auto& [key, text] : c.analysis) {
    const auto it = std::find_if(table().begin(), table().end(),
                                 [&](const auto& e) { return e.first == key; });
    if (it == table().end())
      throw md::ConfigError(originOf(c, key) + "unknown key 'analysis." + key +
                                "' (known keys in [analysis]: " + keyList() + ")",
                            "analysis." + key);
    assign(c, key, it->second, text, s);
  }
  // all time origins need evenly spaced frames: only output.frame_interval alone gives them
  if (s.msd_origins == "all" &&
      (c.output.frames_per_decade > 0 || !(c.output.frame_interval > 0.0)))
    refuse(c, "msd_origins",
           "= \"all\" needs evenly spaced frames: output.frame_interval > 0 and "
           "output.frames_per_decade = 0 (this run has " +
               std::to_string(c.output.frames_per_decade) + " per decade); use \"auto\" or \"t0\"");
  try {
    return an::analysisOptions(s, /*write_grid=*/false);
  } catch (const std::invalid_argument& e) {
    // analyze's messages name the command-line option: name the key instead, with its origin
    std::string msg = e.what();
    std::string first_key;
    static const std::regex option("--([a-z][a-z-]*)");
    std::string out;
    auto begin = std::sregex_iterator(msg.begin(), msg.end(), option);
    std::size_t last = 0;
    for (auto m = begin; m != std::sregex_iterator(); ++m) {
      std::string key = (*m)[1].str();
      std::replace(key.begin(), key.end(), '-', '_');
      if (key == "no_structure") key = "no_structure_factor";
      if (first_key.empty()) first_key = key;
      out += msg.substr(last, static_cast<std::size_t>(m->position()) - last) + "analysis." + key;
      last = static_cast<std::size_t>(m->position() + m->length());
    }
    out += msg.substr(last);
    throw md::ConfigError(originOf(c, first_key) + out,
                          first_key.empty() ? "" : "analysis." + first_key);
  }
}

an::Frame trajectoryFrame(const md::Frame& f, std::size_t index) {
  an::Frame out;
  const std::size_t n = f.size();
  out.index = index;
  out.step = f.step;
  out.time = f.time;
  out.box = f.box;
  out.position.resize(3 * n);
  out.image.resize(3 * n);
  const std::vector<double>* x[3] = {&f.x, &f.y, &f.z};
  const std::vector<std::int32_t>* im[3] = {&f.ix, &f.iy, &f.iz};
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      double xi = (*x[d])[i];
      std::int32_t ii = (*im[d])[i];
      if (!common::wrapCoordinate(xi, ii, f.box))  // (as H5mdWriter::writeFrame)
        throw std::runtime_error("in-situ analysis: particle " + std::to_string(i) +
                                 " has a position that is not finite at step " +
                                 std::to_string(f.step));
      out.position[3 * i + d] = xi;
      out.image[3 * i + d] = ii;
    }
  out.velocity.resize(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    out.velocity[3 * i] = f.vx[i];
    out.velocity[3 * i + 1] = f.vy[i];
    out.velocity[3 * i + 2] = f.vz[i];
  }
  out.charge = f.charge.empty() ? std::vector<double>(n, 0.0) : f.charge;
  out.id.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.id[i] = static_cast<std::int64_t>(i);
  return out;
}

// ---- the reporter ------------------------------------------------------------------------------

namespace {

std::map<std::string, std::string> runParameters(const md::Simulation& sim,
                                                 const std::string& command_line) {
  std::map<std::string, std::string> p;
  for (auto& [k, v] :
       md::trajectoryParameters(sim.config(), sim.engine(), command_line, sim.dtReason()))
    p[k] = v;
  return p;
}

}  // namespace

InSituAnalysis::InSituAnalysis(const md::Simulation& sim, std::string command_line,
                               std::function<void(const std::string&)> log)
    : m_options(analysisOptions(sim.config())),
      m_command_line(std::move(command_line)),
      m_log(std::move(log)) {
  m_analysis = std::make_unique<an::RunAnalysis>(m_options, sim.folder().string(), "in-situ",
                                                 runParameters(sim, m_command_line));
  if (sim.resumed())
    resumeState(sim);
  else
    addCurrentFrame(sim);  // the frame at t = 0 that start() wrote
}

InSituAnalysis::~InSituAnalysis() = default;

void InSituAnalysis::removeOutputs(const fs::path& run) {
  std::error_code ec;
  fs::remove_all(resultFolder(run), ec);
  fs::remove(stateFile(run), ec);
  fs::remove(previousStateFile(run), ec);
}

std::size_t InSituAnalysis::frames() const { return m_analysis->frames(); }

void InSituAnalysis::addCurrentFrame(const md::Simulation& sim) {
  const md::Frame f = sim.engine().frame(md::StateKind::Physical);
  m_analysis->add(trajectoryFrame(f, m_analysis->frames()));
}

void InSituAnalysis::resumeState(const md::Simulation& sim) {
  const std::int64_t step = sim.engine().step();
  const fs::path run = sim.folder();
  std::string found;
  for (const fs::path& file : {stateFile(run), previousStateFile(run)}) {
    if (!fs::exists(file)) continue;
    std::int64_t tag = -1;
    try {
      tag = an::RunAnalysis::stateTag(file.string());
    } catch (const std::runtime_error&) {
      found += (found.empty() ? "" : ", ") + file.filename().string() + " unreadable";
      continue;
    }
    if (tag == step) {
      try {
        m_analysis->restoreState(file.string());
        m_state_step = step;
        return;
      } catch (const std::runtime_error& e) {  // (another build's tables): rebuild below
        found += (found.empty() ? "" : ", ") + std::string(e.what());
        m_analysis = std::make_unique<an::RunAnalysis>(m_options, sim.folder().string(),
                                                       "in-situ",
                                                       runParameters(sim, m_command_line));
        continue;
      }
    }
    found += (found.empty() ? "" : ", ") + file.filename().string() + " at step " +
             std::to_string(tag);
  }
  // No state for this checkpoint: rebuild it from the trajectory's frames where it has them.
  const fs::path traj = sim.trajectoryPath();
  if (sim.config().output.trajectory && sim.config().output.write_velocities &&
      sim.framesWritten() > 0) {
    auto reader = an::openTrajectory(traj.string());
    an::Frame f;
    while (reader->next(f) && f.step <= step) m_analysis->add(f);
    m_state_step = step;
    if (m_log)
      m_log("md: rebuilt the in-situ analysis of step " + std::to_string(step) + " from the " +
            std::to_string(m_analysis->frames()) + " frames of " + traj.string() +
            " (no saved state matched the checkpoint: " + (found.empty() ? "none" : found) + ")");
    return;
  }
  throw std::runtime_error(
      "cannot continue the in-situ analysis of " + run.string() + ": no analysis state for the "
      "checkpoint's step " + std::to_string(step) + " (" + (found.empty() ? "none found" : found) +
      ") and no trajectory frames to rebuild it from; start the run again with --force");
}

std::int64_t InSituAnalysis::nextStep(const md::Simulation& sim) const {
  return md::Reporter::nextStep(sim);  // the trajectory reporter stops the run at frame times
}

void InSituAnalysis::report(const md::Simulation& sim) {
  const std::int64_t step = sim.engine().step();
  if (sim.frameStep() != step || m_analysis->lastStep() == step) return;
  try {
    addCurrentFrame(sim);
  } catch (const std::exception& e) {
    throw std::runtime_error(
        "in-situ analysis failed at step " + std::to_string(step) + " (t = " +
        common::formatReal(sim.engine().time()) + "): " + e.what() +
        "; the run stopped there without a new checkpoint. Continue it from the last one" +
        (m_state_step >= 0 ? " (step " + std::to_string(m_state_step) + ")" : std::string()) +
        " with: granagg md --restart " + sim.folder().string());
  }
}

void InSituAnalysis::beforeCheckpoint(const md::Simulation& sim, std::int64_t step) {
  const fs::path run = sim.folder();
  const fs::path current = stateFile(run), previous = previousStateFile(run);
  // the state of the checkpoint now on disk stays until the new checkpoint is written
  if (fs::exists(current)) fs::rename(current, previous);
  m_analysis->saveState(current.string(), step);
  m_state_step = step;
}

fs::path InSituAnalysis::writeResults(const md::Simulation& sim) {
  const fs::path out = resultFolder(sim.folder());
  an::RunResult result = m_analysis->finish();
  // a continued run's analysis replaces the one of the shorter run it continued
  fs::path old = out;
  old += ".replaced";
  std::error_code ec;
  fs::remove_all(old, ec);
  if (fs::exists(out)) fs::rename(out, old);
  an::writeRunAnalysis(out.string(), std::move(result), m_options, m_command_line);
  fs::remove_all(old, ec);
  return out;
}

std::optional<an::RunResult> storedResult(const std::string& path) {
  const fs::path run(path);
  const fs::path cpath = run / "checkpoint.h5";
  if (!fs::is_directory(run) || !fs::exists(cpath) ||
      !(fs::exists(InSituAnalysis::stateFile(run)) ||
        fs::exists(InSituAnalysis::previousStateFile(run))))
    return std::nullopt;
  const md::Checkpoint cp = md::readCheckpoint(cpath.string());
  if (cp.run.frames_written > 0) return std::nullopt;  // frames to read: analyze does that
  const md::MdConfig cfg = md::parseConfigString(cp.run.config_toml, cpath.string());
  if (!cfg.output.analyze) return std::nullopt;
  const an::AnalysisOptions options = analysisOptions(cfg);
  std::map<std::string, std::string> parameters;
  const auto reader = an::openTrajectory(run.string());
  for (const auto& [k, v] : reader->parameters()) parameters[k] = v;
  an::RunAnalysis analysis(options, path, "in-situ", parameters);
  for (const fs::path& file : {InSituAnalysis::stateFile(run),
                               InSituAnalysis::previousStateFile(run)}) {
    if (!fs::exists(file) || an::RunAnalysis::stateTag(file.string()) != cp.state.step) continue;
    analysis.restoreState(file.string());
    return analysis.finish();
  }
  throw std::invalid_argument("run '" + path + "' stored no frames and its in-situ analysis "
                              "state does not match its checkpoint (step " +
                              std::to_string(cp.state.step) +
                              "): continue it with granagg md --restart " + path);
}

}  // namespace granagg::insitu
