#include "md/neighbor/NeighborList.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <thrust/fill.h>
#include <thrust/execution_policy.h>
#include <thrust/for_each.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>
#include <thrust/sequence.h>
#include <thrust/sort.h>
#include <thrust/transform_reduce.h>

namespace granagg::md {

namespace {

struct CellIndex {
  const double *x, *y, *z;
  int* cell;
  double inv_cell;  // cells per unit length
  int nc;
  HD void operator()(int i) const {
    int cx = static_cast<int>(x[i] * inv_cell), cy = static_cast<int>(y[i] * inv_cell),
        cz = static_cast<int>(z[i] * inv_cell);
    cx = cx < 0 ? 0 : (cx >= nc ? nc - 1 : cx);
    cy = cy < 0 ? 0 : (cy >= nc ? nc - 1 : cy);
    cz = cz < 0 ? 0 : (cz >= nc ? nc - 1 : cz);
    cell[i] = (cx * nc + cy) * nc + cz;
  }
};

/// Inserts slot j into the row kept sorted by particle id (insertion sort; rows are short) if there
/// is room; counts always.
HD inline void insertSorted(int* row, int& n, int cap, int j, const int* id) {
  if (n < cap) {
    int k = n;
    const int key = id[j];
    while (k > 0 && id[row[k - 1]] > key) {
      row[k] = row[k - 1];
      --k;
    }
    row[k] = j;
  }
  ++n;
}

/// Marks where each cell's run starts and ends in the cell-sorted slot list: O(N), one pass
/// (empty cells keep start = end = 0 from the fill).
struct CellBounds {
  const int* cell;  // sorted cell index of each position in the order
  int *start, *end;
  int n;
  HD void operator()(int s) const {
    const int c = cell[s];
    if (s == 0 || cell[s - 1] != c) start[c] = s;
    if (s == n - 1 || cell[s + 1] != c) end[c] = s + 1;
  }
};

struct BuildCells {
  const double *x, *y, *z;
  const int *order, *cell_start, *cell_end, *id;
  int *list, *count;
  common::Box box;
  double inv_cell, r2;
  int nc, cap;
  HD void operator()(int i) const {
    const double xi = x[i], yi = y[i], zi = z[i];
    int cx = static_cast<int>(xi * inv_cell), cy = static_cast<int>(yi * inv_cell), cz = static_cast<int>(zi * inv_cell);
    cx = cx < 0 ? 0 : (cx >= nc ? nc - 1 : cx);
    cy = cy < 0 ? 0 : (cy >= nc ? nc - 1 : cy);
    cz = cz < 0 ? 0 : (cz >= nc ? nc - 1 : cz);
    // periodic neighbour cells along each axis (nc >= 3, so the three are distinct); no modulo
    const int xs[3] = {cx == 0 ? nc - 1 : cx - 1, cx, cx == nc - 1 ? 0 : cx + 1};
    const int ys[3] = {cy == 0 ? nc - 1 : cy - 1, cy, cy == nc - 1 ? 0 : cy + 1};
    const int zs[3] = {cz == 0 ? nc - 1 : cz - 1, cz, cz == nc - 1 ? 0 : cz + 1};
    int* row = list + static_cast<long>(i) * cap;
    int n = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const int cxy = (xs[a] * nc + ys[b]) * nc;
        for (int e = 0; e < 3; ++e) {
          const int c = cxy + zs[e];
          for (int s = cell_start[c]; s < cell_end[c]; ++s) {
            const int j = order[s];
            if (j == i) continue;
            const double rx = box.minimumImageWrapped(xi - x[j]), ry = box.minimumImageWrapped(yi - y[j]),
                         rz = box.minimumImageWrapped(zi - z[j]);
            if (rx * rx + ry * ry + rz * rz < r2) insertSorted(row, n, cap, j, id);
          }
        }
      }
    count[i] = n;
  }
};

struct BuildAllPairs {
  const double *x, *y, *z;
  const int* id;
  int *list, *count;
  common::Box box;
  double r2;
  int N, cap;
  HD void operator()(int i) const {
    int* row = list + static_cast<long>(i) * cap;
    int n = 0;
    for (int j = 0; j < N; ++j) {
      if (j == i) continue;
      const double rx = box.minimumImage(x[i] - x[j]), ry = box.minimumImage(y[i] - y[j]),
                   rz = box.minimumImage(z[i] - z[j]);
      if (rx * rx + ry * ry + rz * rz < r2) insertSorted(row, n, cap, j, id);
    }
    count[i] = n;
  }
};

struct Displacement2 {
  const double *x, *y, *z, *x0, *y0, *z0;
  common::Box box;
  HD double operator()(int i) const {
    const double dx = box.minimumImageWrapped(x[i] - x0[i]), dy = box.minimumImageWrapped(y[i] - y0[i]),
                 dz = box.minimumImageWrapped(z[i] - z0[i]);
    return dx * dx + dy * dy + dz * dz;
  }
};

}  // namespace

NeighborList::NeighborList(double cutoff, double skin) : m_cutoff(cutoff), m_skin(skin) {
  if (!(cutoff > 0.0) || !(skin > 0.0)) throw std::invalid_argument("neighbour list needs cutoff > 0 and skin > 0.");
}

bool NeighborList::needsRebuild(const ParticleData& p, const common::Box& box) {
  const int N = static_cast<int>(p.size());
  if (m_builds == 0 || static_cast<int>(m_x0.size()) != N) return true;
  const double max2 = thrust::transform_reduce(
      thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N),
      Displacement2{raw(p.x), raw(p.y), raw(p.z), raw(m_x0), raw(m_y0), raw(m_z0), box}, 0.0, thrust::maximum<double>());
  return max2 > 0.25 * m_skin * m_skin;
}

bool NeighborList::update(const ParticleData& p, const common::Box& box) {
  if (!needsRebuild(p, box)) return false;
  build(p, box);
  return true;
}

void NeighborList::build(const ParticleData& p, const common::Box& box) {
  const int N = static_cast<int>(p.size());
  const double range = m_cutoff + m_skin;
  if (2.0 * range > box.L)
    throw std::invalid_argument("box edge L = " + std::to_string(box.L) + " is smaller than twice the neighbour range " +
                                std::to_string(range) + " (contact distance 1 + skin): use more particles or a smaller skin.");
  const int nc = static_cast<int>(std::floor(box.L / range));
  const auto first = thrust::counting_iterator<int>(0), last = thrust::counting_iterator<int>(N);
  m_count.resize(N);
  for (;;) {
    m_list.resize(static_cast<std::size_t>(N) * m_capacity);
    if (nc >= 3) {
      const int ncell = nc * nc * nc;
      const double inv_cell = nc / box.L;
      m_cell.resize(N);
      m_order.resize(N);
      thrust::for_each(first, last, CellIndex{raw(p.x), raw(p.y), raw(p.z), raw(m_cell), inv_cell, nc});
      thrust::sequence(m_order.begin(), m_order.end());
      thrust::stable_sort_by_key(m_cell.begin(), m_cell.end(), m_order.begin());
      m_cell_start.assign(ncell, 0);
      m_cell_end.assign(ncell, 0);
      thrust::for_each(first, last, CellBounds{raw(m_cell), raw(m_cell_start), raw(m_cell_end), N});
      thrust::for_each(first, last,
                       BuildCells{raw(p.x), raw(p.y), raw(p.z), raw(m_order), raw(m_cell_start), raw(m_cell_end),
                                  raw(p.id), raw(m_list), raw(m_count), box, inv_cell, range * range, nc, m_capacity});
    } else {
      m_order.clear();
      thrust::for_each(first, last,
                       BuildAllPairs{raw(p.x), raw(p.y), raw(p.z), raw(p.id), raw(m_list), raw(m_count), box, range * range, N,
                                     m_capacity});
    }
    const int most = N ? thrust::reduce(m_count.begin(), m_count.end(), 0, thrust::maximum<int>()) : 0;
    if (most <= m_capacity) break;
    m_capacity = most + most / 4 + 4;  // overflow detected: grow and rebuild, never truncate
  }
  m_x0 = p.x;
  m_y0 = p.y;
  m_z0 = p.z;
  ++m_builds;
}

}  // namespace granagg::md
