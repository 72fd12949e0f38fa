#pragma once
/// \file ParticleClusters.h
/// Particle-contact clusters (docs/model.md section 10, second definition): i and j are bonded when
/// their minimum-image distance |r_ij| <= 1 + tolerance (diameter d = 1); clusters are the
/// connected components, found with a periodic cell list and union-find. The size s of a
/// cluster is its number of particles (monomers count as clusters of size 1).
///
/// Default tolerance 0.05 d: particles resting in an aggregate of the viscoelastic gas touch with
/// overlaps of order 1e-3 but separate briefly as they rattle; 5 % of a diameter keeps such
/// pairs bonded while two free particles pass within it only rarely at phi = 0.076.
#include <cstdint>
#include <vector>

#include "analysis/clusters/ClusterSizes.h"
#include "analysis/clusters/UnionFind.h"
#include "analysis/io/Frame.h"

namespace granagg::analysis {

struct ParticleClustersParams {
  double tolerance = 0.05;  ///< bond when |r_ij| <= 1 + tolerance, in d
};

class ParticleClusters {
 public:
  /// Throws std::invalid_argument when tolerance is negative or not finite.
  explicit ParticleClusters(const ParticleClustersParams& params = {});

  /// Finds the clusters (and contact counts) of one frame.
  void compute(const Frame& frame);
  /// Same from raw wrapped positions (3N values in [0, L)).
  void compute(const double* position, std::size_t n, double box);

  /// Size distribution of the last frame; throws std::logic_error before compute().
  const ClusterSizes& result() const;
  /// Number of partners within 1 + tolerance of each particle in the last frame.
  const std::vector<std::uint32_t>& contacts() const;
  /// Cluster label of each particle (clusters numbered 0.. in order of their first particle).
  const std::vector<std::int32_t>& labels() const;
  /// Number of bonded pairs in the last frame.
  std::size_t bonds() const { return m_bonds; }
  void reset() { m_computed = false; }
  const ParticleClustersParams& params() const { return m_params; }

 private:
  ParticleClustersParams m_params;
  UnionFind m_uf;
  ClusterSizes m_result;
  std::vector<std::uint32_t> m_contacts;
  std::vector<std::int32_t> m_labels;
  std::size_t m_bonds = 0;
  bool m_computed = false;
};

}  // namespace granagg::analysis
