// common/Statistics.h, against closed forms: least squares by hand, Student-t quantiles from
// tables, the bootstrap interval rule written out, and the local slope of exact power laws.
#include <catch2/catch.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "common/Statistics.h"

using namespace granagg::common::stats;

TEST_CASE("fitLine matches least squares by hand, with the slope's error from the scatter",
          "[common][stats]") {
  const std::vector<double> x{1, 2, 3, 4, 5}, y{2.1, 3.9, 6.2, 7.8, 10.1};
  const LineFit f = fitLine(x, y);
  // Sxx = 10, Sxy = 19.9, slope 1.99, intercept 6.02 - 1.99 * 3 = 0.05
  CHECK(f.slope == Approx(1.99).epsilon(1e-12));
  CHECK(f.intercept == Approx(0.05).epsilon(1e-9));
  double ssr = 0;
  for (std::size_t i = 0; i < x.size(); ++i) ssr += std::pow(y[i] - 0.05 - 1.99 * x[i], 2);
  CHECK(f.sumsq == Approx(ssr).epsilon(1e-9));
  CHECK(f.slope_se == Approx(std::sqrt(ssr / 3.0 / 10.0)).epsilon(1e-9));
  CHECK(f.n == 5);
  CHECK(std::isnan(fitLine({1, 2}, {1, 3}).slope_se));  // 2 points: no scatter to speak of
  CHECK_THROWS_AS(fitLine({1}, {1}), std::invalid_argument);
  CHECK_THROWS_AS(fitLine({1, 2}, {1}), std::invalid_argument);
}

TEST_CASE("Student-t half widths and the bootstrap interval rule", "[common][stats]") {
  // t_{0.975} for 1, 4 and 30 degrees of freedom (any table): 12.706, 2.776, 2.042
  CHECK(studentHalfWidth(1.0, 1, 0.95) == Approx(12.7062).epsilon(1e-5));
  CHECK(studentHalfWidth(2.0, 4, 0.95) == Approx(2 * 2.77645).epsilon(1e-5));
  CHECK(studentHalfWidth(1.0, 30, 0.95) == Approx(2.04227).epsilon(1e-5));
  CHECK(std::isnan(studentHalfWidth(1.0, 0, 0.95)));
  CHECK_THROWS_AS(studentHalfWidth(1.0, 4, 1.0), std::invalid_argument);
  // 5 runs: estimate -/+ t_{4, 0.975} sqrt(5/4) sd(replicates)
  const std::vector<double> reps{1.0, 1.2, 0.9, 1.1, 1.3, 0.8};
  double m = 0, v = 0;
  for (double r : reps) m += r / reps.size();
  for (double r : reps) v += (r - m) * (r - m) / (reps.size() - 1);
  const Interval in = bootstrapInterval(reps, 1.05, 5, 0.95);
  const double half = 2.77645 * std::sqrt(5.0 / 4.0) * std::sqrt(v);
  CHECK(in.low == Approx(1.05 - half).epsilon(1e-5));
  CHECK(in.high == Approx(1.05 + half).epsilon(1e-5));
  CHECK_THROWS_AS(bootstrapInterval(reps, 1.0, 1, 0.95), std::invalid_argument);
  CHECK(median({3, 1, 2}) == 2.0);
  CHECK(median({4, 1, 2, 3}) == 2.5);
}

TEST_CASE("the local slope of an exact power law is its exponent, NaN where undefined",
          "[common][stats]") {
  // irregular times: t / p falls between samples, so the (ln t, ln y) interpolation is used
  const std::vector<double> t{0.0, 0.3, 0.7, 1.0, 1.9, 2.0, 3.3, 4.1, 7.7, 10.0, 15.5, 31.0, 64.0};
  std::vector<double> y;
  for (double x : t) y.push_back(x > 0 ? 4.0 * std::pow(x, 1.37) : 0.0);
  const std::vector<double> z = localSlope(t, y, 2.0);
  CHECK(std::isnan(z[0]));  // t = 0
  CHECK(std::isnan(z[1]));  // t / p = 0.15 before the first positive time
  for (std::size_t k = 2; k < t.size(); ++k) {
    INFO("t = " << t[k]);
    CHECK(z[k] == Approx(1.37).epsilon(1e-12));
  }
  CHECK_THROWS_AS(localSlope(t, y, 1.0), std::invalid_argument);
}
