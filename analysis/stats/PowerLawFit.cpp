#include "analysis/stats/PowerLawFit.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <gsl/gsl_cdf.h>
#include <gsl/gsl_fit.h>

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
  double c0, c1, cov00, cov01, cov11, sumsq;
  gsl_fit_linear(lx.data(), 1, ly.data(), 1, lx.size(), &c0, &c1, &cov00, &cov01, &cov11, &sumsq);
  // gsl_fit_linear's cov11 is sumsq/(n-2) * 1/sum (x - <x>)^2: the usual OLS variance of the slope.
  r.exponent = c1;
  r.amplitude = std::exp(c0);
  r.stderr_z = std::sqrt(cov11);
  const double q = gsl_cdf_tdist_Pinv(0.5 + confidence / 2, static_cast<double>(r.points - 2));
  r.low = c1 - q * r.stderr_z;
  r.high = c1 + q * r.stderr_z;
  r.valid = std::isfinite(c1);
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
  std::sort(z.begin(), z.end());
  auto quantile = [&](double q) {
    const double pos = q * static_cast<double>(z.size() - 1);
    const std::size_t i = static_cast<std::size_t>(pos);
    const double w = pos - static_cast<double>(i);
    return i + 1 < z.size() ? z[i] * (1 - w) + z[i + 1] * w : z[i];
  };
  out.low = quantile(0.5 - confidence / 2);
  out.high = quantile(0.5 + confidence / 2);
  double mean = 0, var = 0;
  for (double v : z) mean += v;
  mean /= static_cast<double>(z.size());
  for (double v : z) var += (v - mean) * (v - mean);
  out.stderr_z = std::sqrt(var / static_cast<double>(z.size() - 1));
  return out;
}

std::vector<double> localSlope(const std::vector<double>& t, const std::vector<double>& y,
                               double p) {
  if (t.size() != y.size()) throw std::invalid_argument("localSlope: t and y differ in length.");
  if (!(p > 1.0)) throw std::invalid_argument("localSlope requires p > 1.");
  std::vector<double> z(t.size(), std::nan(""));
  const double lp = std::log(p);
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (!(t[k] > 0) || !(y[k] > 0)) continue;
    const double tp = t[k] / p;
    // bracketing samples a <= tp <= b with positive t and y
    std::size_t b = 0;
    while (b < k && t[b] < tp) ++b;
    if (b > k) continue;
    double yp;
    if (t[b] == tp) {
      yp = y[b];
    } else {
      if (b == 0) continue;
      const std::size_t a = b - 1;
      if (!(t[a] > 0) || !(y[a] > 0) || !(y[b] > 0)) continue;
      const double w = (std::log(tp) - std::log(t[a])) / (std::log(t[b]) - std::log(t[a]));
      yp = std::exp(std::log(y[a]) * (1 - w) + std::log(y[b]) * w);
    }
    if (yp > 0) z[k] = std::log(y[k] / yp) / lp;
  }
  return z;
}

}  // namespace granagg::analysis
