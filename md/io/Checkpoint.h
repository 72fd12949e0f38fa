#pragma once
/// \file Checkpoint.h
/// Restart files (docs/ARCHITECTURE.md): everything a run needs to continue bit for bit as the
/// uninterrupted run would (same build and backend, any thread count), stored in HDF5 at full
/// precision.
///
/// Layout (HDF5; readable with h5py for inspection):
///
///     /                 +-- format = "granagg-checkpoint", format_version = 1,
///                           creator = common::versionString()
///     /state            +-- step (int64), time (double), box (double), N (int64)
///         x y z vx vy vz charge fx fy fz   double[N]
///         ix iy iz                         int32[N]
///     /integrator       +-- dt (double)
///     /run              +-- seed (uint64), frames_written (uint64)
///         config_toml   string                            (RunFields)
///     /scalars/int      +-- one int64 attribute per entry of EngineState::ints
///     /scalars/real     +-- one double attribute per entry of EngineState::reals
///     /arrays           one double[N] dataset per entry of EngineState::arrays (optional:
///                       files without the group read back with no arrays)
///
/// Arrays are chunked with HDF5's Fletcher-32 checksum filter, so silent corruption is detected
/// on reading. Writing is atomic: the file is written as `<path>.tmp`, closed, fsync'ed and
/// renamed over `path` (rename(2) is atomic on POSIX file systems), then the directory is
/// fsync'ed; a crash or a failed write therefore never leaves a half-written checkpoint at
/// `path`, and the previous good checkpoint survives any failure.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "md/io/Frame.h"

namespace granagg::md {

/// The run's own fields (md::Simulation's, the same whatever the engine): the configuration, the
/// seed and the frames in the trajectory (the next scheduled frame follows from the step).
struct RunFields {
  std::string config_toml;           ///< TOML text of the resolved configuration
  std::uint64_t seed = 0;            ///< RNG seed (Philox key; no RNG state is stored)
  std::uint64_t frames_written = 0;  ///< frames already in the trajectory file
};

/// The state an engine defines for itself, beyond particles and forces: named integers (counters,
/// the step of the last Coulomb evaluation), reals and per-particle arrays (N each, in id order).
/// md::Engine stores its multiple-time-step state here (Engine::engineState).
struct EngineState {
  std::map<std::string, std::int64_t> ints;
  std::map<std::string, double> reals;
  std::map<std::string, std::vector<double>> arrays;
};

/// Everything a checkpoint holds: one typed state for reading, writing and restoring.
struct Checkpoint {
  Frame state;  ///< full-precision particle state (positions wrapped, with images)
  /// Forces at the saved state (computed at the end of the last step), one per particle, in
  /// reduced units m d / t^2: velocity Verlet's first half-kick of the next step uses them.
  Forces forces;
  double dt = 0.0;     ///< integrator time step (reduced time units), > 0
  RunFields run;       ///< /run
  EngineState engine;  ///< /scalars/int, /scalars/real, /arrays
};

/// Writes a checkpoint atomically to `path` (via `path + ".tmp"`, see the file comment).
/// Requires N = state.size() >= 1, every array of `state` and the forces sized N, box > 0,
/// dt > 0 and non-empty scalar names (std::invalid_argument otherwise). Throws
/// std::runtime_error naming the file if writing or renaming fails; the previous file at `path`
/// is then untouched and the temporary file removed.
void writeCheckpoint(const std::string& path, const Checkpoint& checkpoint);

/// Reads a checkpoint written by writeCheckpoint. Values come back bit for bit. Throws
/// std::runtime_error naming the file (and dataset) if it is missing, not HDF5, truncated,
/// fails its checksums, lacks an entry, has inconsistent sizes, or is not a granagg checkpoint.
Checkpoint readCheckpoint(const std::string& path);

}  // namespace granagg::md
