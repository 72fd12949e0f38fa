#pragma once
/// \file MdLaunch.h
/// How a study starts its MD runs ([md] engine, docs/pair.md): `granagg md`, or granagg-lammps
/// (docs/lammps.md) under an MPI launcher, with the run's configuration and seed, or continuing
/// the run from the checkpoint in its folder.
#include <string>
#include <vector>

namespace granagg::study {

struct RunJob;

struct MdLaunch {
  std::string engine = "granagg";     ///< a value of MD_ENGINES (PairConfig.h)
  std::string granagg;                ///< the granagg binary (`granagg md`)
  std::string granagg_lammps;         ///< the granagg-lammps binary (engine "lammps")
  std::vector<std::string> launcher;  ///< the MPI launcher's words (engine "lammps")
  bool lammps() const { return engine == "lammps"; }
};

/// The file whose presence in a run folder means the run can continue from a checkpoint:
/// checkpoint.h5 (granagg md) or checkpoint.toml (granagg-lammps, naming its restart file).
std::string checkpointFile(const MdLaunch& launch);

/// The command of one MD run. A fresh start (job.restart false):
///     granagg md --config C --seed S --out DIR --force --threads T -q
///     LAUNCHER... granagg-lammps --config C --set system.seed=S --out DIR --force -q
/// and a restart from the folder's checkpoint (job.restart true):
///     granagg md --restart DIR --force --threads T -q
///     LAUNCHER... granagg-lammps --restart DIR --force -q
/// --force overwrites what an interrupted attempt left (a fresh start) or clears the stale lock
/// of a run killed with the study (a restart); a folder in use is never taken either way.
/// granagg-lammps takes no thread count: its ranks are its cores.
std::vector<std::string> mdCommand(const MdLaunch& launch, const RunJob& job, int threads);

}  // namespace granagg::study
