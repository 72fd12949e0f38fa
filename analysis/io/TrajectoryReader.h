#pragma once
/// \file TrajectoryReader.h
/// Streams frames from a trajectory file, one at a time (memory bounded by one frame).
/// Formats: H5MD 1.1 (H5mdTrajectory.h) and LAMMPS text dumps (LammpsDump.h).
#include <map>
#include <memory>
#include <string>

#include "analysis/io/Frame.h"

namespace granagg::analysis {

class TrajectoryReader {
 public:
  virtual ~TrajectoryReader() = default;
  /// Reads the next frame into `f` (reusing its storage); false at the regular end of the file.
  /// Throws TrajectoryError (file and frame named) for a truncated or malformed frame.
  virtual bool next(Frame& f) = 0;
  /// Number of frames if known in advance (H5MD), else 0 (LAMMPS dumps are not pre-scanned).
  virtual std::size_t frameCountHint() const = 0;
  /// Run parameters stored in the file (H5MD /parameters attributes, e.g. "charging.kappa"); may be
  /// empty.
  virtual const std::map<std::string, std::string>& parameters() const = 0;
  /// The file being read.
  virtual const std::string& path() const = 0;
  /// "h5md" or "lammps-dump".
  virtual std::string format() const = 0;
};

/// Opens `path`: a directory is taken as a run folder holding traj.h5; an HDF5 file (by its
/// signature) as H5MD; anything else as a LAMMPS dump. `lammps_dt` converts LAMMPS timesteps to
/// times when the dump has no "ITEM: TIME" (0: time = timestep). Throws std::invalid_argument
/// when the path does not exist or holds no trajectory.
std::unique_ptr<TrajectoryReader> openTrajectory(const std::string& path, double lammps_dt = 0.0);

}  // namespace granagg::analysis
