#include "analysis/clusters/ClusterSizes.h"

#include <cmath>

namespace granagg::analysis {

ClusterSizes ClusterSizes::fromSizes(const std::vector<std::uint64_t>& sizes) {
  ClusterSizes c;
  long double m2 = 0;  // exact up to 2^64 in long double's 64-bit mantissa
  for (std::uint64_t s : sizes) {
    if (s == 0) continue;
    ++c.n_s[s];
    ++c.clusters;
    c.mass += s;
    m2 += static_cast<long double>(s) * static_cast<long double>(s);
    if (s > c.largest) c.largest = s;
  }
  c.S = c.mass > 0 ? static_cast<double>(m2 / static_cast<long double>(c.mass)) : std::nan("");
  const long double big = static_cast<long double>(c.largest);
  c.S_without_largest =
      c.clusters >= 2
          ? static_cast<double>((m2 - big * big) / (static_cast<long double>(c.mass) - big))
          : std::nan("");
  c.largest_share =
      c.mass > 0 ? static_cast<double>(big / static_cast<long double>(c.mass)) : std::nan("");
  return c;
}

std::vector<std::uint64_t> ClusterSizes::samples() const {
  std::vector<std::uint64_t> out;
  out.reserve(clusters);
  for (const auto& [s, count] : n_s) out.insert(out.end(), count, s);
  return out;
}

}  // namespace granagg::analysis
