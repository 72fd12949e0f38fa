#pragma once
/// \file Frame.h
/// A host copy of the particle state, the unit that the H5MD writer, the checkpoint and the
/// initial-state readers exchange with the engine. Positions are wrapped into [0, L)^3 and the
/// image counts say how many box lengths each particle has crossed (unwrapped = x + image * L).
#include <cstdint>
#include <vector>

namespace granagg::md {

/// Per-particle forces by component, in id order (reduced units m d / t^2): the one type in which
/// forces leave an engine (RunEngine::forces), travel in a checkpoint and reach the trajectory.
struct Forces {
  std::vector<double> x, y, z;
  std::size_t size() const { return x.size(); }
  bool empty() const { return x.empty(); }
  bool operator==(const Forces& o) const { return x == o.x && y == o.y && z == o.z; }
};

struct Frame {
  std::int64_t step = 0;
  double time = 0.0;
  double box = 0.0;                      ///< cubic box edge L
  std::vector<double> x, y, z;           ///< wrapped positions
  std::vector<double> vx, vy, vz;        ///< velocities
  std::vector<double> charge;            ///< charges (zero for a neutral gas)
  std::vector<std::int32_t> ix, iy, iz;  ///< image counts
  /// per-particle forces (optional: filled for output with output.write_forces, else empty)
  Forces force;
  std::size_t size() const { return x.size(); }
};

}  // namespace granagg::md
