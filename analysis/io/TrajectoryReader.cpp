#include "analysis/io/TrajectoryReader.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "analysis/io/H5mdTrajectory.h"
#include "analysis/io/LammpsDump.h"

namespace granagg::analysis {

std::unique_ptr<TrajectoryReader> openTrajectory(const std::string& path, double lammps_dt) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw std::invalid_argument("no such trajectory or run folder: '" + path + "'");
  std::string file = path;
  if (fs::is_directory(path, ec)) {
    file = (fs::path(path) / "traj.h5").string();
    if (!fs::exists(file, ec))
      throw std::invalid_argument("run folder '" + path + "' holds no traj.h5");
  }
  // HDF5 files start with the 8-byte signature \211HDF\r\n\032\n (at offset 0 for our files).
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot read '" + file + "'");
  char sig[8] = {0};
  in.read(sig, 8);
  if (in.gcount() == 8 && std::memcmp(sig, "\211HDF\r\n\032\n", 8) == 0)
    return std::make_unique<H5mdTrajectory>(file);
  if (in.gcount() == 0) throw std::invalid_argument("'" + file + "' is empty");
  return std::make_unique<LammpsDump>(file, lammps_dt);
}

}  // namespace granagg::analysis
