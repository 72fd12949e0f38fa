#pragma once
/// \file H5mdReader.h
/// The one reader of H5MD 1.1 trajectories (de Buyl et al., Comput. Phys. Commun. 185, 1546
/// (2014)): md reads initial states with it, analysis streams runs with it. It reads the files
/// md::H5mdWriter writes and other engines' files that follow the specification (LAMMPS dump
/// h5md, ESPResSo, HALMD, pyh5md...).
///
/// What is required, what is optional, and what is tolerated:
/// - Particle group: the one named, else "all" if present, else the first in name order (what
///   MDAnalysis and h5py list first).
/// - `position`: time-dependent, value [F][N][3], with `step`; `time` may be missing (times are
///   then the steps, as H5MD permits). `step`/`time` may be arrays or the fixed-increment scalar
///   form with an `offset` attribute.
/// - `box`: `edges` as a fixed [3] or [3][3] dataset or a time series of them; cubic (to 1e-6
///   relative, the rounding of single-precision writers). `dimension` and `boundary`, when
///   present, must be 3 and all "periodic"; some converters omit them, so absence is tolerated.
/// - `/h5md`: when present, its `version` must be 1.x; absence is tolerated likewise.
/// - Optional: `velocity` [F][N][3], `charge` [F][N] or fixed [N], `image` [F][N][3] or fixed
///   [N][3]. Shapes are checked on opening. An element sampled on another grid than `position`
///   (matched by step) reads as empty in the frames it has no sample for; an element on the same
///   grid with fewer rows (a truncated write) is an error at the first frame it lacks.
/// - Frames: the shortest of position value, step and time (a run killed while writing a frame
///   leaves a partial last row, which is not counted). Row counts are re-checked on each read, so
///   a file still being written is read safely.
///
/// Frames come back with positions wrapped into [0, L) and the image counts adjusted (files that
/// store unwrapped positions are thus handled); our own files come back bit for bit. Particle ids
/// are 0..N-1 (H5MD has no id element in our files).
///
/// Every error is a common::TrajectoryError (a std::runtime_error) naming the file and the frame
/// (frame 0 when the file cannot be opened) and the dataset concerned. HDF5's own error printing
/// is switched off. No unit conversion is done.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common/TrajectoryFrame.h"

namespace granagg::common {

/// Name of the particle group granagg writes under /particles.
inline constexpr const char* H5MD_PARTICLE_GROUP = "all";
/// Group holding granagg's finely sampled scalar observables (not the H5MD /observables group).
inline constexpr const char* H5MD_OBSERVABLES_GROUP = "/granagg/observables";
/// Dataset under /parameters holding the TOML text of the resolved configuration.
inline constexpr const char* H5MD_CONFIG_DATASET = "config_toml";

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
  /// Opens `path` read-only; `particle_group` as described above ("" = the default rule).
  explicit H5mdReader(const std::string& path, const std::string& particle_group = "");
  /// Reads an H5MD file held in memory (HDF5's file-image API; the bytes are copied). `name`
  /// stands for the file in errors. Used by the fuzz harnesses (tests/fuzz).
  static H5mdReader fromImage(const void* data, std::size_t size, const std::string& name,
                              const std::string& particle_group = "");
  ~H5mdReader();
  H5mdReader(H5mdReader&&) noexcept;
  H5mdReader& operator=(H5mdReader&&) noexcept;
  H5mdReader(const H5mdReader&) = delete;
  H5mdReader& operator=(const H5mdReader&) = delete;

  const std::string& path() const;
  /// Name of the particle group read (under /particles).
  const std::string& particleGroup() const;
  /// Number of particles N.
  std::size_t size() const;
  /// Number of complete frames.
  std::size_t frames() const;
  /// Whether the group has velocity / charge / image data at all.
  bool hasVelocity() const;
  bool hasCharge() const;
  bool hasImage() const;
  /// Integration step, time (reduced units) and cubic box edge L of frame i.
  std::int64_t step(std::size_t i) const;
  double time(std::size_t i) const;
  double box(std::size_t i) const;

  /// Reads frame i into f (its storage is reused): wrapped positions, image counts (empty when
  /// the file has none, unless keepWrapCrossings), velocities and charges (empty when absent at
  /// that frame).
  void readFrame(std::size_t i, TrajectoryFrame& f) const;
  TrajectoryFrame readFrame(std::size_t i) const;

  /// For a file without an `image` element: return the box crossings found while wrapping the
  /// positions as image counts (true; what an initial state read from unwrapped positions needs)
  /// or no image counts at all (false, the default: a trajectory of wrapped positions without
  /// images cannot be unwrapped, and the crossings of one frame cannot tell which it is).
  void keepWrapCrossings(bool keep);

  /// (name, value) of the attributes of /parameters as text (array entries joined by ','; numbers
  /// formatted by common::formatReal); empty if absent. Unreadable attributes are skipped.
  std::vector<std::pair<std::string, std::string>> parameters() const;
  /// Text of /parameters/config_toml ("" if absent).
  std::string configToml() const;
  /// /h5md/creator name and version, e.g. {"granagg", "granagg 0.1.0 (abc123)"} ({"", ""} if
  /// absent).
  std::pair<std::string, std::string> creator() const;

  /// Names of the scalar time series: /granagg/observables first, then H5MD /observables.
  std::vector<std::string> observableNames() const;
  /// Reads one series named by observableNames() (complete samples only); throws
  /// TrajectoryError if absent.
  ObservableSeries readObservable(const std::string& name) const;

 private:
  H5mdReader();  // for fromImage
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::common
