#include "analysis/clusters/GridClusters.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/Csv.h"

namespace granagg::analysis {

namespace {
constexpr double SPHERE_VOLUME = 0.52359877559829887;  // pi/6: volume of a particle of diameter 1
}

GridClusters::GridClusters(const GridClustersParams& p) : m_params(p) {
  if (!(p.spacing > 0.0) || !std::isfinite(p.spacing))
    throw std::invalid_argument("GridClusters requires a positive grid spacing, got " +
                                common::formatReal(p.spacing) + ".");
  if (p.min_count < 0)
    throw std::invalid_argument("GridClusters requires min_count >= 0, got " +
                                std::to_string(p.min_count) + ".");
  if (p.min_count == 0 && !(p.min_fill > 0.0 && p.min_fill <= 1.0))
    throw std::invalid_argument("GridClusters requires min_fill in (0, 1], got " +
                                common::formatReal(p.min_fill) + ".");
}

void GridClusters::compute(const Frame& f) { compute(f.position.data(), f.size(), f.box); }

void GridClusters::compute(const double* pos, std::size_t np, double L) {
  if (!(L > 0.0))
    throw std::invalid_argument("GridClusters: box edge must be positive, got " +
                                common::formatReal(L) + ".");
  if (L != m_box) {
    m_box = L;
    m_n = std::max(1, static_cast<int>(std::floor(L / m_params.spacing)));
    m_h = L / m_n;
    // The integer threshold is fixed once per box size: count * (pi/6) / h^3 >= min_fill.
    // The 1e-9 guards against a product like 3.9999999999 meant to be 4.
    m_min_count =
        m_params.min_count > 0
            ? m_params.min_count
            : std::max(1.0, std::ceil(m_params.min_fill * m_h * m_h * m_h / SPHERE_VOLUME - 1e-9));
  }
  const int n = m_n;
  const std::size_t cells = static_cast<std::size_t>(n) * n * n;
  m_counts.assign(cells, 0.0);
  auto index = [n](int x, int y, int z) { return (static_cast<std::size_t>(x) * n + y) * n + z; };
  auto cellOf = [&](double x) {
    int c = static_cast<int>(x / m_h);
    return c >= n ? n - 1 : (c < 0 ? 0 : c);  // x in [0, L): rounding only
  };
  if (m_params.assignment == GridAssignment::Nearest) {
    for (std::size_t i = 0; i < np; ++i)
      m_counts[index(cellOf(pos[3 * i]), cellOf(pos[3 * i + 1]), cellOf(pos[3 * i + 2]))] += 1.0;
  } else {
    // Cloud in cell: weight (1 - |dx|/h) per axis to the two nearest cell centres (periodic).
    for (std::size_t i = 0; i < np; ++i) {
      int c0[3];
      double w1[3];
      for (int d = 0; d < 3; ++d) {
        const double u = pos[3 * i + d] / m_h - 0.5;  // in units of cells, relative to centres
        const double fl = std::floor(u);
        c0[d] = static_cast<int>(fl);
        w1[d] = u - fl;
      }
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
          for (int c = 0; c < 2; ++c) {
            const double w =
                (a ? w1[0] : 1 - w1[0]) * (b ? w1[1] : 1 - w1[1]) * (c ? w1[2] : 1 - w1[2]);
            const int x = ((c0[0] + a) % n + n) % n, y = ((c0[1] + b) % n + n) % n,
                      z = ((c0[2] + c) % n + n) % n;
            m_counts[index(x, y, z)] += w;
          }
    }
  }
  m_occupied.assign(cells, 0);
  // CIC weights are sums of products of doubles: compare with a relative tolerance.
  const double thr = m_min_count * (1.0 - 1e-12);
  for (std::size_t c = 0; c < cells; ++c) m_occupied[c] = m_counts[c] >= thr ? 1 : 0;

  // 6-connectivity with periodic wrap: unite each occupied site with its +x, +y, +z neighbours.
  m_uf.reset(cells);
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) {
        const std::size_t c = index(x, y, z);
        if (!m_occupied[c]) continue;
        const std::size_t nb[3] = {index((x + 1) % n, y, z), index(x, (y + 1) % n, z),
                                   index(x, y, (z + 1) % n)};
        for (std::size_t o : nb)
          if (m_occupied[o])
            m_uf.unite(static_cast<std::uint32_t>(c), static_cast<std::uint32_t>(o));
      }
  const std::vector<std::uint64_t> sizes =
      m_uf.label(m_labels, [this](std::size_t c) { return m_occupied[c] != 0; });
  m_result = ClusterSizes::fromSizes(sizes);
  m_computed = true;
}

const ClusterSizes& GridClusters::result() const {
  if (!m_computed) throw std::logic_error("GridClusters::result() called before compute().");
  return m_result;
}

double GridClusters::occupiedFraction() const {
  if (!m_computed)
    throw std::logic_error("GridClusters::occupiedFraction() called before compute().");
  return m_occupied.empty()
             ? 0.0
             : static_cast<double>(m_result.mass) / static_cast<double>(m_occupied.size());
}

void GridClusters::reset() {
  m_computed = false;
  m_result = ClusterSizes{};
}

}  // namespace granagg::analysis
