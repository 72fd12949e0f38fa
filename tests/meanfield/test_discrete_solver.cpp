// Discrete Smoluchowski solver (CVODE + FFT right-hand side) against the exact solutions of the
// classic kernels from n_k(0) = delta_k1 (docs/model.md section 12; Leyvraz 2003, Phys. Rep. 383,
// 95), plus mass conservation, truncation detection and the growing size range.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <vector>

#include "meanfield/growth/GrowthExponent.h"
#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/DiscreteSolver.h"

using namespace granagg::meanfield;

namespace {
struct Exact {
  std::function<double(int k, double t)> n;
  std::function<double(double t)> M0, M2;
};

// constant K0 = 1, a = t/2: n_k = (1+a)^-2 (a/(1+a))^(k-1), M0 = 1/(1+a), M2 = 1 + t
Exact constantExact() {
  return {[](int k, double t) {
            const double a = t / 2;
            return std::pow(1 + a, -2.0) * std::pow(a / (1 + a), k - 1);
          },
          [](double t) { return 1.0 / (1.0 + t / 2); }, [](double t) { return 1.0 + t; }};
}
// additive i+j, T = 1 - e^-t: n_k = k^(k-1)/k! T^(k-1) e^-t e^(-kT), M0 = e^-t, M2 = e^(2t)
Exact additiveExact() {
  return {[](int k, double t) {
            const double T = 1 - std::exp(-t);
            return std::exp((k - 1) * std::log(double(k)) - std::lgamma(k + 1.0) +
                            (k - 1) * std::log(T) - t - k * T);
          },
          [](double t) { return std::exp(-t); }, [](double t) { return std::exp(2 * t); }};
}
// multiplicative ij, t < 1: n_k = k^(k-2)/k! t^(k-1) e^(-kt), M0 = 1 - t/2, M2 = 1/(1-t)
Exact multiplicativeExact() {
  return {[](int k, double t) {
            return std::exp((k - 2) * std::log(double(k)) - std::lgamma(k + 1.0) +
                            (k - 1) * std::log(t) - k * t);
          },
          [](double t) { return 1.0 - t / 2; }, [](double t) { return 1.0 / (1.0 - t); }};
}

void checkAgainstExact(const Kernel& kernel, const Exact& ex, const std::vector<double>& times,
                       int M, const std::string& integrator) {
  DiscreteOptions o;
  o.times = times;
  o.max_size = M;
  o.grow = false;  // fixed M, chosen so that the tail beyond M is below 1e-20 at the last time
  o.rtol = 1e-11;
  o.atol = 1e-18;
  o.integrator = integrator;
  o.snapshot_max_size = 20;
  const SmolResult r = solveDiscrete(kernel, o);
  REQUIRE(r.samples.size() == times.size());
  REQUIRE(r.stopped_early.empty());
  for (std::size_t i = 0; i < times.size(); ++i) {
    const double t = times[i];
    const auto& s = r.samples[i];
    INFO(kernel.name() << " with " << integrator << " at t = " << t);
    CHECK(s.valid);
    // Relative 1e-6 is the acceptance level; CVODE runs at rtol 1e-11 so its global error
    // (a few hundred steps) stays well below it.
    CHECK(s.M0 == Approx(ex.M0(t)).epsilon(1e-6));
    CHECK(s.M1 == Approx(1.0).epsilon(1e-6));
    CHECK(s.M2 == Approx(ex.M2(t)).epsilon(1e-6));
    for (int k = 1; k <= 20; ++k) {
      INFO("k = " << k);
      CHECK(r.snapshots[i].n[k - 1] == Approx(ex.n(k, t)).epsilon(1e-6));
    }
  }
}
}  // namespace

TEST_CASE("discrete solver reproduces the constant-kernel exact solution",
          "[meanfield][discrete]") {
  for (const char* integ : {"adams", "bdf"})
    checkAgainstExact(Kernel::constant(), constantExact(), {2, 10, 50}, 2048, integ);
}

TEST_CASE("discrete solver reproduces the additive-kernel exact solution",
          "[meanfield][discrete]") {
  checkAgainstExact(Kernel::additive(), additiveExact(), {0.25, 0.5, 1.0, 1.5}, 2048, "bdf");
}

TEST_CASE("discrete solver reproduces the multiplicative-kernel exact solution before gelation",
          "[meanfield][discrete][slow]") {
  checkAgainstExact(Kernel::multiplicative(), multiplicativeExact(), {0.2, 0.5, 0.7, 0.8}, 2048,
                    "bdf");
  checkAgainstExact(Kernel::multiplicative(), multiplicativeExact(), {0.2, 0.5}, 300, "bdf-dense");
}

TEST_CASE("growing range conserves mass and reaches large S for the beta kernel",
          "[meanfield][discrete]") {
  DiscreteOptions o;
  o.times = logSpacedTimes(0.01, 1e5, 141);
  o.s_end = 2000;
  const SmolResult r = solveDiscrete(Kernel::beta(2.0), o);
  REQUIRE(r.stopped_early.empty());
  REQUIRE(r.samples.back().S >= 2000);
  CHECK(r.stats.resizes > 0);
  double worst = 0.0;
  for (const auto& s : r.samples) worst = std::max(worst, std::fabs(s.mass_loss));
  // Adams with fixed-point iteration preserves the linear invariant M1 up to round-off.
  CHECK(worst < 1e-10);
  // the local slope is on its way to 6/5 (about 1.19 near S ~ 250-2000, docs/model.md section 12)
  std::vector<double> t, S;
  for (const auto& s : r.samples) {
    t.push_back(s.t);
    S.push_back(s.S);
  }
  const auto ls = localSlope(t, S, 2.0);
  CHECK(ls.z.back() == Approx(1.19).margin(0.01));
}

TEST_CASE("truncation is detected and never reported as valid", "[meanfield][discrete]") {
  DiscreteOptions o;
  o.times = logSpacedTimes(0.1, 1e4, 41);
  o.max_size = 100;  // far too small for S ~ 1e2..1e3
  const SmolResult r = solveDiscrete(Kernel::beta(3.0), o);
  REQUIRE_FALSE(r.stopped_early.empty());
  CHECK(r.stop_cause == StopCause::Truncation);
  CHECK_THAT(r.stopped_early, Catch::Contains("M = 100 (the largest allowed)"));
  CHECK_FALSE(r.samples.back().valid);
  CHECK(r.samples.back().mass_loss > o.mass_loss_tolerance);
  for (std::size_t i = 0; i + 1 < r.samples.size(); ++i) CHECK(r.samples[i].valid);

  o.stop_on_truncation = false;  // marks and continues
  const SmolResult r2 = solveDiscrete(Kernel::beta(3.0), o);
  CHECK(r2.samples.size() == o.times.size());
  CHECK_FALSE(r2.samples.back().valid);
}

TEST_CASE("discrete solver rejects bad options", "[meanfield][discrete]") {
  DiscreteOptions o;
  CHECK_THROWS_WITH(solveDiscrete(Kernel::constant(), o), Catch::Contains("output time"));
  o.times = {1.0, 0.5};
  CHECK_THROWS_WITH(solveDiscrete(Kernel::constant(), o), Catch::Contains("increase strictly"));
  o.times = {1.0};
  o.max_size = 1;
  CHECK_THROWS_WITH(solveDiscrete(Kernel::constant(), o), Catch::Contains("at least 2"));
  o.max_size = 100;
  o.integrator = "rk4";
  CHECK_THROWS_AS(solveDiscrete(Kernel::constant(), o), std::invalid_argument);
}
