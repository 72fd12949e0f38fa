#include "analysis/stats/GrowthMarkers.h"

#include "common/Statistics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace granagg::analysis {

LogBinnedFit fitLogBinnedPowerLaw(const std::map<std::uint64_t, std::uint64_t>& counts,
                                  double ratio, std::size_t min_bins) {
  if (!(ratio > 1.0) || !std::isfinite(ratio))
    throw std::invalid_argument("log-binned fit: bin ratio must be > 1");
  if (min_bins < 3) throw std::invalid_argument("log-binned fit: needs at least 3 bins");
  LogBinnedFit fit;
  if (counts.empty()) return fit;
  fit.s_max = counts.rbegin()->first;
  std::vector<double> x, y;
  // Bin k holds the integer sizes in [lo, hi): lo = ceil(ratio^k), with hi > lo always (a ratio
  // close to 1 would otherwise give empty bins at small s).
  auto it = counts.begin();
  double edge = 1.0;
  std::uint64_t lo = 1;
  while (it != counts.end()) {
    edge *= ratio;
    std::uint64_t hi = static_cast<std::uint64_t>(std::ceil(edge - 1e-9));
    if (hi <= lo) hi = lo + 1;
    double n = 0;
    for (; it != counts.end() && it->first < hi; ++it)
      if (it->first >= lo) n += static_cast<double>(it->second);
    if (n > 0) {
      x.push_back(0.5 * std::log(static_cast<double>(lo) * static_cast<double>(hi - 1)));
      y.push_back(std::log(n / static_cast<double>(hi - lo)));
    }
    lo = hi;
  }
  fit.bins = x.size();
  if (x.size() < min_bins) return fit;
  // gsl_fit_linear's covariance is already estimated from the scatter about the line: tau_err is
  // its slope's standard error as it is, not scaled by the residual variance again
  const common::stats::LineFit f = common::stats::fitLine(x, y);
  fit.tau = -f.slope;
  fit.tau_err = f.slope_se;
  fit.valid = std::isfinite(fit.tau);
  return fit;
}

OnsetTime onsetTime(const std::vector<double>& t, const std::vector<double>& S, double factor,
                    double t_base) {
  if (t.size() != S.size()) throw std::invalid_argument("onset time: t and S differ in length");
  if (!(factor > 1.0) || !std::isfinite(factor))
    throw std::invalid_argument("onset time: factor must be > 1");
  if (!(t_base > 0.0) || !std::isfinite(t_base))
    throw std::invalid_argument("onset time: baseline time must be > 0");
  OnsetTime o;
  std::vector<double> early;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] > 0 && t[k] <= t_base && std::isfinite(S[k]) && S[k] > 0) early.push_back(S[k]);
  if (early.empty()) return o;
  std::sort(early.begin(), early.end());
  const std::size_t m = early.size();
  o.S_base = m % 2 ? early[m / 2] : 0.5 * (early[m / 2 - 1] + early[m / 2]);
  o.S_threshold = factor * o.S_base;
  double t_prev = 0, S_prev = 0;
  bool have_prev = false;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (!(t[k] > 0) || !std::isfinite(S[k]) || !(S[k] > 0)) continue;
    if (S[k] >= o.S_threshold) {
      if (have_prev && S_prev < o.S_threshold) {
        const double f = std::log(o.S_threshold / S_prev) / std::log(S[k] / S_prev);
        o.t_c = std::exp(std::log(t_prev) + f * std::log(t[k] / t_prev));
      } else {
        o.t_c = t[k];  // already above at the first usable sample
      }
      o.valid = true;
      return o;
    }
    t_prev = t[k];
    S_prev = S[k];
    have_prev = true;
  }
  return o;
}

GrowthRegime classifyGrowth(const std::vector<double>& t, const std::vector<double>& S,
                            const std::vector<double>& z_local, double factor, double t_base,
                            double flat_tolerance) {
  if (z_local.size() != t.size())
    throw std::invalid_argument("growth regime: t and z_local differ in length");
  const double NaN = std::numeric_limits<double>::quiet_NaN();
  GrowthRegime g;
  const OnsetTime on = onsetTime(t, S, factor, t_base);
  g.t_c = on.valid ? on.t_c : NaN;
  double S_last = NaN, t_last = NaN;
  for (std::size_t k = t.size(); k-- > 0;)
    if (std::isfinite(S[k]) && S[k] > 0 && t[k] > 0) {
      S_last = S[k];
      t_last = t[k];
      break;
    }
  g.growth_factor = on.S_base > 0 ? S_last / on.S_base : NaN;
  g.z_local_min = g.z_local_max = NaN;
  char buf[320];
  if (!(g.growth_factor >= factor)) {
    g.regime = "none";
    std::snprintf(buf, sizeof buf,
                  "S grew by a factor %.3g by t = %.4g, less than %g: no aggregation yet",
                  g.growth_factor, t_last, factor);
    g.reason = buf;
    return g;
  }
  std::vector<double> z;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= t_last / std::sqrt(10.0) && t[k] <= t_last && std::isfinite(z_local[k]))
      z.push_back(z_local[k]);
  if (z.size() < 3) {
    g.regime = "onset";
    std::snprintf(
        buf, sizeof buf,
        "S grew by a factor %.3g (onset t_c = %.4g); fewer than 3 local slopes in the last "
        "half decade, no scaling regime can be claimed",
        g.growth_factor, g.t_c);
    g.reason = buf;
    return g;
  }
  g.z_local_min = *std::min_element(z.begin(), z.end());
  g.z_local_max = *std::max_element(z.begin(), z.end());
  double mean = 0;
  for (double x : z) mean += x;
  mean /= static_cast<double>(z.size());
  const bool flat = mean > 0 && (g.z_local_max - g.z_local_min) <= flat_tolerance * mean;
  g.regime = flat ? "scaling" : "onset";
  std::snprintf(
      buf, sizeof buf,
      "S grew by a factor %.3g (onset t_c = %.4g); local slope %.3g..%.3g over t = %.4g..%.4g: %s",
      g.growth_factor, g.t_c, g.z_local_min, g.z_local_max, t_last / std::sqrt(10.0), t_last,
      flat ? "flat, a scaling regime" : "still changing, not yet a power law");
  g.reason = buf;
  return g;
}

}  // namespace granagg::analysis
