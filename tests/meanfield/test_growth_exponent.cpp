// Growth-exponent estimators against exact power laws and synthetic data with known spread.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "meanfield/growth/GrowthExponent.h"
#include "meanfield/solvers/SmolResult.h"

using namespace granagg::meanfield;

TEST_CASE("local slope and fit of an exact power law equal its exponent", "[meanfield][growth]") {
  const auto t = logSpacedTimes(0.1, 1e4, 61);
  std::vector<double> S;
  for (double x : t) S.push_back(3.7 * std::pow(x, 1.23));
  for (double p : {2.0, 10.0, 3.3}) {
    const auto ls = localSlope(t, S, p);
    REQUIRE(ls.t.size() > 10);
    for (double z : ls.z) CHECK(z == Approx(1.23).epsilon(1e-12));
  }
  const auto f = fitPowerLaw(t, S, 1.0, 1e3);
  CHECK(f.z == Approx(1.23).epsilon(1e-12));
  CHECK(f.prefactor == Approx(3.7).epsilon(1e-10));
  CHECK(f.z_high - f.z_low < 1e-10);
  CHECK(f.points == 37);  // 12 points per decade, 3 decades, both ends included
}

TEST_CASE("power-law fit interval covers the true exponent at its nominal rate",
          "[meanfield][growth]") {
  // Multiplicative log-normal noise (sigma = 0.05) on S = t^1.5: 200 independent fixed-seed
  // replicas; a 95 % interval should cover 1.5 in 95 % of them. Binomial spread for 200 trials is
  // sqrt(200 * 0.95 * 0.05) = 3.1, so 180..200 covered (more than 4 sigma wide) cannot fail by
  // chance, while a wrong standard error (e.g. off by 2x) would.
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> noise(0.0, 0.05);
  const auto t = logSpacedTimes(1.0, 1e3, 40);
  int covered = 0;
  for (int r = 0; r < 200; ++r) {
    std::vector<double> S;
    for (double x : t) S.push_back(std::pow(x, 1.5) * std::exp(noise(rng)));
    const auto f = fitPowerLaw(t, S, 1.0, 1e3);
    covered += (f.z_low <= 1.5 && 1.5 <= f.z_high);
  }
  CHECK(covered >= 180);
  CHECK(covered <= 200);
}

TEST_CASE("asymptotic exponent extrapolates z(t) = z t/(t+t0)", "[meanfield][growth]") {
  // S = (1 + t/t0)^z has the local slope z t / (t + t0): the 1/t extrapolation recovers z.
  const double z = 1.2, t0 = 50.0;
  const auto t = logSpacedTimes(1.0, 1e7, 141);
  std::vector<double> S;
  for (double x : t) S.push_back(std::pow(1.0 + x / t0, z));
  const auto a = asymptoticExponent(t, S, 2.0, 1e-4);
  CHECK(a.z == Approx(z).margin(1e-5));
  CHECK(a.converged);
  // stopping early (t_max = 1e3 ~ 20 t0) is correctly reported as not converged
  std::vector<double> t2, S2;
  for (std::size_t i = 0; i < t.size() && t[i] <= 1e3; ++i) {
    t2.push_back(t[i]);
    S2.push_back(S[i]);
  }
  CHECK_FALSE(asymptoticExponent(t2, S2, 2.0, 1e-4).converged);
}

TEST_CASE("growth estimators reject bad series", "[meanfield][growth]") {
  CHECK_THROWS_WITH(localSlope({1, 2, 2}, {1, 2, 3}), Catch::Contains("increase strictly"));
  CHECK_THROWS_WITH(localSlope({1, 2, 3}, {1, -2, 3}), Catch::Contains("S must be positive"));
  CHECK_THROWS_WITH(fitPowerLaw({1, 2, 3, 4}, {1, 2, 3, 4}, 3.0, 4.0),
                    Catch::Contains("at least 3 points"));
  CHECK_THROWS_AS(localSlope({1, 2, 3}, {1, 2, 3}, 1.0), std::invalid_argument);
}
