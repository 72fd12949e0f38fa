#pragma once
/// \file GridClusters.h
/// Clusters on a grid, the paper's method (Singh & Mazza 2018, after Paul & Das): particle
/// centres are counted per cell of a cubic grid, cells with a local filling fraction of at least
/// `min_fill` are occupied, and occupied cells sharing a face (6-connectivity) form a cluster,
/// with periodic boundaries (union-find). The size s of a cluster is its number of sites.
///
/// Defaults (docs/model.md section 10, calibrated on hard-sphere gases at phi = 0.076): cells per
/// side n = floor(L / 2) (spacing h = L/n, just above 2 d) and min_fill = 0.25, i.e. a cell is
/// occupied when it holds at least ceil(0.25 h^3 / (pi/6)) centres (4 for h = 2). The homogeneous
/// gas then has about 1-2 % occupied sites and S near 1, far below site percolation (0.3116 in
/// 3-D), while compact clusters give site counts proportional to their mass. A spacing of 1 d would
/// make a single particle an occupied site and the homogeneous gas percolates.
#include <cstdint>
#include <vector>

#include "analysis/clusters/ClusterSizes.h"
#include "analysis/clusters/UnionFind.h"
#include "analysis/io/Frame.h"

namespace granagg::analysis {

/// How particles are assigned to grid cells.
enum class GridAssignment {
  Nearest,      ///< each centre counts 1 in the cell holding it (nearest grid point, NGP)
  CloudInCell,  ///< trilinear weights over the 8 nearest cell centres (CIC smoothing)
};

struct GridClustersParams {
  double spacing = 2.0;    ///< target cell edge, in d; cells per side = max(1, floor(L / spacing))
  double min_fill = 0.25;  ///< occupied when (count * pi/6) / h^3 >= min_fill
  int min_count = 0;       ///< if > 0: occupied when count >= min_count (overrides min_fill)
  GridAssignment assignment = GridAssignment::Nearest;
};

class GridClusters {
 public:
  /// Throws std::invalid_argument for a non-positive spacing, min_fill outside (0, 1] or a
  /// negative min_count.
  explicit GridClusters(const GridClustersParams& params = {});

  /// Labels the clusters of one frame (positions wrapped into [0, L)).
  void compute(const Frame& frame);
  /// Same from raw positions (3N values in [0, L)).
  void compute(const double* position, std::size_t n, double box);

  /// Size distribution of the last computed frame; throws std::logic_error before compute().
  const ClusterSizes& result() const;
  /// Cells per side of the last frame.
  int cellsPerSide() const { return m_n; }
  /// Cell edge h = L / n of the last frame, in d.
  double cellSize() const { return m_h; }
  /// Occupation threshold actually used (count per cell), computed once per box size.
  double minCount() const { return m_min_count; }
  /// Fraction of occupied sites in the last frame.
  double occupiedFraction() const;
  /// Occupancy (0/1) of the last frame, index (ix * n + iy) * n + iz.
  const std::vector<std::uint8_t>& occupancy() const { return m_occupied; }
  /// Cluster label per cell (-1: empty; clusters numbered 0.. in order of their first cell).
  const std::vector<std::int32_t>& labels() const { return m_labels; }
  /// Per-cell counts (or CIC weights) of the last frame.
  const std::vector<double>& counts() const { return m_counts; }
  /// Forgets the last result.
  void reset();
  const GridClustersParams& params() const { return m_params; }

 private:
  GridClustersParams m_params;
  int m_n = 0;
  double m_h = 0.0, m_box = -1.0, m_min_count = 0.0;
  std::vector<double> m_counts;
  std::vector<std::uint8_t> m_occupied;
  std::vector<std::int32_t> m_labels;
  UnionFind m_uf;
  ClusterSizes m_result;
  bool m_computed = false;
};

}  // namespace granagg::analysis
