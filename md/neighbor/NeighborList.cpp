#include "md/neighbor/NeighborList.h"

#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>

#include <thrust/execution_policy.h>
#include <thrust/for_each.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>
#include <thrust/scan.h>
#include <thrust/sequence.h>
#include <thrust/sort.h>
#include <thrust/transform_reduce.h>

#include "md/engine/Launch.h"

namespace granagg::md {

namespace {

struct CellIndex {
  const Scalar4* pos;
  int* cell;
  double inv_cell;  // cells per unit length
  int nc;
  HD void operator()(int i) const {
    const Scalar4 r = pos[i];
    int cx = static_cast<int>(r.x * inv_cell), cy = static_cast<int>(r.y * inv_cell),
        cz = static_cast<int>(r.z * inv_cell);
    cx = cx < 0 ? 0 : (cx >= nc ? nc - 1 : cx);
    cy = cy < 0 ? 0 : (cy >= nc ? nc - 1 : cy);
    cz = cz < 0 ? 0 : (cz >= nc ? nc - 1 : cz);
    cell[i] = (cx * nc + cy) * nc + cz;
  }
};

/// Appends slot j to the row if there is room; counts always (an overflow is detected by the
/// caller from the count).
HD inline void append(int* row, int& n, int cap, int j) {
  if (n < cap) row[n] = j;
  ++n;
}
/// Branch-free append of candidate j if `hit`: j is written whatever `hit` -- to row[n], past the
/// row's entries, or once the row is full to `spill` (never to a row slot: a full row may be
/// exactly full, and its last entry must survive) -- and n advances by hit. Most candidates of a
/// cell search miss, at random: a branch on them is mispredicted about as often as it is taken.
HD inline void appendIf(int* row, int& n, int cap, int j, bool hit, int& spill) {
  *(n < cap ? row + n : &spill) = j;
  n += hit;
}

/// Entries of a row (n of them) with a partner slot above i: the pairs the row owns. Rows of a
/// dilute gas hold zero to two entries: the first two are read whatever n (capacity >= 4) and
/// counted by masks, without branches.
HD inline int ownedEntries(const int* row, int n, int i) {
  int own = (n > 0) & (row[0] > i);
  own += (n > 1) & (row[1] > i);
  for (int k = 2; k < n; ++k) own += row[k] > i;
  return own;
}

/// Sorts a row of slots by particle id: insertion sort for the short rows of contact-only lists,
/// Shell sort (Ciura's gaps) for the long rows of Coulomb real-space lists, where insertion while
/// scanning was quadratic in the row length.
HD inline void sortRowById(int* row, int n, const int* id) {
  if (n < 2) return;
  if (n == 2) {  // most sorted rows of a dilute gas: one compare-and-swap
    const int a = row[0], b = row[1];
    const bool swap = id[b] < id[a];
    row[0] = swap ? b : a;
    row[1] = swap ? a : b;
    return;
  }
  const int gaps[6] = {132, 57, 23, 10, 4, 1};
  constexpr int LOCAL = 384;
  if (n > 16 && n <= LOCAL) {
    // long rows: sort (id, slot) keys held in a local buffer, so that no comparison loads id[]
    // through the row (an indirect, cache-missing load per comparison dominated the build)
    std::uint64_t key[LOCAL];
    for (int k = 0; k < n; ++k)
      key[k] = (static_cast<std::uint64_t>(id[row[k]]) << 32) | static_cast<std::uint32_t>(row[k]);
    for (int g = 0; g < 6; ++g) {
      const int gap = gaps[g];
      for (int k = gap; k < n; ++k) {
        const std::uint64_t v = key[k];
        int m = k;
        while (m >= gap && key[m - gap] > v) {
          key[m] = key[m - gap];
          m -= gap;
        }
        key[m] = v;
      }
    }
    for (int k = 0; k < n; ++k) row[k] = static_cast<int>(key[k] & 0xffffffffu);
    return;
  }
  for (int g = n <= 16 ? 5 : 0; g < 6; ++g) {
    const int gap = gaps[g];
    for (int k = gap; k < n; ++k) {
      const int v = row[k], key = id[v];
      int m = k;
      while (m >= gap && id[row[m - gap]] > key) {
        row[m] = row[m - gap];
        m -= gap;
      }
      row[m] = v;
    }
  }
}

/// First slot (in the cell-sorted order) of every cell, as lower bounds: start[c] = first s with
/// cell[s] >= c, and start[ncell] = N. Empty cells get start[c] = start[c + 1], so the slots of
/// consecutive cells c0..c1 are the one range [start[c0], start[c1 + 1]). O(N + ncell): slot s
/// writes the cells after its predecessor's, up to its own.
struct CellStarts {
  const int* cell;  // sorted cell index of each position in the order
  int* start;
  int n, ncell;
  HD int operator()(int s) const {
    const int lo = s == 0 ? 0 : cell[s - 1] + 1, hi = cell[s];
    // The last RUN cells up to hi without a loop or a branch (a cell below lo goes to the scratch
    // slot start[ncell + 1]; the index is selected by a mask, as g++ turns a select of addresses
    // into a branch); longer runs of empty cells by a loop. Cells outnumber particles a few times
    // and the runs vary at random: a loop per slot costs a mispredicted exit.
    for (int k = 0; k < RUN; ++k) {
      const int c = hi - k, below = -static_cast<int>(c < lo);
      start[c ^ ((c ^ (ncell + 1)) & below)] = s;
    }
    for (int c = lo; c <= hi - RUN; ++c) start[c] = s;
    if (s == n - 1)
      for (int c = hi + 1; c <= ncell; ++c) start[c] = n;
    return 0;
  }
  static constexpr int RUN = 4;
};

/// SORTED: the particle storage is in cell order (slot s is the s-th in the order), so candidates
/// are read straight from consecutive slots instead of through the order.
template <bool SORTED>
struct BuildCells {
  const Scalar4* pos;
  const int *order, *cell_start, *id;
  int *list, *count;
  int* owned;  // null, or the number of entries j > i of each row (the pairs it owns: keepPairs)
  common::Box box;
  double inv_cell, r2;
  int nc, cap;

  /// Candidates in the slot range [s0, s1) of the cell order.
  HD void scan(int s0, int s1, int i, double xi, double yi, double zi, int* row, int& n,
               int& spill) const {
    for (int s = s0; s < s1; ++s) {
      const int j = SORTED ? s : order[s];
      const Scalar4 rj = pos[j];
      const double rx = box.minimumImageWrapped(xi - rj.x), ry = box.minimumImageWrapped(yi - rj.y),
                   rz = box.minimumImageWrapped(zi - rj.z);
      appendIf(row, n, cap, j, (rx * rx + ry * ry + rz * rz < r2) & (j != i), spill);
    }
  }

  /// SORTED: the slots of the range [s0, s1) go to the candidate buffer without a loop -- four
  /// consecutive slots are written whatever the length and the first min(length, 4) kept -- and
  /// the rest (dense cells only) is scanned at once. In a dilute gas a range holds about one
  /// particle: a loop per range costs a mispredicted exit each, here the candidates of all ranges
  /// are screened in one loop. Unsorted: scanned at once.
  HD void range(int s0, int s1, int i, double xi, double yi, double zi, int* row, int& n,
                int& spill, int* cand, int& m) const {
    if (!SORTED) return scan(s0, s1, i, xi, yi, zi, row, n, spill);
    const int len = s1 - s0;
    for (int k = 0; k < GATHER; ++k) cand[m + k] = s0 + k;
    m += len < GATHER ? len : GATHER;
    if (len > GATHER) scan(s0 + GATHER, s1, i, xi, yi, zi, row, n, spill);
  }
  static constexpr int GATHER = 4;

  /// The candidates cand[0, m); WRAP: with minimum images (differences across the faces), without
  /// branches: about one candidate in three of a particle next to a face is across it.
  template <bool WRAP>
  HD_INLINE void screen(const int* cand, int m, int i, double xi, double yi, double zi, int* row,
                        int& n, int& spill) const {
    for (int t = 0; t < m; ++t) {
      const int j = cand[t];
      const Scalar4 rj = pos[j];
      double rx = xi - rj.x, ry = yi - rj.y, rz = zi - rj.z;
      if (WRAP) {
        rx = box.minimumImageWrappedBranchless(rx);
        ry = box.minimumImageWrappedBranchless(ry);
        rz = box.minimumImageWrappedBranchless(rz);
      }
      appendIf(row, n, cap, j, (rx * rx + ry * ry + rz * rz < r2) & (j != i), spill);
    }
  }

  HD int operator()(int i) const {
    const Scalar4 ri = pos[i];
    const double xi = ri.x, yi = ri.y, zi = ri.z;
    int cx = static_cast<int>(xi * inv_cell), cy = static_cast<int>(yi * inv_cell),
        cz = static_cast<int>(zi * inv_cell);
    cx = cx < 0 ? 0 : (cx >= nc ? nc - 1 : cx);
    cy = cy < 0 ? 0 : (cy >= nc ? nc - 1 : cy);
    cz = cz < 0 ? 0 : (cz >= nc ? nc - 1 : cz);
    // periodic neighbour cells along x and y (nc >= 3, so the three are distinct); no modulo
    const int xs[3] = {cx == 0 ? nc - 1 : cx - 1, cx, cx == nc - 1 ? 0 : cx + 1};
    const int ys[3] = {cy == 0 ? nc - 1 : cy - 1, cy, cy == nc - 1 ? 0 : cy + 1};
    int* row = list + static_cast<long>(i) * cap;
    int n = 0, spill = 0;
    int cand[18 * GATHER];  // at most 18 ranges (9 columns, split in two where they wrap in z)
    int m = 0;
    // the three cells cz-1, cz, cz+1 of a column are consecutive in the cell order (one slot range)
    // unless the column wraps through the z faces (two ranges)
    if (cz > 0 && cz < nc - 1) {
      for (int a = 0; a < 3; ++a) {
        const int xbase = xs[a] * nc;
        for (int b = 0; b < 3; ++b) {
          const int c0 = (xbase + ys[b]) * nc + cz - 1;
          range(cell_start[c0], cell_start[c0 + 3], i, xi, yi, zi, row, n, spill, cand, m);
        }
      }
    } else {
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const int base = (xs[a] * nc + ys[b]) * nc;
          if (cz == 0) {
            range(cell_start[base], cell_start[base + 2], i, xi, yi, zi, row, n, spill, cand, m);
            range(cell_start[base + nc - 1], cell_start[base + nc], i, xi, yi, zi, row, n, spill,
                  cand, m);
          } else {
            range(cell_start[base], cell_start[base + 1], i, xi, yi, zi, row, n, spill, cand, m);
            range(cell_start[base + nc - 2], cell_start[base + nc], i, xi, yi, zi, row, n, spill,
                  cand, m);
          }
        }
    }
    // SORTED: the gathered candidates, in one loop. Away from the faces (no neighbour cell wraps,
    // about two particles in three) every difference is its own minimum image: no image tests.
    if (cx > 0 && cx < nc - 1 && cy > 0 && cy < nc - 1 && cz > 0 && cz < nc - 1)
      screen<false>(cand, m, i, xi, yi, zi, row, n, spill);
    else
      screen<true>(cand, m, i, xi, yi, zi, row, n, spill);
    sortRowById(row, n < cap ? n : cap,
                id);  // sums over the row then run in id order (determinism)
    count[i] = n;
    if (owned) owned[i] = ownedEntries(row, n < cap ? n : cap, i);
    return 0;
  }
};

/// Row i of a longer list filtered to the pairs within range.
struct FilterRows {
  const Scalar4* pos;
  const int *super_rows, *super_count;
  int super_cap;
  int *list, *count;
  int* owned;  // as in BuildCells
  common::Box box;
  double r2;
  int cap;
  HD void operator()(int i) const {
    const Scalar4 ri = pos[i];
    const int* in = super_rows + static_cast<long>(i) * super_cap;
    int* row = list + static_cast<long>(i) * cap;
    int n = 0, spill = 0;
    for (int k = 0; k < super_count[i]; ++k) {
      const int j = in[k];
      const Scalar4 rj = pos[j];
      const double rx = box.minimumImageWrapped(ri.x - rj.x),
                   ry = box.minimumImageWrapped(ri.y - rj.y),
                   rz = box.minimumImageWrapped(ri.z - rj.z);
      appendIf(row, n, cap, j, rx * rx + ry * ry + rz * rz < r2, spill);
    }
    count[i] = n;
    if (owned) owned[i] = ownedEntries(row, n < cap ? n : cap, i);
  }
};

/// Row i's share of the compressed pair form (NeighborList::keepPairs): its owned pairs, its
/// entries with the pair of each, and each pair's entry in this row. The pair of an entry
/// (i, j < i) is found in row j, the row that owns it, by counting j's owned pairs before i.
/// Returns the entries whose partner row does not list i (zero for a valid list, which is
/// symmetric: both rows test the same squared distance).
struct CompressRow {
  const int *rows, *count, *pair_offsets, *entry_offsets;
  int *pair_owners, *pair_partners, *entry_owners, *entry_pairs, *pair_entries;
  int cap;
  HD int operator()(int i) const {
    const int* row = rows + static_cast<long>(i) * cap;
    int p = pair_offsets[i], e = entry_offsets[i], missing = 0;
    for (int k = 0; k < count[i]; ++k, ++e) {
      const int j = row[k];
      entry_owners[e] = i;
      if (j > i) {
        pair_owners[p] = i;
        pair_partners[p] = j;
        pair_entries[2 * p] = e;
        entry_pairs[e] = p++;
        continue;
      }
      const int* rj = rows + static_cast<long>(j) * cap;
      int q = pair_offsets[j], m = 0;
      while (m < count[j] && rj[m] != i) q += rj[m++] > j;
      missing += m == count[j];
      if (m < count[j]) pair_entries[2 * q + 1] = e;  // (else the list is invalid: reported below)
      entry_pairs[e] = ~q;
    }
    return missing;
  }
};

struct BuildAllPairs {
  const Scalar4* pos;
  const int* id;
  int *list, *count;
  int* owned;  // as in BuildCells
  common::Box box;
  double r2;
  int N, cap;
  HD void operator()(int i) const {
    int* row = list + static_cast<long>(i) * cap;
    int n = 0;
    for (int j = 0; j < N; ++j) {
      if (j == i) continue;
      const Scalar4 ri = pos[i], rj = pos[j];
      const double rx = box.minimumImageWrapped(ri.x - rj.x),
                   ry = box.minimumImageWrapped(ri.y - rj.y),
                   rz = box.minimumImageWrapped(ri.z - rj.z);
      if (rx * rx + ry * ry + rz * rz < r2) append(row, n, cap, j);
    }
    sortRowById(row, n < cap ? n : cap,
                id);  // sums over the row then run in id order (determinism)
    count[i] = n;
    if (owned) owned[i] = ownedEntries(row, n < cap ? n : cap, i);
  }
};

}  // namespace

/// A number never returned before in this process (NeighborList::generation).
static std::uint64_t nextGeneration() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

NeighborList::NeighborList(double cutoff, double skin) : m_cutoff(cutoff), m_skin(skin) {
  if (!(cutoff > 0.0) || !(skin > 0.0))
    throw std::invalid_argument("neighbour list needs cutoff > 0 and skin > 0.");
}

void NeighborList::setSkin(double skin) {
  if (!(skin > 0.0)) throw std::invalid_argument("neighbour list needs skin > 0.");
  m_skin = skin;
}

bool NeighborList::needsRebuild(const ParticleData& p, double max_displacement2) const {
  return m_builds == 0 || m_built_n != p.size() ||
         !(max_displacement2 <= 0.25 * m_skin * m_skin);  // NaN: rebuild
}

int NeighborList::cellsPerSide(const common::Box& box) const {
  const double range = m_cutoff + m_skin;
  if (2.0 * range > box.L)
    throw std::invalid_argument(
        "box edge L = " + std::to_string(box.L) + " is smaller than twice the neighbour range " +
        std::to_string(range) +
        " (contact distance 1 + skin): use more particles or a smaller skin.");
  return static_cast<int>(std::floor(box.L / range));
}

const DVec<int>& NeighborList::computeCellOrder(const ParticleData& p, const common::Box& box) {
  const int N = static_cast<int>(p.size());
  const int nc = cellsPerSide(box);
  if (nc < 3) {
    m_order.clear();
    return m_order;
  }
  m_cell.resize(N);
  m_order.resize(N);
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N),
                   CellIndex{raw(p.pos), raw(m_cell), nc / box.L, nc});
  thrust::sequence(m_order.begin(), m_order.end());
  thrust::stable_sort_by_key(m_cell.begin(), m_cell.end(), m_order.begin());
  return m_order;
}

void NeighborList::build(const ParticleData& p, const common::Box& box) {
  buildImpl(p, box, false);
}

void NeighborList::buildSorted(const ParticleData& p, const common::Box& box) {
  if (m_order.empty()) return buildImpl(p, box, false);  // box too small for cells: all-pairs build
  if (m_order.size() != p.size() || m_cell.size() != p.size())
    throw std::logic_error("NeighborList::buildSorted: no cell order computed for these particles");
  buildImpl(p, box, true);
}

void NeighborList::buildImpl(const ParticleData& p, const common::Box& box, bool sorted) {
  const int N = static_cast<int>(p.size());
  const double range = m_cutoff + m_skin;
  const int nc = cellsPerSide(box);
  const auto first = thrust::counting_iterator<int>(0), last = thrust::counting_iterator<int>(N);
  m_count.resize(N);
  m_capacity = m_next_capacity;
  // sorted: computeCellOrder ran on these positions and the storage was permuted by its order, so
  // m_cell (sorted in place with the order) holds the cell of every slot and the order is the
  // identity
  if (nc >= 3 && !sorted) computeCellOrder(p, box);
  for (;;) {
    m_list.resize(static_cast<std::size_t>(N) * m_capacity);
    if (nc >= 3) {
      const int ncell = nc * nc * nc;
      const double inv_cell = nc / box.L;
      m_cell_start.resize(ncell + 2);  // + 1: CellStarts' scratch slot
      // blocked loops (md/engine/Launch.h): the functors' members stay in registers
      const int block = blockSizeFor(N);
      forEachBlocked(N, block, CellStarts{raw(m_cell), raw(m_cell_start), N, ncell}, NoReduction{},
                     nullptr);
      if (sorted)
        forEachBlocked(N, block,
                       BuildCells<true>{raw(p.pos), nullptr, raw(m_cell_start), raw(p.id),
                                        raw(m_list), raw(m_count), ownedOut(N), box, inv_cell,
                                        range * range, nc, m_capacity},
                       NoReduction{}, nullptr);
      else
        forEachBlocked(N, block,
                       BuildCells<false>{raw(p.pos), raw(m_order), raw(m_cell_start), raw(p.id),
                                         raw(m_list), raw(m_count), ownedOut(N), box, inv_cell,
                                         range * range, nc, m_capacity},
                       NoReduction{}, nullptr);
    } else {
      m_order.clear();
      thrust::for_each(first, last,
                       BuildAllPairs{raw(p.pos), raw(p.id), raw(m_list), raw(m_count), ownedOut(N),
                                     box, range * range, N, m_capacity});
    }
    if (fitCapacity(N)) break;
  }
  m_built_n = p.size();
  ++m_builds;
  m_generation = nextGeneration();
}

void NeighborList::compress(int N) {
  const auto first = thrust::counting_iterator<int>(0), last = thrust::counting_iterator<int>(N);
  m_entry_offsets.resize(N + 1);
  thrust::exclusive_scan(m_count.begin(), m_count.end(), m_entry_offsets.begin());
  const int entries =
      N ? static_cast<int>(m_entry_offsets[N - 1]) + static_cast<int>(m_count[N - 1]) : 0;
  m_entry_offsets[N] = entries;
  // m_pair_offsets holds each row's owned pairs, counted by the build (ownedOut)
  const int last_owned = N ? static_cast<int>(m_pair_offsets[N - 1]) : 0;
  thrust::exclusive_scan(m_pair_offsets.begin(), m_pair_offsets.begin() + N,
                         m_pair_offsets.begin());
  const int pairs = N ? static_cast<int>(m_pair_offsets[N - 1]) + last_owned : 0;
  m_pair_offsets[N] = pairs;
  m_pair_owners.resize(pairs);
  m_pair_partners.resize(pairs);
  m_entry_owners.resize(entries);
  m_entry_pairs.resize(entries);
  m_pair_entries.resize(2 * static_cast<std::size_t>(pairs));
  const int missing = thrust::transform_reduce(
      first, last,
      CompressRow{raw(m_list), raw(m_count), raw(m_pair_offsets), raw(m_entry_offsets),
                  raw(m_pair_owners), raw(m_pair_partners), raw(m_entry_owners), raw(m_entry_pairs),
                  raw(m_pair_entries), m_capacity},
      0, thrust::plus<int>());
  if (missing != 0 || 2 * pairs != entries)
    throw std::logic_error("NeighborList: the rows are not symmetric (" + std::to_string(missing) +
                           " entries without their mirror entry)");
}

int* NeighborList::ownedOut(int N) {
  if (!m_keep_pairs) return nullptr;
  m_pair_offsets.resize(N + 1);
  return raw(m_pair_offsets);
}

bool NeighborList::fitCapacity(int N) {
  const int most =
      N ? thrust::reduce(m_count.begin(), m_count.end(), 0, thrust::maximum<int>()) : 0;
  if (most <= m_capacity) {
    if (m_keep_pairs) compress(N);
    // rows much wider than needed cost a cache line per particle per step for nothing: the next
    // build uses a tighter capacity (a later overflow is caught by the caller). Not this one: its
    // rows are laid out with the current stride.
    m_next_capacity = 2 * (most + most / 4 + 4) < m_capacity ? most + most / 4 + 4 : m_capacity;
    return true;
  }
  m_capacity = m_next_capacity =
      most + most / 4 + 4;  // overflow detected: grow and rebuild, never truncate
  return false;
}

void NeighborList::buildFrom(const NeighborList& super, const ParticleData& p,
                             const common::Box& box) {
  const int N = static_cast<int>(p.size());
  if (super.m_built_n != p.size() || super.listRange() < listRange())
    throw std::logic_error(
        "NeighborList::buildFrom: the longer list is not built for these particles or is too "
        "short");
  const double range = m_cutoff + m_skin;
  m_count.resize(N);
  m_capacity = m_next_capacity;
  do {
    m_list.resize(static_cast<std::size_t>(N) * m_capacity);
    thrust::for_each(
        thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N),
        FilterRows{raw(p.pos), super.rows(), super.counts(), super.capacity(), raw(m_list),
                   raw(m_count), ownedOut(N), box, range * range, m_capacity});
  } while (!fitCapacity(N));
  m_built_n = p.size();
  ++m_builds;
  m_generation = nextGeneration();
}

}  // namespace granagg::md
