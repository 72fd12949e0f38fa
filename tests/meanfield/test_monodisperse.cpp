// Monodisperse approximation di/dt = K(i, i) (docs/model.md section 12): Boost.Odeint solution
// against the closed form, and its growth exponent z = 3 beta / (beta + 3).
#include <catch2/catch.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/MonodisperseSolver.h"
#include "meanfield/solvers/SmolResult.h"

using namespace granagg::meanfield;

TEST_CASE("monodisperse closed form against hand-derived solutions", "[meanfield][mono]") {
  // Independent of Kernel(1, 1): c and lambda written out by hand.
  // beta kernel: K(i, i) = K0 (2 i^{1/3})^2 (2/i)^{1/beta} = 4 K0 2^{1/beta} i^{2/3 - 1/beta}.
  for (double beta : {2.0, 3.0}) {
    const double c = 4.0 * std::pow(2.0, 1.0 / beta), lambda = 2.0 / 3.0 - 1.0 / beta;
    for (double t : {0.0, 0.3, 10.0, 1e6}) {
      const double expected = std::pow(1.0 + (1.0 - lambda) * c * t, 1.0 / (1.0 - lambda));
      CHECK(monodisperseMeanSize(Kernel::beta(beta), t) == Approx(expected).epsilon(1e-13));
    }
  }
  // constant: di/dt = K0 -> i = 1 + K0 t; additive: di/dt = 2 K0 i -> e^{2 K0 t};
  // multiplicative: di/dt = K0 i^2 -> 1 / (1 - K0 t), blowing up at t = 1/K0.
  CHECK(monodisperseMeanSize(Kernel::constant(2.0), 3.0) == Approx(7.0).epsilon(1e-14));
  CHECK(monodisperseMeanSize(Kernel::additive(), 1.5) == Approx(std::exp(3.0)).epsilon(1e-14));
  CHECK(monodisperseMeanSize(Kernel::multiplicative(), 0.75) == Approx(4.0).epsilon(1e-13));
  CHECK(monodisperseBlowUpTime(Kernel::multiplicative(2.0)) == Approx(0.5).epsilon(1e-15));
  CHECK(std::isinf(monodisperseBlowUpTime(Kernel::beta(2.0))));
  // a later start: i0 = 8 under the constant kernel
  CHECK(monodisperseMeanSize(Kernel::constant(), 2.0, 8.0) == Approx(10.0).epsilon(1e-14));
}

TEST_CASE("monodisperse Odeint solution matches the closed form", "[meanfield][mono]") {
  // Odeint (RKF78, rtol = atol = 1e-12 on ln i) over 13 decades of time: the accumulated error in
  // ln i stays ~1e-11, so a relative 1e-8 on i has three orders of margin.
  MonodisperseOptions o;
  o.times = logSpacedTimes(1e-3, 1e10, 27);
  for (double beta : {2.0, 2.5, 3.0, 4.0}) {
    const Kernel K = Kernel::beta(beta);
    const SmolResult r = solveMonodisperse(K, o);
    REQUIRE(r.samples.size() == o.times.size());
    CHECK(r.method == "mono");
    CHECK(r.stopped_early.empty());
    for (const MomentSample& s : r.samples) {
      INFO("beta = " << beta << ", t = " << s.t);
      CHECK(s.S == Approx(monodisperseMeanSize(K, s.t)).epsilon(1e-8));
      CHECK(s.M1 == 1.0);
      CHECK(s.M0 == Approx(1.0 / s.S).epsilon(1e-15));
      CHECK(s.M2 == s.S);
      CHECK(s.valid);
    }
  }
  MonodisperseOptions g;
  g.times = {0.1, 0.5, 0.9, 0.99};
  const SmolResult mult = solveMonodisperse(Kernel::multiplicative(), g);
  for (const MomentSample& s : mult.samples) CHECK(s.S == Approx(1.0 / (1.0 - s.t)).epsilon(1e-8));
  g.times = {0.1, 1.0, 5.0};
  const SmolResult add = solveMonodisperse(Kernel::additive(), g);
  for (const MomentSample& s : add.samples) CHECK(s.S == Approx(std::exp(2.0 * s.t)).epsilon(1e-8));
}

TEST_CASE("monodisperse growth exponent is 3 beta / (beta + 3)", "[meanfield][mono]") {
  // The local slope is d ln i / d ln t = z t / (t + t0) exactly, with t0 = 1 / ((1 - lambda) c)
  // ~ 0.2 (header). Two estimates from the numerical solution:
  // (a) the finite-difference slope log[i(t)/i(t/2)] / log 2 at t = 1e12, where z t0 / t < 1e-12;
  // (b) an extrapolation from early times: 1/z(t) = 1/z + t0 / (z t) is linear in 1/t, so the
  //     exact slope z(t) = t K(i, i) / i at t = 10 and 100 (still 2e-2 and 2e-3 from z) gives
  //     z by a straight line through two points.
  for (double beta : {2.0, 3.0}) {
    const Kernel K = Kernel::beta(beta);
    const double z_exact = 3.0 * beta / (beta + 3.0);
    MonodisperseOptions o;
    o.times = {10.0, 100.0, 5e11, 1e12};
    const SmolResult r = solveMonodisperse(K, o);
    const auto& s = r.samples;
    const double z_late = std::log(s[3].S / s[2].S) / std::log(2.0);
    CHECK(std::fabs(z_late - z_exact) < 1e-6);
    const double z10 = 10.0 * K(s[0].S, s[0].S) / s[0].S;
    const double z100 = 100.0 * K(s[1].S, s[1].S) / s[1].S;
    CHECK(std::fabs(z100 - z_exact) > 1e-4);  // not yet converged: the extrapolation does the work
    // 1/z(t) = A + B / t through (1/10, 1/z10) and (1/100, 1/z100); z = 1/A
    const double B = (1.0 / z10 - 1.0 / z100) / (0.1 - 0.01);
    const double A = 1.0 / z100 - B * 0.01;
    CHECK(std::fabs(1.0 / A - z_exact) < 1e-6);
    CHECK(K.scalingExponent() == Approx(z_exact).epsilon(1e-14));
  }
}

TEST_CASE("monodisperse solver stops at s_end", "[meanfield][mono]") {
  MonodisperseOptions o;
  o.times = logSpacedTimes(1.0, 1e8, 9);
  o.s_end = 1e3;
  const SmolResult r = solveMonodisperse(Kernel::beta(3.0), o);
  REQUIRE(!r.samples.empty());
  CHECK(r.samples.back().S >= 1e3);
  CHECK(r.samples[r.samples.size() - 2].S < 1e3);
  CHECK(r.samples.size() < o.times.size());
}

TEST_CASE("monodisperse solver rejects bad input", "[meanfield][mono]") {
  const Kernel K = Kernel::beta(2.0);
  MonodisperseOptions o;
  CHECK_THROWS_AS(solveMonodisperse(K, o), std::invalid_argument);  // no times
  o.times = {1.0, 1.0};
  CHECK_THROWS_WITH(solveMonodisperse(K, o), Catch::Contains("increase strictly"));
  o.times = {-1.0, 1.0};
  CHECK_THROWS_WITH(solveMonodisperse(K, o), Catch::Contains("positive"));
  o.times = {1.0};
  o.initial_size = 0.0;
  CHECK_THROWS_WITH(solveMonodisperse(K, o), Catch::Contains("initial_size"));
  o.initial_size = 1.0;
  o.rtol = 0.0;
  CHECK_THROWS_WITH(solveMonodisperse(K, o), Catch::Contains("rtol"));
  o.rtol = 1e-10;
  o.times = {0.5, 1.0};
  CHECK_THROWS_WITH(solveMonodisperse(Kernel::multiplicative(), o), Catch::Contains("blow-up"));
  CHECK_THROWS_AS(monodisperseMeanSize(K, -1.0), std::invalid_argument);
  CHECK_THROWS_AS(monodisperseMeanSize(Kernel::multiplicative(), 1.0), std::invalid_argument);
  CHECK_THROWS_AS(monodisperseMeanSize(K, 1.0, -2.0), std::invalid_argument);
}
