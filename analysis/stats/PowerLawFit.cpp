#include "analysis/stats/PowerLawFit.h"

#include "common/Statistics.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace granagg::analysis {

PowerLawFitResult fitPowerLaw(const std::vector<double>& t, const std::vector<double>& y,
                              double t_min, double t_max, double confidence) {
  if (t.size() != y.size()) throw std::invalid_argument("fitPowerLaw: t and y differ in length.");
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("fitPowerLaw: confidence must lie in (0, 1).");
  std::vector<double> lx, ly;
  for (std::size_t k = 0; k < t.size(); ++k)
    // Window ends include samples within a relative 1e-4 (WINDOW_SLACK): MD frames sit on whole
    // steps, so the frame meant for t = 1000 may be at 1000.001 and must not drop out.
    if (t[k] > 0 && t[k] >= t_min * (1 - WINDOW_SLACK) && t[k] <= t_max * (1 + WINDOW_SLACK) &&
        y[k] > 0 && std::isfinite(y[k]) && std::isfinite(t[k])) {
      lx.push_back(std::log(t[k]));
      ly.push_back(std::log(y[k]));
    }
  PowerLawFitResult r;
  r.points = lx.size();
  if (r.points < 3) return r;
  const auto [lo, hi] = std::minmax_element(ly.begin(), ly.end());
  if (*hi - *lo <= 1e-12) {  // ln y equal to round-off
    r.constant = true;
    return r;
  }
  const common::stats::LineFit f = common::stats::fitLine(lx, ly);
  r.exponent = f.slope;
  r.amplitude = std::exp(f.intercept);
  r.stderr_z = f.slope_se;
  const double half =
      common::stats::studentHalfWidth(r.stderr_z, static_cast<double>(r.points - 2), confidence);
  r.low = f.slope - half;
  r.high = f.slope + half;
  r.valid = std::isfinite(f.slope);
  return r;
}

PowerLawFitResult bootstrapPowerLaw(const std::vector<double>& t,
                                    const std::vector<std::vector<double>>& runs, double t_min,
                                    double t_max, int replicates, std::uint64_t seed,
                                    double confidence) {
  if (runs.size() < 2) throw std::invalid_argument("bootstrapPowerLaw needs at least 2 runs.");
  if (replicates < 10)
    throw std::invalid_argument("bootstrapPowerLaw needs at least 10 replicates.");
  for (const auto& r : runs)
    if (r.size() != t.size())
      throw std::invalid_argument("bootstrapPowerLaw: every run needs one value per time.");
  auto meanOver = [&](const std::vector<std::size_t>& pick) {
    std::vector<double> m(t.size(), 0.0);
    for (std::size_t r : pick)
      for (std::size_t k = 0; k < t.size(); ++k) m[k] += runs[r][k];
    for (double& v : m) v /= static_cast<double>(pick.size());
    return m;
  };
  std::vector<std::size_t> all(runs.size());
  for (std::size_t r = 0; r < runs.size(); ++r) all[r] = r;
  PowerLawFitResult out = fitPowerLaw(t, meanOver(all), t_min, t_max, confidence);
  if (!out.valid) return out;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> draw(0, runs.size() - 1);
  std::vector<double> z;
  std::vector<std::size_t> pick(runs.size());
  for (int b = 0; b < replicates; ++b) {
    for (auto& p : pick) p = draw(rng);
    const PowerLawFitResult f = fitPowerLaw(t, meanOver(pick), t_min, t_max, confidence);
    if (f.valid) z.push_back(f.exponent);
  }
  // the interval rule of common/Statistics.h (the same as fit-beta's); err: the replicates' sd
  const common::stats::Interval in =
      common::stats::bootstrapInterval(z, out.exponent, runs.size(), confidence);
  out.low = in.low;
  out.high = in.high;
  double mean = 0, var = 0;
  for (double v : z) mean += v;
  mean /= static_cast<double>(z.size());
  for (double v : z) var += (v - mean) * (v - mean);
  out.stderr_z = std::sqrt(var / static_cast<double>(z.size() - 1));
  return out;
}

std::vector<double> localSlope(const std::vector<double>& t, const std::vector<double>& y,
                               double p) {
  return common::stats::localSlope(t, y, p);
}

}  // namespace granagg::analysis
