/// `granagg-lammps`: granagg's model on LAMMPS across MPI ranks (docs/lammps.md).
///
///     mpirun -np P granagg-lammps --config run.toml [--preset NAME] [--set k=v] --out DIR
///
/// The same configuration keys, presets and initial states as `granagg md`; the run is
/// md::lammps::runOnLammps (md/lammps/LammpsRun.h). Exit status as granagg's (cli/main.cpp):
/// 0 done, 2 bad input (one line naming the option or key, printed by rank 0), 1 other failures.
/// A separate executable, so that `granagg` itself never links MPI.
#include <mpi.h>

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/lammps/LammpsRun.h"

namespace {

struct Args {
  std::string config, preset, out;
  std::vector<std::string> set;
  bool force = false, quiet = false, collisions = false;
};

int run(int argc, char** argv, int rank) {
  using namespace granagg;
  Args a;
  CLI::App app(
      "granagg-lammps: granagg's model (viscoelastic contacts, collisional charging, Coulomb "
      "forces)\non LAMMPS across MPI ranks: mpirun -np P granagg-lammps --config run.toml --out "
      "DIR.\nThe configuration keys, presets and initial states of `granagg md` "
      "(docs/config.md);\nwhat LAMMPS cannot honour is an error naming the key "
      "(docs/lammps.md).",
      "granagg-lammps");
  app.set_version_flag("--version", common::versionString());
  app.add_option("-c,--config", a.config, "TOML configuration (keys: docs/config.md)");
  app.add_option("--preset", a.preset, "Preset from data/presets: quick, paper, haff");
  app.add_option("--set", a.set, "Override a key, e.g. --set system.N=5000 (repeatable)");
  app.add_option("-o,--out", a.out,
                 "Output folder (default lammps-out); must not exist or be empty unless --force");
  app.add_flag("--force", a.force, "Write into an existing, non-empty output folder");
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
    if (rank == 0) std::fprintf(stderr, "granagg-lammps: %s\n", e.what());
    return 2;
  }
  try {
    if (!a.config.empty() && !a.preset.empty())
      throw std::invalid_argument("give one of --config FILE and --preset NAME, not both.");
    const md::MdConfig cfg =
        a.config.empty() && a.preset.empty()
            ? md::parseConfigString("", "(defaults)", a.set)
            : md::parseConfigFile(
                  a.config.empty() ? cli::findPreset("presets", a.preset, "--preset") : a.config,
                  a.set);
    md::lammps::LammpsRunOptions o;
    o.out = a.out;
    o.overwrite = a.force;
    o.quiet = a.quiet;
    o.record_collisions = a.collisions;
    o.command_line = common::commandLine(argc, argv);
    md::lammps::runOnLammps(cfg, o, MPI_COMM_WORLD);
    return 0;
  } catch (const std::invalid_argument& e) {
    if (rank == 0) std::fprintf(stderr, "granagg-lammps: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    // may have happened on one rank only (a file rank 0 could not write): end every rank
    std::fprintf(stderr, "granagg-lammps: error on rank %d: %s\n", rank, e.what());
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
