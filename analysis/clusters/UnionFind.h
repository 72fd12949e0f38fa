#pragma once
/// \file UnionFind.h
/// Disjoint-set forest with union by size and path halving (Tarjan 1975): near-constant
/// amortised cost per operation, used for periodic connected-component labelling.
#include <cstdint>
#include <numeric>
#include <vector>

namespace granagg::analysis {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n = 0) { reset(n); }
  /// n singletons.
  void reset(std::size_t n) {
    m_parent.resize(n);
    std::iota(m_parent.begin(), m_parent.end(), std::uint32_t{0});
    m_size.assign(n, 1);
  }
  /// Root of a's set.
  std::uint32_t find(std::uint32_t a) {
    while (m_parent[a] != a) {
      m_parent[a] = m_parent[m_parent[a]];  // path halving
      a = m_parent[a];
    }
    return a;
  }
  /// Merges the sets of a and b.
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (m_size[a] < m_size[b]) std::swap(a, b);
    m_parent[b] = a;
    m_size[a] += m_size[b];
  }
  /// Size of the set whose root is r.
  std::uint32_t rootSize(std::uint32_t r) const { return m_size[r]; }
  /// Numbers the sets of the elements i with member(i): labels[i] = 0, 1, ... in the order of
  /// each set's first element (-1 for the others). Returns the size of each labelled set.
  template <class Member>
  std::vector<std::uint64_t> label(std::vector<std::int32_t>& labels, Member member) {
    const std::size_t n = m_parent.size();
    labels.assign(n, -1);
    std::vector<std::int32_t> label_of_root(n, -1);
    std::vector<std::uint64_t> sizes;
    for (std::size_t i = 0; i < n; ++i) {
      if (!member(i)) continue;
      const std::uint32_t r = find(static_cast<std::uint32_t>(i));
      if (label_of_root[r] < 0) {
        label_of_root[r] = static_cast<std::int32_t>(sizes.size());
        sizes.push_back(m_size[r]);
      }
      labels[i] = label_of_root[r];
    }
    return sizes;
  }
  std::size_t size() const { return m_parent.size(); }

 private:
  std::vector<std::uint32_t> m_parent, m_size;
};

}  // namespace granagg::analysis
