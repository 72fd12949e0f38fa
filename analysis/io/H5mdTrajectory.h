#pragma once
/// \file H5mdTrajectory.h
/// Streams the frames of an H5MD 1.1 file through common::H5mdReader (common/H5mdReader.h says
/// what is required, optional and tolerated). Errors are TrajectoryErrors naming the file and
/// the frame; a file without image counts gives frames without them (MSD skipped).
#include <map>
#include <memory>
#include <string>

#include "analysis/io/TrajectoryReader.h"

namespace granagg::analysis {

class H5mdTrajectory final : public TrajectoryReader {
 public:
  /// Opens `path`; `group` selects /particles/<group> (empty: "all" if present, else the
  /// first in name order, which is what MDAnalysis reads).
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
