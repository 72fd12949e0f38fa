// The growth exponent z of S(t) over a window, with its bootstrap interval over runs
// (BetaFit.h: ZFit).
#include "meanfield/fit/BetaFit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/Csv.h"
#include "common/Statistics.h"
#include "common/Strings.h"
#include "meanfield/fit/FitSupport.h"

namespace granagg::meanfield {

using common::formatReal;
using namespace detail;

ZFit fitGrowthExponent(const GrowthData& data, const SlopeWindow& window,
                       const BootstrapOptions& o) {
  validateGrowthData(data);
  if (!(o.confidence > 0.0 && o.confidence < 1.0))
    throw std::invalid_argument("confidence must lie in (0, 1).");
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < data.t.size(); ++i)
    if (data.t[i] >= window.t0 && data.t[i] <= window.t1) idx.push_back(i);
  if (idx.size() < 3)
    throw std::invalid_argument("too few points in the window [" + formatReal(window.t0) + ", " +
                                formatReal(window.t1) + "]: " + std::to_string(idx.size()) +
                                ", at least 3 needed.");
  std::vector<double> x, y;
  for (std::size_t i : idx) {
    x.push_back(std::log(data.t[i]));
    y.push_back(std::log(data.S[i]));
  }
  ZFit f;
  const auto [y_lo, y_hi] = std::minmax_element(y.begin(), y.end());
  if (*y_hi - *y_lo <= 1e-12) {
    f.z = f.z_low = f.z_high = NaN;
    f.S0 = f.S1 = f.prefactor = std::exp(*y_lo);
    f.t0 = data.t[idx.front()];
    f.t1 = data.t[idx.back()];
    f.points = static_cast<int>(idx.size());
    f.confidence = o.confidence;
    f.interval_method = "none";
    f.note = "S is " + common::formatShort(f.S0) + " at every sample of the window [" +
             common::formatShort(f.t0) + ", " + common::formatShort(f.t1) +
             "]: it does not grow, no growth exponent.";
    return f;
  }
  double c0, se;
  ols(x, y, f.z, c0, se);
  f.prefactor = std::exp(c0);
  f.t0 = data.t[idx.front()];
  f.t1 = data.t[idx.back()];
  f.points = static_cast<int>(idx.size());
  f.S0 = std::exp(c0 + f.z * x.front());
  f.S1 = std::exp(c0 + f.z * x.back());
  f.confidence = o.confidence;
  constexpr double ROUNDOFF = 1e-12;
  if (data.runs.size() >= static_cast<std::size_t>(std::max(o.min_runs, 2)) && o.replicates_z > 0) {
    Rng rng(o.seed);
    std::vector<double> zs;
    for (int b = 0; b < o.replicates_z; ++b) {
      const std::vector<double> S = resampledMean(data, rng.resample(data.runs.size()));
      std::vector<double> yb;
      for (std::size_t i : idx) yb.push_back(std::log(S[i]));
      double zb, cb, sb;
      ols(x, yb, zb, cb, sb);
      zs.push_back(zb);
    }
    bootstrapInterval(zs, f.z, data.runs.size(), o.confidence, f.z_low, f.z_high);
    f.z_low = std::min(f.z_low, f.z - ROUNDOFF);
    f.z_high = std::max(f.z_high, f.z + ROUNDOFF);
    f.interval_method = "bootstrap-runs";
    f.replicates = o.replicates_z;
  } else {
    const double half = std::max(
        common::stats::studentHalfWidth(se, static_cast<double>(idx.size() - 2), o.confidence),
        ROUNDOFF);
    f.z_low = f.z - half;
    f.z_high = f.z + half;
    f.interval_method = "student-t";
  }
  return f;
}

}  // namespace granagg::meanfield
