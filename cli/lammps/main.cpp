/// `granagg-lammps`: granagg's model on LAMMPS across MPI ranks (docs/lammps.md).
///
///     mpirun -np P granagg-lammps --config run.toml [--preset NAME] [--set k=v] --out DIR
///     mpirun -np P granagg-lammps --restart DIR [--set run.t_end=T]
///
/// The same configuration keys, presets and initial states as `granagg md`, and the same outputs:
/// the run is md::Simulation's (md/run/Simulation.h) with md::lammps::LammpsEngine
/// (md/lammps/LammpsEngine.h) as its engine, the log lines md/run/RunLog.h's. SIGINT and SIGTERM
/// stop the run at the end of a chunk with a checkpoint, on every rank (the flag is OR-ed over the
/// ranks), as `granagg md` does. Exit status as granagg's (cli/main.cpp): 0 done, 2 bad input
/// (one line naming the option or key, printed by rank 0), 128 + the signal for a run stopped by
/// one, 1 other failures. A separate executable, so that `granagg` itself never links MPI.
#include <mpi.h>

#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Strings.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/lammps/CollisionLog.h"
#include "md/lammps/FixCharging.h"
#include "md/lammps/LammpsEngine.h"
#include "md/run/RunLog.h"
#include "md/run/Simulation.h"

namespace {

using namespace granagg;

struct Args {
  std::string config, preset, out, restart;
  std::vector<std::string> set;
  bool force = false, quiet = false, collisions = false;
};

void log(int rank, const std::vector<std::string>& lines) {
  if (rank != 0) return;
  for (const auto& l : lines) std::fprintf(stderr, "%s\n", l.c_str());
}

void runLammps(const Args& a, const std::string& command_line, int rank) {
  const MPI_Comm comm = MPI_COMM_WORLD;
  md::RunOptions options;
  options.command_line = command_line;
  options.overwrite = a.force;
  cli::catchStopSignals();  // SIGINT / SIGTERM: stop at the end of a chunk with a checkpoint
  options.stop = cli::stopSignal();
  std::optional<md::Simulation> sim;
  md::lammps::LammpsEngine* engine = nullptr;  // owned by the Simulation
  std::int64_t resumed_from = -1;
  if (!a.restart.empty()) {
    if (!a.out.empty())
      throw std::invalid_argument(
          "--out cannot be combined with --restart: the run continues in its own folder " +
          a.restart);
    if (!a.config.empty() || !a.preset.empty() || a.collisions)
      throw std::invalid_argument(
          "--restart continues a run with its own configuration and outputs: do not combine it "
          "with --config, --preset or --collisions.");
    const md::lammps::LammpsCheckpoint ck = md::lammps::readLammpsCheckpoint(a.restart, comm);
    resumed_from = ck.step;
    sim.emplace(md::Simulation::resume(
        a.restart, a.set, options, ck.run_fields,
        (std::filesystem::path(a.restart) / md::lammps::LAMMPS_CHECKPOINT_FILE).string(),
        [&](const md::MdConfig& cfg) {
          auto e = std::make_unique<md::lammps::LammpsEngine>(cfg, a.restart, ck, comm);
          engine = e.get();
          return e;
        }));
  } else {
    if (!a.config.empty() && !a.preset.empty())
      throw std::invalid_argument("give one of --config FILE and --preset NAME, not both.");
    md::MdConfig cfg =
        a.config.empty() && a.preset.empty()
            ? md::parseConfigString("", "(defaults)", a.set)
            : md::parseConfigFile(
                  a.config.empty() ? cli::findPreset("presets", a.preset, "--preset") : a.config,
                  a.set);
    const std::string out = a.out.empty() ? "lammps-out" : a.out;
    auto e = std::make_unique<md::lammps::LammpsEngine>(cfg, out, a.collisions, command_line,
                                                        comm);
    engine = e.get();
    sim.emplace(md::Simulation::start(cfg, std::move(e), out, options));
  }
  if (sim->finished()) {  // --restart of a run at its run.t_end: say so, write nothing
    if (rank == 0)
      std::fprintf(stderr,
                   "granagg-lammps: the run in %s is complete at run.t_end = %s (step %lld): "
                   "nothing to do; to run it further: granagg-lammps --restart %s --set "
                   "run.t_end=T (T > %s)\n",
                   sim->folder().c_str(), common::formatReal(sim->config().run.t_end).c_str(),
                   static_cast<long long>(sim->engine().step()), sim->folder().c_str(),
                   common::formatReal(sim->config().run.t_end).c_str());
    return;
  }
  if (!a.quiet && rank == 0) {
    if (!sim->clearedStaleLock().empty())
      std::fprintf(stderr, "granagg-lammps: cleared the stale lock of %s\n",
                   sim->clearedStaleLock().c_str());
    if (!sim->trajectoryRepair().empty())
      std::fprintf(stderr, "granagg-lammps: %s\n", sim->trajectoryRepair().c_str());
    // the input LAMMPS got (also OUT/lammps.in)
    for (const auto& c : engine->input().commands) std::fprintf(stderr, "lammps: %s\n", c.c_str());
    for (const auto& n : engine->input().notes)
      std::fprintf(stderr, "granagg-lammps: %s\n", n.c_str());
    log(rank, md::runStartLines(*sim));
    sim->addReporter(std::make_shared<md::ProgressReporter>(*sim));
  }
  std::shared_ptr<md::lammps::CollisionLog> collisions;
  if (engine->recordsCollisions()) {
    collisions = std::make_shared<md::lammps::CollisionLog>(
        *engine, sim->folder() / "collisions.csv", command_line, resumed_from);
    sim->addReporter(collisions);
  }
  const md::RunSummary s = sim->run();
  const md::lammps::ContactStats stats = engine->fix().stats();  // (collective)
  if (collisions && !collisions->error().empty())
    throw std::runtime_error("cannot write collisions.csv: " + collisions->error());
  if (!a.quiet) {
    log(rank, md::runSummaryLines(*sim, s));
    log(rank, {"granagg-lammps: " + std::to_string(stats.migrations) +
               " migrations between ranks; total charge " +
               common::formatReal(s.observables.total_charge) + ", <|q|> = " +
               common::formatReal(s.observables.mean_abs_charge)});
  }
  if (s.stopped) {
    const int sig = *cli::stopSignal();
    // (the rank that caught no signal reports the one another rank caught as SIGTERM)
    throw cli::Interrupted(
        std::string(sig == SIGINT ? "SIGINT" : "SIGTERM") + " at step " +
            std::to_string(sim->engine().step()) + " (t = " +
            common::formatReal(sim->engine().time()) + " of " +
            common::formatReal(sim->config().run.t_end) +
            "); checkpoint and trajectory written; continue with: granagg-lammps --restart " +
            sim->folder().string(),
        sig == SIGINT ? SIGINT : SIGTERM);
  }
}

int run(int argc, char** argv, int rank) {
  Args a;
  CLI::App app(
      "granagg-lammps: granagg's model (viscoelastic contacts, collisional charging, Coulomb "
      "forces)\non LAMMPS across MPI ranks: mpirun -np P granagg-lammps --config run.toml --out "
      "DIR.\nThe configuration keys, presets and initial states of `granagg md` "
      "(docs/config.md), and its outputs\n(traj.h5, checkpoints); what LAMMPS cannot honour is "
      "an error naming the key (docs/lammps.md).",
      "granagg-lammps");
  app.set_version_flag("--version", common::versionString());
  app.add_option("-c,--config", a.config, "TOML configuration (keys: docs/config.md)");
  app.add_option("--preset", a.preset, "Preset from data/presets: quick, paper, haff");
  app.add_option("--set", a.set, "Override a key, e.g. --set system.N=5000 (repeatable)");
  app.add_option("-o,--out", a.out,
                 "Output folder (default lammps-out); must not exist or be empty unless --force");
  app.add_option("--restart", a.restart,
                 "Continue the run whose output folder (with checkpoint.toml) is given; --set "
                 "run.t_end=T runs it further. Any number of ranks");
  app.add_flag("--force", a.force,
               "Overwrite an existing output folder; clear a stale lock (of a run that was "
               "killed) with --out or --restart. A folder in use is never taken");
  app.add_flag("--collisions", a.collisions,
               "Also write OUT/collisions.csv: step, ids, approach speed and charge exchanged of "
               "every collision");
  app.add_flag("-q,--quiet", a.quiet, "No log lines");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return rank == 0 ? app.exit(e) : 0;
  } catch (const CLI::CallForVersion& e) {
    return rank == 0 ? app.exit(e) : 0;
  } catch (const CLI::ParseError& e) {
    if (rank == 0)
      std::fprintf(stderr, "granagg-lammps: %s\n", common::terminalSafe(e.what()).c_str());
    return 2;
  }
  try {
    runLammps(a, common::commandLine(argc, argv), rank);
    return 0;
  } catch (const std::invalid_argument& e) {  // (on every rank: the checks agree)
    if (rank == 0)
      std::fprintf(stderr, "granagg-lammps: %s\n", common::terminalSafe(e.what()).c_str());
    return 2;
  } catch (const cli::Interrupted& e) {  // (on every rank: the stop is agreed on)
    if (rank == 0)
      std::fprintf(stderr, "granagg-lammps: stopped: %s\n", common::terminalSafe(e.what()).c_str());
    return e.status();
  } catch (const std::exception& e) {
    // may have happened on one rank only (a file rank 0 could not write): end every rank
    std::fprintf(stderr, "granagg-lammps: error on rank %d: %s\n", rank,
                 common::terminalSafe(e.what()).c_str());
    MPI_Abort(MPI_COMM_WORLD, 1);
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const int status = run(argc, argv, rank);
  MPI_Finalize();
  return status;
}
