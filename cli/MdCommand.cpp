/// `granagg md`: run the MD engine from a TOML configuration, write an H5MD trajectory,
/// observables and checkpoints into an output folder; `--restart DIR` continues a run. The run is
/// md::Simulation's (md/run/Simulation.h), its log lines md/run/RunLog.h's; this file wires the
/// options.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/OutputPath.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"
#include "md/run/RunLog.h"
#include "md/run/Simulation.h"
#include "study/insitu/InSituAnalysis.h"

namespace granagg::cli {

namespace {

struct MdArgs {
  std::string config;
  std::string preset;
  std::vector<std::string> set;
  std::string out;
  std::string restart;
  std::string seed;  // "" = not given; else an integer in [0, 2^64) (checked in runMd)
  int threads = 0;
  bool force = false;
  bool quiet = false;
  bool profile = false;
  bool analyze = false;
};

/// The log on stderr, one line each (stdout stays empty: md writes no table).
void log(const std::vector<std::string>& lines) {
  for (const auto& l : lines) std::fprintf(stderr, "%s\n", l.c_str());
}

/// --seed as given, if it is an integer in [0, 2^64) (system.seed's range, docs/config.md): a
/// long long option turned -1 into "not given" and clamped seeds above 2^63 - 1.
std::string checkedSeed(const std::string& s) {
  errno = 0;
  char* end = nullptr;
  const bool digits =
      !s.empty() && s.size() <= 20 && s.find_first_not_of("0123456789") == std::string::npos;
  if (digits) std::strtoull(s.c_str(), &end, 10);
  if (!digits || errno == ERANGE)
    throw std::invalid_argument("--seed must be an integer in [0, 2^64) (got '" + s + "')");
  return s;
}

void runMd(const MdArgs& a, const CliContext& ctx) {
  if (a.threads < 0) throw std::invalid_argument("--threads must be >= 1.");
  if (a.threads > 0) md::Engine::setThreads(a.threads);
  md::RunOptions options;
  options.command_line = ctx.command_line;
  options.overwrite = a.force;
  options.profile = a.profile;
  catchStopSignals();  // SIGINT / SIGTERM: stop at the end of a chunk with a checkpoint
  options.stop = stopSignal();
  std::optional<md::Simulation> sim;
  if (!a.restart.empty()) {
    if (!a.out.empty())
      throw std::invalid_argument(
          "--out cannot be combined with --restart: the run continues in "
          "its own folder " +
          a.restart);
    if (!a.config.empty() || !a.preset.empty() || !a.seed.empty())
      throw std::invalid_argument(
          "--restart continues a run with its own configuration: do not "
          "combine it with --config, --preset or --seed.");
    if (a.analyze)
      throw std::invalid_argument(
          "--analyze cannot be combined with --restart: the in-situ analysis starts with its run "
          "(a run started with --analyze continues its analysis by itself); analyse this one with "
          "granagg analyze " + a.restart);
    sim.emplace(md::Simulation::resume(a.restart, a.set, options));
  } else {
    if (!a.config.empty() && !a.preset.empty())
      throw std::invalid_argument("give one of --config FILE and --preset NAME, not both.");
    std::vector<std::string> overrides = a.set;
    if (!a.seed.empty()) overrides.push_back("system.seed=" + checkedSeed(a.seed));
    if (a.analyze) overrides.push_back("output.analyze=true");
    // neither: every key has a default (docs/config.md), --set changes them
    const md::MdConfig cfg =
        a.config.empty() && a.preset.empty()
            ? md::parseConfigString("", "(defaults)", overrides)
            : md::parseConfigFile(
                  a.config.empty() ? findPreset("presets", a.preset, "--preset") : a.config,
                  overrides);
    const std::string out = a.out.empty() ? "md-out" : a.out;
    common::checkOutputFolder(out);  // before the initial state and the engine are built
    if (cfg.output.analyze) insitu::analysisOptions(cfg);  // bad [analysis]: exit 2, nothing written
    sim.emplace(md::Simulation::start(cfg, out, options));
    if (cfg.output.analyze) insitu::InSituAnalysis::removeOutputs(out);  // of a run --force replaced
  }
  if (sim->finished() && sim->config().output.analyze &&
      !std::filesystem::exists(insitu::InSituAnalysis::resultFolder(sim->folder()))) {
    // stopped after its last checkpoint but before its analysis was written (a kill, a full
    // disk): the state of the last step finishes it
    insitu::InSituAnalysis analysis(*sim, ctx.command_line);
    const auto folder = analysis.writeResults(*sim);
    std::fprintf(stderr, "md: the run in %s is complete; wrote its in-situ analysis (%zu frames) "
                 "to %s\n", sim->folder().c_str(), analysis.frames(), folder.c_str());
    return;
  }
  if (sim->finished()) {  // --restart of a run at its run.t_end: say so, write nothing
    std::fprintf(stderr,
                 "md: the run in %s is complete at run.t_end = %s (step %lld): nothing to do; "
                 "to run it further: granagg md --restart %s --set run.t_end=T (T > %s)\n",
                 sim->folder().c_str(), common::formatReal(sim->config().run.t_end).c_str(),
                 static_cast<long long>(sim->engine().step()), sim->folder().c_str(),
                 common::formatReal(sim->config().run.t_end).c_str());
    return;
  }
  std::shared_ptr<insitu::InSituAnalysis> analysis;
  if (sim->config().output.analyze) {
    analysis = std::make_shared<insitu::InSituAnalysis>(
        *sim, ctx.command_line,
        [&a](const std::string& line) {
          if (!a.quiet) std::fprintf(stderr, "%s\n", line.c_str());
        });
    sim->addReporter(analysis);
  }
  if (!sim->clearedStaleLock().empty() && !a.quiet)
    std::fprintf(stderr, "md: took over the stale lock of %s, which ended without releasing it\n",
                 sim->clearedStaleLock().c_str());
  if (!sim->trajectoryRepair().empty() && !a.quiet)
    std::fprintf(stderr, "md: %s\n", sim->trajectoryRepair().c_str());
  if (!a.quiet) {
    log(md::runStartLines(*sim));
    sim->addReporter(std::make_shared<md::ProgressReporter>(*sim));
  }
  md::RunSummary s;
  try {
    s = sim->run();
  } catch (const std::runtime_error& e) {
    // A write that failed mid-run (a full disk, a quota): the last checkpoint and the journaled
    // trajectory stand, so the run continues once the cause is gone.
    if (dynamic_cast<const md::RunAborted*>(&e)) throw;
    throw std::runtime_error(std::string(e.what()) + "; once that is fixed, continue with " +
                             "granagg md --restart " + sim->folder().string());
  }
  if (a.profile) log(md::profileLines(sim->engine(), s.steps, s.loop_seconds));
  if (!a.quiet) log(md::runSummaryLines(*sim, s));
  if (analysis && !s.stopped) {
    const auto folder = analysis->writeResults(*sim);
    if (!a.quiet)
      std::fprintf(stderr, "md: in-situ analysis of %zu frames written to %s\n", analysis->frames(),
                   folder.c_str());
  }
  if (s.stopped) {
    const int sig = *stopSignal();
    char t[32];
    std::snprintf(t, sizeof t, "%.6g", sim->engine().time());
    throw Interrupted(std::string("md: ") + (sig == SIGINT ? "SIGINT" : "SIGTERM") + " at step " +
                          std::to_string(sim->engine().step()) + " (t = " + t + " of " +
                          common::formatReal(sim->config().run.t_end) +
                          "); checkpoint and trajectory written; continue with: granagg md "
                          "--restart " +
                          sim->folder().string(),
                      sig);
  }
}

}  // namespace

void registerMdCommand(CLI::App& app, const CliContext& ctx) {
  auto a = std::make_shared<MdArgs>();
  CLI::App* md = app.add_subcommand(
      "md",
      "Run the MD engine (viscoelastic or spring-dashpot granular gas) and write an H5MD "
      "trajectory,\n"
      "observables and a checkpoint into an output folder. Reduced units d = m = T0 = 1.");
  md->add_option("-c,--config", a->config, "TOML configuration (keys: docs/config.md)");
  md->add_option("--preset", a->preset, "Preset from data/presets: quick, paper, haff");
  md->add_option("--set", a->set, "Override a key, e.g. --set system.N=5000 (repeatable)");
  md->add_option("-o,--out", a->out,
                 "Output folder (default md-out); must not exist or be empty unless --force");
  md->add_option("--restart", a->restart,
                 "Continue the run whose output folder (with checkpoint.h5) is given; --set "
                 "run.t_end=T runs it further");
  md->add_option("--seed", a->seed, "Random seed, an integer in [0, 2^64) (overrides system.seed)");
  md->add_option("--threads", a->threads, "OpenMP threads (default: all cores; OMP_NUM_THREADS)")
      ->check(CLI::Range(1, 4096));
  md->add_flag("--force", a->force,
               "Overwrite an existing output folder; clear a stale lock (of a run that was "
               "killed) with --out or --restart. A folder in use is never taken");
  md->add_flag("--analyze", a->analyze,
               "Analyse every frame during the run ([analysis] options, those of granagg analyze)"
               " into OUT/analysis, as granagg analyze OUT --out OUT/analysis would; with --set "
               "output.trajectory=false no particle frame is stored (output.analyze = true)");
  md->add_flag("-q,--quiet", a->quiet, "No progress line or summary");
  md->add_flag(
      "--profile", a->profile,
      "Time the MD loop by phase (contact pass, lists, Coulomb, PPPM parts); prints a table "
      "and writes OUT/profile.csv. Changes no result");
  md->callback([a, ctx]() { runMd(*a, ctx); });
}

}  // namespace granagg::cli
