#include "analysis/stats/PowerLawMle.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_min.h>
#include <gsl/gsl_sf_zeta.h>

namespace granagg::analysis {

namespace {

constexpr double TAU_LO = 1.0 + 1e-6;  // zeta(tau, q) diverges at tau = 1
constexpr double TAU_HI = 30.0;        // beyond this the tail is a single value in practice

/// ln zeta(tau, q); +inf on error (GSL's error handler is off: errors come back as status codes).
double logHzeta(double tau, double q) {
  gsl_sf_result r;
  if (gsl_sf_hzeta_e(tau, q, &r) != GSL_SUCCESS || !(r.val > 0))
    return std::numeric_limits<double>::infinity();
  return std::log(r.val);
}

struct Objective {
  double xmin;
  double mean_log;  // (1/n) sum ln x_i over the tail
};

/// Negative log-likelihood per sample: ln zeta(tau, xmin) + tau <ln x> (Clauset et al. eq. 3.5).
double negLogLik(double tau, void* p) {
  const auto* o = static_cast<const Objective*>(p);
  return logHzeta(tau, o->xmin) + tau * o->mean_log;
}

struct ErrorHandlerOff {
  ErrorHandlerOff() { gsl_set_error_handler_off(); }
};

}  // namespace

double discretePowerLawCcdf(double tau, std::uint64_t xmin, std::uint64_t x) {
  if (x <= xmin) return 1.0;
  return std::exp(logHzeta(tau, static_cast<double>(x)) - logHzeta(tau, static_cast<double>(xmin)));
}

namespace {

using Histogram =
    std::vector<std::pair<std::uint64_t, std::uint64_t>>;  // (value, count), increasing values

Histogram histogramOf(const std::vector<std::uint64_t>& samples) {
  std::vector<std::uint64_t> sorted = samples;
  std::sort(sorted.begin(), sorted.end());
  Histogram h;
  for (std::uint64_t x : sorted) {
    if (!h.empty() && h.back().first == x)
      ++h.back().second;
    else
      h.emplace_back(x, 1);
  }
  return h;
}

/// MLE on the tail h[first..] with xmin = h[first].first (or a smaller xmin given explicitly).
PowerLawMleResult fitTail(const Histogram& h, std::size_t first, std::uint64_t xmin) {
  static const ErrorHandlerOff off;
  PowerLawMleResult r;
  r.xmin = xmin;
  if (xmin < 1 || first >= h.size()) return r;
  double sum_log = 0.0;
  for (std::size_t k = first; k < h.size(); ++k) {
    r.n_tail += h[k].second;
    sum_log += static_cast<double>(h[k].second) * std::log(static_cast<double>(h[k].first));
  }
  // All samples in one value: the likelihood grows without bound in tau.
  if (r.n_tail < 2 || first + 1 >= h.size()) return r;
  Objective obj{static_cast<double>(xmin), sum_log / static_cast<double>(r.n_tail)};
  gsl_function F{&negLogLik, &obj};
  // Starting point: the continuous approximation with the 1/2 shift (Clauset et al. eq. 3.7).
  double guess = 1.0 + static_cast<double>(r.n_tail) /
                           (sum_log - static_cast<double>(r.n_tail) *
                                          std::log(static_cast<double>(xmin) - 0.5));
  if (!std::isfinite(guess)) guess = 2.5;
  guess = std::clamp(guess, TAU_LO + 1e-3, TAU_HI - 1e-3);
  const double f_lo = negLogLik(TAU_LO, &obj), f_hi = negLogLik(TAU_HI, &obj);
  double f_g = negLogLik(guess, &obj);
  if (!(f_g < f_lo && f_g < f_hi)) {
    // Brent needs a bracketing triple: fall back to a coarse scan for the smallest value.
    double best = std::numeric_limits<double>::infinity();
    for (int k = 1; k < 400; ++k) {
      const double t = TAU_LO + (TAU_HI - TAU_LO) * k / 400.0;
      const double f = negLogLik(t, &obj);
      if (f < best) {
        best = f;
        guess = t;
      }
    }
    f_g = best;
    if (!(f_g < f_lo && f_g < f_hi)) return r;
  }
  gsl_min_fminimizer* s = gsl_min_fminimizer_alloc(gsl_min_fminimizer_brent);
  // Brent stops near sqrt(DBL_EPSILON) |tau| ~ 3e-8 relative: ask for 1e-7, far below any
  // statistical error of tau.
  gsl_min_fminimizer_set_with_values(s, &F, guess, f_g, TAU_LO, f_lo, TAU_HI, f_hi);
  int status = GSL_CONTINUE;
  for (int it = 0; it < 200 && status == GSL_CONTINUE; ++it) {
    if (gsl_min_fminimizer_iterate(s) != GSL_SUCCESS) break;
    status = gsl_min_test_interval(gsl_min_fminimizer_x_lower(s), gsl_min_fminimizer_x_upper(s),
                                   1e-7, 0.0);
  }
  r.tau = gsl_min_fminimizer_x_minimum(s);
  gsl_min_fminimizer_free(s);
  // Fisher information per sample: d^2/dtau^2 ln zeta(tau, xmin), by central differences with a
  // step (1e-3) where truncation (~h^2) and round-off (~1e-16/h^2) errors are both ~1e-6.
  const double hstep = 1e-3;
  const double t0 = std::max(r.tau, TAU_LO + hstep);
  const double d2 = (logHzeta(t0 + hstep, obj.xmin) - 2 * logHzeta(t0, obj.xmin) +
                     logHzeta(t0 - hstep, obj.xmin)) /
                    (hstep * hstep);
  r.tau_err = d2 > 0 ? 1.0 / std::sqrt(static_cast<double>(r.n_tail) * d2) : std::nan("");
  r.valid = status == GSL_SUCCESS && std::isfinite(r.tau);
  // KS distance: the empirical CDF is a step function, the model CDF increases, so the largest
  // gap lies at a sample value or just below the next one.
  const double n = static_cast<double>(r.n_tail);
  const double lz = logHzeta(r.tau, obj.xmin);
  auto cdf = [&](std::uint64_t v) {
    return 1.0 - std::exp(logHzeta(r.tau, static_cast<double>(v + 1)) - lz);
  };
  double D = 0.0, below = 0.0;
  if (h[first].first > xmin) D = std::fabs(0.0 - cdf(h[first].first - 1));
  for (std::size_t k = first; k < h.size(); ++k) {
    below += static_cast<double>(h[k].second);
    const double emp = below / n;
    D = std::max(D, std::fabs(emp - cdf(h[k].first)));
    if (k + 1 < h.size() && h[k + 1].first > h[k].first + 1)
      D = std::max(D, std::fabs(emp - cdf(h[k + 1].first - 1)));
  }
  r.ks = D;
  return r;
}

PowerLawMleResult scanXmin(const Histogram& h, std::size_t min_tail) {
  PowerLawMleResult best;
  best.ks = std::numeric_limits<double>::infinity();
  std::uint64_t tail = 0;
  for (const auto& hc : h) tail += hc.second;
  for (std::size_t k = 0; k < h.size(); ++k) {
    if (tail < std::max<std::uint64_t>(min_tail, 2)) break;
    if (h[k].first >= 1) {
      const PowerLawMleResult r = fitTail(h, k, h[k].first);
      if (r.valid && r.ks < best.ks) best = r;
    }
    tail -= h[k].second;
  }
  if (!best.valid) best = PowerLawMleResult{};
  return best;
}

}  // namespace

PowerLawMleResult fitDiscretePowerLaw(const std::vector<std::uint64_t>& samples,
                                      std::uint64_t xmin) {
  const Histogram h = histogramOf(samples);
  std::size_t first = 0;
  while (first < h.size() && h[first].first < xmin) ++first;
  return fitTail(h, first, xmin);
}

PowerLawMleResult fitDiscretePowerLawKs(const std::vector<std::uint64_t>& samples,
                                        std::size_t min_tail) {
  return scanXmin(histogramOf(samples), min_tail);
}

PowerLawMleResult fitDiscretePowerLawKs(const std::map<std::uint64_t, std::uint64_t>& counts,
                                        std::size_t min_tail) {
  Histogram h;
  for (const auto& [v, c] : counts)
    if (c > 0) h.emplace_back(v, c);
  return scanXmin(h, min_tail);
}

}  // namespace granagg::analysis
