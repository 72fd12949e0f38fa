#pragma once
/// \file NeighborList.h
/// Cell list + Verlet neighbour list with a skin (device source; Thrust).
///
/// Full lists (every pair appears in the rows of both partners), each row sorted by particle id
/// (ParticleData::id, not the storage slot) so that per-particle force sums run in a fixed order
/// whatever the storage order (Engine.h, determinism). Rows have a fixed
/// capacity; a row that would overflow is detected after the build, the capacity grows and the list
/// is rebuilt -- never truncated (STYLE.md). The list is rebuilt when some particle has moved more
/// than skin/2 since the last build (then no pair can have come within the contact distance 1
/// unseen). Boxes with fewer than 3 cells per side use an all-pairs build (small systems).
#include <cstdint>

#include "common/Box.h"
#include "md/engine/ParticleData.h"

namespace granagg::md {

class NeighborList {
 public:
  /// \param cutoff interaction range (1 for contacts); \param skin added to it for the list.
  NeighborList(double cutoff, double skin);

  /// True if never built (for this N) or if max_displacement2, a bound on the largest squared
  /// displacement of any particle since the last build, exceeds (skin/2)^2 (then a pair may have
  /// come within the cutoff unseen). The engine bounds displacements by the sum over steps of
  /// dt max|v|, which kickDrift measures in its own pass.
  bool needsRebuild(const ParticleData& p, double max_displacement2) const;
  /// Slots sorted by cell for the current positions (stable), without building the list; empty if
  /// the box is too small for cells (all-pairs builds). For sorting the particle storage.
  const DVec<int>& computeCellOrder(const ParticleData& p, const common::Box& box);
  /// Unconditional rebuild.
  void build(const ParticleData& p, const common::Box& box);
  /// Unconditional rebuild right after the storage was permuted into the order computeCellOrder
  /// returned (positions unchanged since): the cell search then reads candidates from consecutive
  /// slots and skips sorting the cells again. Same list as build().
  void buildSorted(const ParticleData& p, const common::Box& box);
  /// Unconditional rebuild from a longer list that is valid for the current positions out to at
  /// least this list's range (every pair closer than listRange() is in `super`): each row keeps
  /// the entries of super's row within range, already in id order. Much cheaper than a cell
  /// search when super is the Coulomb list and this the short contact list (Engine).
  void buildFrom(const NeighborList& super, const ParticleData& p, const common::Box& box);

  /// Also keep the list in compressed pair form, rebuilt with every build, for passes that walk the
  /// entries of many particles as one loop and compute each pair's contact once (ContactForce.cpp):
  /// - pairs: every pair once, owned by its lower slot. Pair p joins pairOwners()[p] and
  ///   pairPartners()[p] (> owner); the pairs of owner i are [pairOffsets()[i], pairOffsets()[i +
  ///   1]), in row (id) order.
  /// - entries: the full rows back to back, entry e of row entryOwners()[e] (the entries of row i
  ///   are [entryOffsets()[i], entryOffsets()[i + 1]), in row order), each with its pair:
  ///   entryPairs()[e] = p where the row owns pair p, ~p (negative) where the row is p's partner.
  /// Every offset array holds N + 1 values.
  void keepPairs(bool on) { m_keep_pairs = on; }
  bool hasPairs() const { return m_keep_pairs && m_pair_offsets.size() == m_built_n + 1; }
  const int* pairOffsets() const { return raw(m_pair_offsets); }
  const int* pairOwners() const { return raw(m_pair_owners); }
  const int* pairPartners() const { return raw(m_pair_partners); }
  std::size_t pairCount() const { return m_pair_owners.size(); }
  const int* entryOffsets() const { return raw(m_entry_offsets); }
  const int* entryOwners() const { return raw(m_entry_owners); }
  const int* entryPairs() const { return raw(m_entry_pairs); }
  /// The two entries of pair p: pairEntries()[2p] in the owner's row, pairEntries()[2p + 1] in
  /// the partner's.
  const int* pairEntries() const { return raw(m_pair_entries); }
  /// Identifies the current list among every list built in this process (changes at each build).
  std::uint64_t generation() const { return m_generation; }

  const int* rows() const { return raw(m_list); }     ///< row i at rows()[i * capacity()]
  const int* counts() const { return raw(m_count); }  ///< entries in row i
  int capacity() const { return m_capacity; }
  std::int64_t builds() const { return m_builds; }
  double listRange() const { return m_cutoff + m_skin; }
  double skin() const { return m_skin; }
  /// A new skin (> 0) for the next build (md/neighbor/Skin.h). Call it right before rebuilding:
  /// the list reports and tests the new skin at once, and its entries are complete for it only
  /// after the build. The cell order is computed for it too (computeCellOrder).
  void setSkin(double skin);

 private:
  int cellsPerSide(const common::Box& box) const;
  void buildImpl(const ParticleData& p, const common::Box& box, bool sorted);
  /// Finishes a build: checks the rows against the capacity (true: they fit) and plans the next
  /// one.
  bool fitCapacity(int N);
  /// The compressed pair form of the rows (keepPairs), from the rows and their owned pairs
  /// (ownedOut).
  void compress(int N);
  /// With keepPairs, where a build writes the number of pairs each row owns (its entries j > i,
  /// the pair form's pair counts before the scan); otherwise null.
  int* ownedOut(int N);
  double m_cutoff, m_skin;
  int m_capacity = 16;  // row stride of the current list
  int m_next_capacity =
      16;  // for the next build: grows on overflow, shrinks when rows are mostly empty
  std::int64_t m_builds = 0;
  DVec<int> m_list, m_count;
  bool m_keep_pairs = false;
  DVec<int> m_pair_offsets, m_pair_owners, m_pair_partners;
  DVec<int> m_entry_offsets, m_entry_owners, m_entry_pairs, m_pair_entries;
  std::uint64_t m_generation = 0;
  std::size_t m_built_n = 0;  // N at the last build
  DVec<int> m_cell, m_order, m_cell_start;
};

}  // namespace granagg::md
