#pragma once
/// Everything granagg reads from an H5MD file, for the two H5MD harnesses: the frames (at most 8),
/// /parameters, the creator, the config text and every observable series.
#include "common/H5mdReader.h"
#include "common/TrajectoryFrame.h"

namespace granagg::fuzz {

inline void readEverything(const common::H5mdReader& r) {
  common::TrajectoryFrame f;
  for (std::size_t k = 0; k < r.frames() && k < 8; ++k) {
    (void)r.step(k);
    (void)r.time(k);
    (void)r.box(k);
    r.readFrame(k, f);
  }
  (void)r.parameters();
  (void)r.configToml();
  (void)r.creator();
  for (const auto& name : r.observableNames()) (void)r.readObservable(name);
}

}  // namespace granagg::fuzz
