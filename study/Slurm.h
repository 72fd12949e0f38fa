#pragma once
/// \file Slurm.h
/// A study as a Slurm job array (one task per MD run) plus a follow-up job for the rest.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace granagg::study {

struct SlurmJob {
  std::string name;       ///< the study's name (job names granagg-<name>[-post])
  std::size_t tasks = 0;  ///< array tasks: one per MD run
  int runs_per_K = 0;     ///< task index = k * runs_per_K + r
  std::vector<double> K;  ///< the Coulomb constants, in index order
  int threads = 4;        ///< --cpus-per-task (of the follow-up job; of a task without nodes)
  /// > 0: each task is one granagg-lammps run on `nodes` nodes with `tasks_per_node` MPI ranks
  /// each (one CPU per rank), started by `launcher`; 0: each task is a `granagg md` run with
  /// `threads` CPUs.
  int nodes = 0, tasks_per_node = 0;
  std::string launcher;       ///< the ranks' launcher in a task, e.g. srun --nodes=2 ... (shown)
  std::string task_options;   ///< further options of the study command in every job (shell-quoted)
  std::filesystem::path out;  ///< the study folder (logs go to out/logs)
  std::string study_command;  ///< the command that resumes the study (shell-quoted)
  std::string written_by;     ///< the command line that wrote the script
};

/// The script: run with bash, it submits the array and a follow-up job that starts once every
/// task succeeded; run with sbatch, the array only. Each task runs
/// `study_command --run-index $SLURM_ARRAY_TASK_ID`; SIGTERM 5 minutes before the time limit
/// stops a run with a checkpoint, so that resubmitting continues it.
std::string slurmScript(const SlurmJob& job);

}  // namespace granagg::study
