// Fisher exponent (discrete power-law MLE, Clauset et al. 2009) on synthetic samples; growth
// exponent fits, bootstrap and local slopes on exact power laws.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include <gsl/gsl_sf_zeta.h>

#include "analysis/stats/PowerLawFit.h"
#include "analysis/stats/PowerLawMle.h"

using namespace granagg::analysis;

namespace {

/// Exact inverse-CDF sample of p(x) = x^-tau / zeta(tau, xmin): the smallest x with
/// P(X > x) = zeta(tau, x+1)/zeta(tau, xmin) < u, found by doubling then bisection.
std::vector<std::uint64_t> samplePowerLaw(double tau, std::uint64_t xmin, std::size_t n,
                                          std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double z0 = gsl_sf_hzeta(tau, static_cast<double>(xmin));
  auto tailAbove = [&](std::uint64_t x) {
    return gsl_sf_hzeta(tau, static_cast<double>(x + 1)) / z0;
  };
  std::vector<std::uint64_t> out(n);
  for (auto& x : out) {
    double u = U(rng);
    while (u <= 0.0) u = U(rng);
    std::uint64_t lo = xmin, hi = xmin;
    while (tailAbove(hi) >= u) {
      lo = hi;
      hi = hi * 2;
    }
    // invariant: tailAbove(hi) < u; answer in [lo, hi]
    if (tailAbove(lo) < u) {
      x = lo;
      continue;
    }
    while (hi - lo > 1) {
      const std::uint64_t mid = lo + (hi - lo) / 2;
      (tailAbove(mid) < u ? hi : lo) = mid;
    }
    x = hi;
  }
  return out;
}

}  // namespace

TEST_CASE("the sampler reproduces the discrete power law's probabilities", "[analysis][mle]") {
  // P(X = 1) = 1/zeta(2.5) for xmin = 1; 20000 samples: binomial sd 0.0035
  const auto s = samplePowerLaw(2.5, 1, 20000, 5);
  double ones = 0;
  for (auto x : s) ones += (x == 1);
  CHECK(ones / 20000 == Approx(1.0 / gsl_sf_hzeta(2.5, 1.0)).margin(4 * 0.0035));
}

TEST_CASE("the MLE recovers tau from synthetic discrete power-law samples within its interval",
          "[analysis][mle]") {
  // n = 3000 tail samples give sigma ~ (tau - 1)/sqrt(n) ~ 0.01-0.04. We require |tau_hat - tau| <
  // 3 sigma: the MLE is asymptotically normal, so a correct estimator fails a case with probability
  // 0.3 %; the seeds are fixed, so the outcome is deterministic.
  std::uint64_t seed = 100;
  for (double tau : {1.6, 2.0, 2.5, 3.2}) {
    for (std::uint64_t xmin : {1u, 3u}) {
      INFO("tau = " << tau << ", xmin = " << xmin);
      const auto s = samplePowerLaw(tau, xmin, 3000, ++seed);
      const PowerLawMleResult fixed = fitDiscretePowerLaw(s, xmin);
      REQUIRE(fixed.valid);
      CHECK(fixed.n_tail == 3000);
      CHECK(std::fabs(fixed.tau - tau) < 3 * fixed.tau_err);
      // the Fisher-information error is close to the asymptotic (tau - 1)/sqrt(n) scale
      CHECK(fixed.tau_err > 0.3 * (tau - 1) / std::sqrt(3000.0));
      CHECK(fixed.tau_err < 3.0 * (tau - 1) / std::sqrt(3000.0));
      // with xmin chosen by the KS distance (fewer tail samples, so a wider interval)
      const PowerLawMleResult ks = fitDiscretePowerLawKs(s, 50);
      REQUIRE(ks.valid);
      CHECK(ks.xmin >= xmin);
      CHECK(std::fabs(ks.tau - tau) < 3 * ks.tau_err);
      CHECK(ks.ks < 0.05);
    }
  }
}

TEST_CASE("the KS choice of xmin finds where a power-law tail starts", "[analysis][mle]") {
  // Below 8: a flat body (uniform on 1..7); from 8 on: a tau = 2.2 power law.
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> body(1, 7);
  auto tail = samplePowerLaw(2.2, 8, 4000, 12);
  std::vector<std::uint64_t> s = tail;
  for (int k = 0; k < 4000; ++k) s.push_back(static_cast<std::uint64_t>(body(rng)));
  const PowerLawMleResult r = fitDiscretePowerLawKs(s, 50);
  REQUIRE(r.valid);
  CHECK(r.xmin >= 6);
  CHECK(r.xmin <= 12);
  CHECK(std::fabs(r.tau - 2.2) < 3 * r.tau_err);
  // the histogram overload gives the same answer
  std::map<std::uint64_t, std::uint64_t> counts;
  for (auto x : s) ++counts[x];
  const PowerLawMleResult h = fitDiscretePowerLawKs(counts, 50);
  CHECK(h.tau == r.tau);
  CHECK(h.xmin == r.xmin);
}

TEST_CASE("the MLE declines degenerate samples", "[analysis][mle]") {
  CHECK_FALSE(fitDiscretePowerLaw({}, 1).valid);
  CHECK_FALSE(fitDiscretePowerLaw({4, 4, 4, 4}, 1).valid);  // one value: no maximum in tau
  CHECK_FALSE(
      fitDiscretePowerLawKs(std::vector<std::uint64_t>{1, 2, 3}, 10).valid);  // tail below min_tail
  CHECK(discretePowerLawCcdf(2.0, 1, 1) == 1.0);
  CHECK(discretePowerLawCcdf(2.0, 1, 2) == Approx(1.0 - 6.0 / (M_PI * M_PI)).epsilon(1e-12));
}

TEST_CASE("power-law fit of an exact power law returns its exponent with a zero-width interval",
          "[analysis][fit]") {
  std::vector<double> t, y;
  for (int k = 0; k <= 40; ++k) {
    t.push_back(std::pow(10.0, -1 + 3.0 * k / 40));
    y.push_back(2.5 * std::pow(t.back(), 1.2));
  }
  const PowerLawFitResult f = fitPowerLaw(t, y, 1.0, 100.0);
  REQUIRE(f.valid);
  CHECK(f.exponent == Approx(1.2).epsilon(1e-12));
  CHECK(f.amplitude == Approx(2.5).epsilon(1e-10));
  CHECK(f.high - f.low < 1e-10);
  CHECK(f.points == 27);  // t_k = 10^(-1 + 3k/40) lies in [1, 100] for k = 14..40
}

TEST_CASE("a series that does not change has no growth exponent, not z = 0 +- 0",
          "[analysis][fit]") {
  // S_grid = 1 at every frame (no aggregation): least squares would give z = 0 [0, 0], an
  // interval of zero width from zero residuals, a certainty the data do not carry.
  const std::vector<double> t{1, 2, 3, 4, 5, 6}, one(6, 1.0);
  const PowerLawFitResult f = fitPowerLaw(t, one, 0, 10);
  CHECK_FALSE(f.valid);
  CHECK(f.constant);
  CHECK(f.points == 6);
  const PowerLawFitResult b = bootstrapPowerLaw(t, {one, one, one}, 0, 10, 100, 1);
  CHECK_FALSE(b.valid);
  CHECK(b.constant);
  // a change anywhere in the window is a series to fit
  std::vector<double> step = one;
  step.back() = 1.5;
  CHECK(fitPowerLaw(t, step, 0, 10).valid);
  CHECK_FALSE(fitPowerLaw(t, step, 0, 10).constant);
}

TEST_CASE("the fit's 95 % interval uses the Student t quantile", "[analysis][fit]") {
  // y = t^1 * exp(e) with residuals e = +-0.1 alternating: slope 1 exactly in expectation
  std::vector<double> t{1, 2, 3, 4, 5}, y;
  for (std::size_t k = 0; k < t.size(); ++k) y.push_back(t[k] * std::exp(k % 2 ? 0.1 : -0.1));
  const PowerLawFitResult f = fitPowerLaw(t, y, 0, 10);
  REQUIRE(f.valid);
  // t_{3, 0.975} = 3.182446305
  CHECK((f.high - f.exponent) / f.stderr_z == Approx(3.182446305).epsilon(1e-8));
  CHECK_THROWS_AS(fitPowerLaw(t, y, 0, 10, 1.5), std::invalid_argument);
  CHECK_FALSE(fitPowerLaw({1, 2}, {1, 2}, 0, 10).valid);
}

TEST_CASE("bootstrap over runs of exact power laws is exact, with noise it is reproducible",
          "[analysis][fit]") {
  std::vector<double> t;
  for (int k = 1; k <= 20; ++k) t.push_back(k * 5.0);
  std::vector<std::vector<double>> runs;
  for (double A : {0.5, 1.0, 2.0, 3.0}) {
    std::vector<double> y;
    for (double x : t) y.push_back(A * std::pow(x, 0.8));
    runs.push_back(y);
  }
  const PowerLawFitResult b = bootstrapPowerLaw(t, runs, 10, 100, 200, 1);
  CHECK(b.exponent == Approx(0.8).epsilon(1e-12));
  CHECK(b.low == Approx(0.8).epsilon(1e-12));
  CHECK(b.high == Approx(0.8).epsilon(1e-12));

  std::mt19937_64 rng(3);
  std::normal_distribution<double> G(0.0, 0.05);
  for (auto& r : runs)
    for (auto& y : r) y *= std::exp(G(rng));
  const PowerLawFitResult b1 = bootstrapPowerLaw(t, runs, 10, 100, 500, 42);
  const PowerLawFitResult b2 = bootstrapPowerLaw(t, runs, 10, 100, 500, 42);
  CHECK(b1.low == b2.low);
  CHECK(b1.high == b2.high);
  CHECK(b1.low < b1.exponent);
  CHECK(b1.exponent < b1.high);
  CHECK_THROWS_AS(bootstrapPowerLaw(t, {runs[0]}, 10, 100), std::invalid_argument);
}

TEST_CASE("the local slope of an exact power law equals its exponent", "[analysis][fit]") {
  // irregular times: t/p falls between samples, so the log-log interpolation is exercised
  std::vector<double> t{0.0, 0.3, 0.7, 1.0, 1.9, 2.0, 3.3, 4.1, 7.7, 10.0, 15.5, 31.0, 64.0};
  std::vector<double> y;
  for (double x : t) y.push_back(x > 0 ? 4.0 * std::pow(x, 1.37) : 0.0);
  for (double p : {2.0, 3.0, 1.5}) {
    const auto z = localSlope(t, y, p);
    for (std::size_t k = 0; k < t.size(); ++k) {
      INFO("t = " << t[k] << ", p = " << p);
      if (t[k] / p >= 0.3)
        CHECK(z[k] == Approx(1.37).epsilon(1e-12));
      else
        CHECK(std::isnan(z[k]));
    }
  }
  CHECK_THROWS_AS(localSlope(t, y, 1.0), std::invalid_argument);
}
