/// \file MdLaunch.cpp
/// The command lines of a study's MD runs (MdLaunch.h).
#include "study/MdLaunch.h"

#include "study/PairStudy.h"

namespace granagg::study {

std::string checkpointFile(const MdLaunch& launch) {
  return launch.lammps() ? "checkpoint.toml" : "checkpoint.h5";
}

std::vector<std::string> mdCommand(const MdLaunch& launch, const RunJob& job, int threads) {
  std::vector<std::string> argv;
  if (launch.lammps()) {
    argv = launch.launcher;
    argv.push_back(launch.granagg_lammps);
  } else {
    argv = {launch.granagg, "md"};
  }
  if (job.restart) {
    argv.insert(argv.end(), {"--restart", job.dir.string(), "--force"});
  } else {
    argv.insert(argv.end(), {"--config", job.config.string()});
    if (launch.lammps())
      argv.insert(argv.end(), {"--set", "system.seed=" + std::to_string(job.seed)});
    else
      argv.insert(argv.end(), {"--seed", std::to_string(job.seed)});
    argv.insert(argv.end(), {"--out", job.dir.string(), "--force"});
  }
  if (!launch.lammps()) argv.insert(argv.end(), {"--threads", std::to_string(threads)});
  argv.push_back("-q");
  return argv;
}

}  // namespace granagg::study
