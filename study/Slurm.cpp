/// \file Slurm.cpp
/// The study's Slurm script (Slurm.h).
#include "study/Slurm.h"

#include <sstream>

#include "common/Csv.h"
#include "study/Process.h"

namespace granagg::study {

std::string slurmScript(const SlurmJob& j) {
  const std::string logs = (j.out / "logs").string(), path = (j.out / "batch.slurm").string();
  std::string K;
  for (double k : j.K) K += (K.empty() ? "" : ", ") + common::formatReal(k);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# granagg pair study '" << j.name << "': " << j.tasks << " MD runs (" << j.K.size()
    << " values of K x " << j.runs_per_K
    << " runs) as a Slurm job array, then the analysis, mean field, fit, figures and report as a\n"
    << "# follow-up job that starts once every array task succeeded. Written by: " << j.written_by
    << "\n#\n"
    << "#   bash " << path << "      submits both jobs (array + dependent follow-up)\n"
    << "#   sbatch " << path << "    submits the array only\n#\n"
    << "# Each task runs one MD run into " << (j.out / "runs").string()
    << "/K<K>/run<r>/ and marks it done; a task whose\n"
    << "# run is already done returns at once, so resubmitting the array after a failure redoes "
       "only what is missing.\n"
    << "# Adjust the #SBATCH lines (partition, account, time, GPUs: --gres=gpu:1 for a CUDA build) "
       "to your cluster.\n"
    << "#SBATCH --job-name=granagg-" << j.name << "\n"
    << "#SBATCH --array=0-" << (j.tasks - 1) << "\n";
  if (j.nodes > 0)
    s << "# Each task runs granagg-lammps on " << j.nodes << " node(s) x " << j.tasks_per_node
      << " MPI ranks, one CPU each, started with: " << j.launcher << "\n"
      << "#SBATCH --nodes=" << j.nodes << "\n"
      << "#SBATCH --ntasks-per-node=" << j.tasks_per_node << "\n"
      << "#SBATCH --cpus-per-task=1\n";
  else
    s << "#SBATCH --cpus-per-task=" << j.threads << "\n";
  s << "#SBATCH --time=24:00:00\n"
    << "# SIGTERM to the task 5 minutes before its time limit: the run stops with a checkpoint\n"
    << "# (granagg pair passes the signal on to the run), and resubmitting continues it from "
       "there.\n"
    << "#SBATCH --signal=B:TERM@300\n"
    << "#SBATCH --output=" << logs << "/slurm-%A_%a.out\n"
    << "set -euo pipefail\n"
    << "if [ -z \"${SLURM_JOB_ID:-}\" ]; then\n"
    << "  jid=$(sbatch --parsable \"$0\")\n"
    << "  sbatch --dependency=afterok:${jid%%;*} --job-name=granagg-" << j.name
    << "-post --cpus-per-task=" << j.threads << " --time=04:00:00 --output=" << logs
    << "/slurm-post-%j.out --wrap="
    << shellQuote(j.study_command + (j.task_options.empty() ? "" : " " + j.task_options)) << "\n"
    << "  echo \"submitted array job $jid and its follow-up\"\n"
    << "  exit 0\n"
    << "fi\n"
    << "# task index = k * " << j.runs_per_K << " + r for K index k (K = " << K << ") and run r\n"
    << "exec " << j.study_command << " --run-index \"$SLURM_ARRAY_TASK_ID\""
    << (j.task_options.empty() ? "" : " " + j.task_options)
    << " --threads \"${SLURM_CPUS_PER_TASK:-" << (j.nodes > 0 ? 1 : j.threads) << "}\" -q\n";
  return s.str();
}

}  // namespace granagg::study
