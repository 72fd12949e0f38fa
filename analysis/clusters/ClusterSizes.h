#pragma once
/// \file ClusterSizes.h
/// Cluster-size distribution N_s(s) and the mean cluster size
/// S = sum_s s^2 N_s / sum_s s N_s (docs/model.md section 10; the paper's S(t)), with the two
/// measures that separate the population of clusters from the one that dominates S once it is
/// large: S without the largest cluster, the mean cluster size of percolation theory (Stauffer &
/// Aharony, "Introduction to Percolation Theory", 2nd ed. (1994), section 2.3: the infinite
/// cluster is left out of the sums), and the largest cluster's share of the mass.
#include <cstdint>
#include <map>
#include <vector>

namespace granagg::analysis {

struct ClusterSizes {
  std::map<std::uint64_t, std::uint64_t> n_s;  ///< size s -> number of clusters N_s of that size
  std::uint64_t clusters = 0;                  ///< sum_s N_s
  std::uint64_t mass = 0;                      ///< sum_s s N_s (sites or particles in clusters)
  std::uint64_t largest = 0;                   ///< largest s (0 when there is no cluster)
  double S = 0.0;                              ///< sum s^2 N_s / sum s N_s (NaN when no cluster)
  /// (sum s^2 N_s - s_max^2) / (sum s N_s - s_max): S of the clusters but one largest (NaN with
  /// fewer than two clusters)
  double S_without_largest = 0.0;
  double largest_share = 0.0;  ///< s_max / sum s N_s (NaN when no cluster)

  /// Builds the distribution from a list of cluster sizes (one entry per cluster, s >= 1).
  static ClusterSizes fromSizes(const std::vector<std::uint64_t>& sizes);
  /// All cluster sizes, one entry per cluster, in increasing order (input of the power-law MLE).
  std::vector<std::uint64_t> samples() const;
};

}  // namespace granagg::analysis
