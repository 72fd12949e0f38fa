/// \file Statistics.cpp
/// Least squares, Student-t and bootstrap intervals (Statistics.h).
#include "common/Statistics.h"

#include <gsl/gsl_cdf.h>
#include <gsl/gsl_fit.h>
#include <gsl/gsl_statistics_double.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace granagg::common::stats {

namespace {
constexpr double NaN = std::numeric_limits<double>::quiet_NaN();
}

LineFit fitLine(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) throw std::invalid_argument("fitLine: x and y differ in length");
  if (x.size() < 2) throw std::invalid_argument("fitLine: needs at least 2 points");
  double c0, c1, cov00, cov01, cov11, sumsq;
  // gsl_fit_linear estimates the covariance from the scatter of the points about the line: cov11
  // is already sumsq / (n - 2) / sum (x - <x>)^2, the OLS variance of the slope.
  gsl_fit_linear(x.data(), 1, y.data(), 1, x.size(), &c0, &c1, &cov00, &cov01, &cov11, &sumsq);
  LineFit f;
  f.slope = c1;
  f.intercept = c0;
  f.sumsq = sumsq;
  f.n = x.size();
  f.slope_se = f.n >= 3 ? std::sqrt(std::max(cov11, 0.0)) : NaN;
  return f;
}

double studentHalfWidth(double se, double dof, double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("confidence must lie in (0, 1)");
  if (!(dof >= 1.0)) return NaN;
  return gsl_cdf_tdist_Pinv(0.5 + confidence / 2.0, dof) * se;
}

Interval bootstrapInterval(const std::vector<double>& replicates, double estimate, std::size_t runs,
                           double confidence) {
  if (runs < 2) throw std::invalid_argument("bootstrapInterval needs at least 2 runs");
  if (replicates.size() < 2) throw std::invalid_argument("bootstrapInterval needs 2 replicates");
  const double sd = gsl_stats_sd(replicates.data(), 1, replicates.size());
  const double R = static_cast<double>(runs);
  const double half = studentHalfWidth(std::sqrt(R / (R - 1.0)) * sd, R - 1.0, confidence);
  return {estimate - half, estimate + half};
}

std::vector<double> localSlope(const std::vector<double>& t, const std::vector<double>& y,
                               double p) {
  if (t.size() != y.size()) throw std::invalid_argument("localSlope: t and y differ in length");
  if (!(p > 1.0)) throw std::invalid_argument("localSlope requires p > 1");
  std::vector<double> z(t.size(), NaN);
  const double lp = std::log(p);
  std::size_t b = 0;  // the bracketing samples a < t_k / p <= b; b only moves forward (O(n))
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (!(t[k] > 0) || !(y[k] > 0)) continue;
    const double tp = t[k] / p;
    while (b < k && t[b] < tp) ++b;
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

double median(std::vector<double> v) {
  if (v.empty()) return NaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace granagg::common::stats
