#pragma once
/// \file H5mdReader.h
/// Reads H5MD 1.1 trajectories into Frames: files written by H5mdWriter and other engines' files
/// that follow the specification (LAMMPS dump h5md, ESPResSo, HALMD, pyh5md...).
///
/// Required in the particle group: `position` (time-dependent, value [F][N][3]) and `box`
/// (dimension = 3, boundary all "periodic", `edges` as a fixed [3] or [3][3] dataset or as a
/// time series of [3] vectors or [3][3] matrices; cubic, since Frame holds one edge L).
/// Optional: `velocity` ([F][N][3]), `charge` ([F][N] or fixed [N]), `image` ([F][N][3] or fixed
/// [N][3]). `step`/`time` may be arrays or the fixed-increment scalar form with an `offset`
/// attribute. Elements sampled on a different grid than `position` are matched by step.
/// Positions are returned wrapped into [0, L) with image counts adjusted (files that store
/// unwrapped positions are thus handled); our own files come back bit for bit.
///
/// Every error is a std::runtime_error naming the file and the frame or dataset concerned
/// (missing group or dataset, shape mismatch, truncated or non-HDF5 file). HDF5's own error
/// printing is switched off. Reduced units as written by granagg (no unit conversion is done).
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "md/io/Frame.h"

namespace granagg::md {

/// A scalar time series from the file (one of /granagg/observables, or H5MD /observables).
struct ObservableSeries {
  std::string name;
  std::vector<std::int64_t> step;  ///< integration steps
  std::vector<double> time;        ///< reduced time units
  std::vector<double> value;
};

/// Random access to the frames of one particle group of an H5MD file (kept open until destroyed).
class H5mdReader {
 public:
  /// Opens `path` read-only. `particle_group` names the group under /particles; "" picks the
  /// first in name order (what MDAnalysis and h5py list first).
  explicit H5mdReader(const std::string& path, const std::string& particle_group = "");
  ~H5mdReader();
  H5mdReader(H5mdReader&&) noexcept;
  H5mdReader& operator=(H5mdReader&&) noexcept;
  H5mdReader(const H5mdReader&) = delete;
  H5mdReader& operator=(const H5mdReader&) = delete;

  /// Path of the file.
  const std::string& path() const;
  /// Name of the particle group read (under /particles).
  const std::string& particleGroup() const;
  /// Number of particles N.
  std::size_t size() const;
  /// Number of complete frames: the shortest of position value, step and time (a run killed
  /// while writing a frame leaves a partial last row, which is not counted).
  std::size_t frames() const;
  /// Whether velocity / charge / image data are present (absent ones read as described at
  /// readFrame).
  bool hasVelocity() const;
  bool hasCharge() const;
  bool hasImage() const;
  /// Integration step of frame i.
  std::int64_t step(std::size_t i) const;
  /// Time of frame i (reduced time units).
  double time(std::size_t i) const;
  /// Cubic box edge L of frame i (reduced length units).
  double box(std::size_t i) const;

  /// Reads frame i: step, time, box, wrapped positions, velocities (empty vectors if the file has
  /// none), charges (zeros if none) and image counts (zeros if none, before wrapping).
  Frame readFrame(std::size_t i) const;

  /// (name, value) of the attributes of /parameters, numbers formatted as text; empty if absent.
  std::vector<std::pair<std::string, std::string>> parameters() const;
  /// Text of /parameters/config_toml ("" if absent).
  std::string configToml() const;
  /// /h5md/creator name and version, e.g. {"granagg", "granagg 0.1.0 (abc123)"} ({"", ""} if
  /// absent).
  std::pair<std::string, std::string> creator() const;

  /// Names of the scalar time series: /granagg/observables first, then H5MD /observables.
  std::vector<std::string> observableNames() const;
  /// Reads one series named by observableNames(); throws std::runtime_error if absent.
  ObservableSeries readObservable(const std::string& name) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::md
