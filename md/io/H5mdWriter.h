#pragma once
/// \file H5mdWriter.h
/// Writes MD trajectories as H5MD 1.1 files (docs/ARCHITECTURE.md), readable by h5py, by
/// analysis/ and by MDAnalysis 2.x's H5MD reader. Reduced units throughout (d = m = T0 = 1;
/// lengths in particle diameters, time in sqrt(m d^2 / T0)); no `unit` attributes are written,
/// so MDAnalysis must be told `convert_units=False`:
///
///     u = MDAnalysis.Universe.empty(N, trajectory=False)   # or any topology with N atoms
///     u.load_new("traj.h5", format="H5MD", convert_units=False)
///
/// (checked against h5py frame by frame by scripts/check_mdanalysis.py, run by the CLI tests).
///
/// MDAnalysis also ignores charges (read them from particles/all/charge/value with h5py).
///
/// Layout written (F = frames so far, N = particles; every time series is an H5MD
/// time-dependent group {value, step, time} whose first axis grows by one row per frame):
///
///     /h5md                          +-- version = [1, 1] (int32[2])
///         author                     +-- name ($USER, or "unknown")
///         creator                    +-- name = "granagg", version = common::versionString()
///     /particles/all
///         position/{value double[F][N][3], step int64[F], time double[F]}   wrapped into [0, L)
///         velocity/{value double[F][N][3], step, time}                     (unless disabled)
///         charge/{value double[F][N], step, time}
///         image/{value int32[F][N][3], step, time}      unwrapped = position + image * L
///         box                        +-- dimension = 3, boundary = ["periodic" x 3]
///             edges/{value double[F][3][3] (diag(L, L, L)), step, time}
///     /parameters                    +-- one string attribute per resolved parameter
///         config_toml                    string: TOML text of the resolved configuration
///     /granagg/observables/<name>/{value double[S], step int64[S], time double[S]}
///     /granagg/restarts/<k>      +-- step, time, t_end, command, version, utc: the k-th
///                                    continuation of the run (k = 0, 1, ...; recordRestart)
///
/// All `step` and `time` datasets under /particles/all are HDF5 hard links to
/// position/step and position/time (H5MD allows shared step/time), so every element is sampled
/// on the frame grid by construction; box edges as a 3x3 matrix per frame is the form MDAnalysis
/// reads safely. Scalar observables (energy, temperature...) are sampled far more often than
/// frames, and MDAnalysis indexes every /observables/<name>/value with the *frame* index, so they
/// are deliberately kept out of the H5MD /observables group: they live in the application group
/// /granagg/observables (H5MD permits non-specified groups), one time-dependent group per name,
/// whose step/time datasets are hard links to those of the first name.
///
/// A sidecar `<stem>.xdmf` (see xdmfPathFor) lets ParaView's "XDMF Reader" show the particles as a
/// Polyvertex point cloud with velocity, charge and image attributes and one time step per frame.
///
/// Robustness: the HDF5 file is flushed after every frame and each flush is committed through an
/// undo journal (common/H5Journal.h, `traj.h5.journal` while the file is open), so a run killed
/// at any moment leaves a file that reopen() and common::H5mdReader return to its last complete
/// frame (step/time are extended last: a frame counts only once they are written;
/// common::H5mdReader takes the shortest of value/step/time). Not thread-safe.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common/H5mdReader.h"
#include "md/io/Frame.h"

namespace granagg::md {

// The layout names readers look for (common/H5mdReader.h): particle group, observables group,
// configuration dataset.
using common::H5MD_CONFIG_DATASET;
using common::H5MD_OBSERVABLES_GROUP;
using common::H5MD_PARTICLE_GROUP;

/// Streams frames and scalar observables of one run into an H5MD 1.1 file.
class H5mdWriter {
 public:
  /// Creates `path` for a system of N particles (N >= 1).
  /// \param parameters  resolved parameters (key, value) written as string attributes of
  ///                    /parameters, e.g. {"seed","42"}, {"version",...}, {"command",...};
  ///                    keys must be non-empty and unique.
  /// \param config_toml TOML text of the resolved configuration (/parameters/config_toml).
  /// \param overwrite   replace an existing file; otherwise std::invalid_argument names it.
  /// \param write_velocities  write particles/all/velocity (default true).
  /// \param write_forces  write particles/all/force from Frame::force (default false).
  /// The XDMF sidecar is (re)written next to it regardless of `overwrite` (it holds no data).
  /// Throws std::invalid_argument for bad arguments, std::runtime_error if HDF5 fails.
  H5mdWriter(const std::string& path, std::size_t N,
             const std::vector<std::pair<std::string, std::string>>& parameters,
             const std::string& config_toml, bool overwrite, bool write_velocities = true,
             bool write_forces = false);

  /// Reopens a trajectory written by H5mdWriter to continue a run restarted from a checkpoint
  /// taken at `restart_step`: frames and observable samples with step > restart_step (written
  /// after that checkpoint by the interrupted run) are discarded so that the restarted run
  /// rewrites them, and the file ends exactly as an uninterrupted run's would. N and
  /// write_velocities and write_forces must match the file (std::invalid_argument otherwise).
  /// /parameters is kept.
  static H5mdWriter reopen(const std::string& path, std::size_t N, std::int64_t restart_step,
                           bool write_velocities = true, bool write_forces = false);

  /// Closes the file (as close(), but errors are swallowed: call close() to see them).
  ~H5mdWriter();
  H5mdWriter(H5mdWriter&&) noexcept;
  H5mdWriter& operator=(H5mdWriter&&) noexcept;
  H5mdWriter(const H5mdWriter&) = delete;
  H5mdWriter& operator=(const H5mdWriter&) = delete;

  /// Appends one frame and flushes the file. Requires frame.size() == N, every array sized N
  /// (velocities only when written; an empty `charge` is written as zeros, a neutral gas),
  /// box L > 0 (reduced length units), finite positions and a step larger than the previous
  /// frame's (std::invalid_argument otherwise). Positions outside [0, L) (engine round-off, e.g.
  /// x == L) are wrapped in the written copy and their image counts adjusted so that the
  /// unwrapped position is unchanged; positions already in [0, L) are written bit for bit.
  void writeFrame(const Frame& frame);

  /// Appends one sample of scalar observables at `step` / `time` (reduced time units) to
  /// /granagg/observables/<name>. The first call fixes the set of names (non-empty, unique,
  /// without '/'); later calls must give the same names (any order). A reopened file (reopen())
  /// accepts others, so that a run started by an older granagg can be continued by a newer one:
  /// a name the file lacks is added, NaN for the samples before it, and a name the file holds
  /// that a call omits gets NaN for that sample. Samples are buffered and written at the next
  /// frame, flush() or close() (or every 4096 samples), so calling it every few steps is cheap.
  /// Steps must increase strictly.
  void writeObservables(std::int64_t step, double time,
                        const std::vector<std::pair<std::string, double>>& values);

  /// Records that the run was continued from `step` (time `time`) to `t_end` by `command` with
  /// granagg `version`, at the current UTC time, as the next group /granagg/restarts/<k>
  /// (/parameters keeps describing the run as it was started).
  void recordRestart(std::int64_t step, double time, double t_end, const std::string& command,
                     const std::string& version);

  /// Writes buffered observables, flushes HDF5's caches to disk and refreshes the XDMF sidecar.
  /// Call it before writing a checkpoint so trajectory and checkpoint agree.
  void flush();

  /// flush() then closes the file; further writes throw std::logic_error. Idempotent.
  void close();

  /// What reopen() repaired, in one line for the log ("" if nothing): the write that a killed
  /// run left unfinished, rolled back to the last complete frame (common/H5Journal.h).
  const std::string& repairNote() const;
  /// Frames written so far (including those kept by reopen()).
  std::size_t frames() const;
  /// Observable samples written or buffered so far.
  std::size_t observableSamples() const;
  /// Number of particles N.
  std::size_t size() const;
  /// Path of the HDF5 file.
  const std::string& path() const;
  /// Path of the XDMF sidecar.
  const std::string& xdmfPath() const;

  /// Sidecar path for a trajectory: "traj.h5" -> "traj.xdmf" (also for .hdf5, .h5md; any other
  /// name gets ".xdmf" appended).
  static std::string xdmfPathFor(const std::string& h5_path);

 private:
  struct Impl;
  explicit H5mdWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::md
