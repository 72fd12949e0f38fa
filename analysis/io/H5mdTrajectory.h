#pragma once
/// \file H5mdTrajectory.h
/// Streams frames from an H5MD 1.1 file (de Buyl et al., Comput. Phys. Commun. 185, 1546 (2014)):
/// /particles/<group>/{position, box} required; image, velocity, charge optional. Time-dependent
/// elements are groups {value [F,...], step, time}; step/time may be arrays or the H5MD
/// fixed-increment scalar (with an `offset` attribute). A time-independent charge (dataset [N])
/// is accepted. Box edges: [3] or [3x3] per frame (or one fixed value); cubic boxes only.
#include <map>
#include <memory>
#include <string>

#include "analysis/io/TrajectoryReader.h"

namespace granagg::analysis {

class H5mdTrajectory final : public TrajectoryReader {
 public:
  /// Opens `path`; `group` selects /particles/<group> (empty: "all" if present, else the
  /// alphabetically first, which is what MDAnalysis reads). Throws TrajectoryError (frame 0)
  /// for an unreadable or truncated file and for missing required datasets.
  explicit H5mdTrajectory(const std::string& path, const std::string& group = "");
  ~H5mdTrajectory() override;
  bool next(Frame& f) override;
  std::size_t frameCountHint() const override;
  const std::map<std::string, std::string>& parameters() const override;
  const std::string& path() const override;
  std::string format() const override { return "h5md"; }
  /// Number of particles.
  std::size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::analysis
