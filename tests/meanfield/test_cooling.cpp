// Homogeneous cooling (meanfield/kinetic/Cooling.h): Haff's law against an independent Odeint
// integration of its ODE, the velocity-dependent cooling equation against Haff's law and exact
// moments, the viscoelastic t^{-5/3} asymptote and the small-damping closed form.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <boost/numeric/odeint.hpp>

#include "meanfield/kinetic/Cooling.h"

using namespace granagg::meanfield;

namespace {
std::vector<double> logTimes(double t_min, double t_max, int count) {
  std::vector<double> t{0.0};
  for (int k = 0; k < count; ++k) t.push_back(t_min * std::pow(t_max / t_min, k / (count - 1.0)));
  return t;
}
}  // namespace

TEST_CASE("Haff's law equals an independent integration of its ODE",
          "[meanfield][kinetic][cooling]") {
  // dT/dt = -(1 - eps^2) omega0 T^{3/2} / 3 with Runge-Kutta-Fehlberg 7(8) in plain t at
  // tolerance 1e-13: its error is ~1e-12 relative, so 1e-9 is a safe bound that still tests
  // the closed form far beyond plotting accuracy.
  namespace odeint = boost::numeric::odeint;
  for (double eps : {0.9, 0.5}) {
    const double omega0 = enskogCollisionFrequency(0.076, 1.0);
    using State = std::array<double, 1>;
    auto rhs = [&](const State& T, State& dT, double) {
      dT[0] = -(1.0 - eps * eps) * omega0 * std::pow(T[0], 1.5) / 3.0;
    };
    State T{1.0};
    double t = 0.0;
    for (double tout : {0.5, 3.0, 30.0, 1000.0}) {
      odeint::integrate_adaptive(
          odeint::make_controlled(1e-13, 1e-13, odeint::runge_kutta_fehlberg78<State>()), rhs, T, t,
          tout, 1e-3);
      t = tout;
      CHECK(T[0] == Approx(haffTemperature(tout, eps, 0.076)).epsilon(1e-9));
    }
  }
}

TEST_CASE("velocity-dependent cooling with constant restitution reduces to Haff's law",
          "[meanfield][kinetic][cooling]") {
  // Exact reduction (derivation in Cooling.cpp); what remains is the ODE error. rtol = 1e-12 on
  // ln T gives ~1e-10 (measured), so 1e-8 as asked.
  CoolingOptions o;
  o.rtol = 1e-12;
  o.atol = 1e-14;
  const auto t = logTimes(1e-2, 1e6, 25);
  for (double eps : {0.9, 0.3}) {
    const auto r = solveCooling([eps](double) { return eps; }, t, o);
    REQUIRE(r.size() == t.size());
    for (const auto& s : r) {
      CHECK(s.T == Approx(haffTemperature(s.t, eps, 0.076)).epsilon(1e-8));
      CHECK(s.loss == Approx(1.0 - eps * eps).epsilon(1e-12));
    }
    // Haff's local slope -2 t/(t + tau0) -> -2.
    CHECK(r.back().slope == Approx(-2.0).epsilon(0).margin(1e-3));
  }
}

TEST_CASE("energy loss average weights impact speeds with P(g) = g/(2T) exp(-g^2/4T)",
          "[meanfield][kinetic][cooling]") {
  // e(g)^2 = 1 - k g^p gives L = k <g^{2+p}> / (4T) = k (4T)^{p/2} Gamma(2 + p/2) exactly; with
  // p = 1/5 this is the first-order viscoelastic loss. k g^p < 1 up to the cut g = 20 sqrt(T).
  // The quadrature runs at 1e-12; bound 1e-10. (L >= 1e-4 here: forming 1 - e^2 from e costs
  // 1e-16 / L in relative precision.)
  const double k = 0.002;
  for (double p : {0.2, 1.0, 2.0}) {
    for (double T : {1.0, 1e-2}) {
      const auto e = [k, p](double g) {
        return std::sqrt(std::max(0.0, 1.0 - k * std::pow(g, p)));
      };
      CHECK(energyLossFactor(e, T) ==
            Approx(k * std::pow(4.0 * T, p / 2.0) * std::tgamma(2.0 + p / 2.0)).epsilon(1e-10));
    }
  }
  // dT/dt = -omega T L / 3.
  CHECK(coolingRate([](double) { return 0.9; }, 0.076, 1.0) ==
        Approx(-0.19 * enskogCollisionFrequency(0.076, 1.0) / 3.0).epsilon(1e-12));
}

TEST_CASE("viscoelastic cooling approaches T ~ t^{-5/3}", "[meanfield][kinetic][cooling]") {
  // Defaults (E = 278.6, D = 27.7, clamped). The local slope first overshoots towards Haff's -2
  // (strong damping: L ~ 0.9 at T = 1) and then relaxes to -5/3 from below with corrections of
  // order T^{1/10} ~ t^{-1/6}: measured -1.843 at t ~ 630, -1.672 at t = 1e12, -1.6669 at 1e20.
  const auto r = solveViscoelasticCooling(ContactParams{}, {0.0, 1e3, 1e12, 1e20});
  CHECK(r[1].slope < -1.8);                                         // MD times: far from -5/3
  CHECK(r[2].slope == Approx(-5.0 / 3.0).epsilon(0).margin(0.01));  // within 0.01 at t = 1e12
  CHECK(r[3].slope == Approx(-5.0 / 3.0).epsilon(0).margin(1e-3));  // within 1e-3 at t = 1e20
  CHECK(r[3].slope < -5.0 / 3.0);                                   // approached from below
  // The late-time asymptote T0 (t/tau0')^{-5/3} is exact (e -> 1 as T -> 0); at t = 1e20 the
  // relative correction ~t^{-1/6} is 1e-3 (measured 5e-4).
  const double tau = viscoelasticCoolingTau0(ContactParams{}, 0.076);
  CHECK(r[3].T == Approx(std::pow(1e20 / tau, -5.0 / 3.0)).epsilon(2e-3));
}

TEST_CASE("small-damping closed form agrees with the viscoelastic cooling ODE to first order",
          "[meanfield][kinetic][cooling]") {
  // T0 (1 + t/tau0')^{-5/3} is first order in delta = C1 b1 T0^{1/10}, so its largest relative
  // deviation from the ODE should be O(delta) and fall ~10x when D falls 10x. Measured: 2.3e-2
  // at D/100 (delta = 0.014), 2.1e-3 at D/1000; bounds 1.5x the measurements.
  const auto t = logTimes(1.0, 1e12, 13);
  double deviation[2];
  int k = 0;
  for (double f : {0.01, 0.001}) {
    ContactParams p;
    p.D *= f;
    const auto r = solveViscoelasticCooling(p, t);
    double worst = 0.0;
    for (const auto& s : r)
      worst = std::max(worst, std::fabs(s.T / viscoelasticCoolingTemperature(s.t, p, 0.076) - 1.0));
    deviation[k++] = worst;
  }
  CHECK(deviation[0] < 3.5e-2);
  CHECK(deviation[1] < 3.5e-3);
  CHECK(deviation[0] / deviation[1] == Approx(10.0).epsilon(0).margin(3.0));
  // At the defaults the closed form is far off at intermediate times (delta = 1.4).
  const auto r = solveViscoelasticCooling(ContactParams{}, {10.0});
  CHECK(std::fabs(r[0].T / viscoelasticCoolingTemperature(10.0, ContactParams{}, 0.076) - 1.0) >
        1.0);
}

TEST_CASE("cooling rejects bad parameters", "[meanfield][kinetic][cooling]") {
  const auto e = [](double) { return 0.9; };
  CHECK_THROWS_AS(solveCooling(e, {-1.0}), std::invalid_argument);
  CHECK_THROWS_AS(solveCooling(e, {2.0, 1.0}), std::invalid_argument);
  CoolingOptions o;
  o.phi = 0.8;
  CHECK_THROWS_AS(solveCooling(e, {1.0}, o), std::invalid_argument);
  o = CoolingOptions{};
  o.T0 = 0.0;
  CHECK_THROWS_AS(solveCooling(e, {1.0}, o), std::invalid_argument);
  CHECK_THROWS_AS(solveCooling(RestitutionFunction{}, {1.0}), std::invalid_argument);
  CHECK_THROWS_AS(energyLossFactor(e, -1.0), std::invalid_argument);
  ContactParams p;
  p.D = 0.0;
  CHECK_THROWS_AS(viscoelasticCoolingTau0(p, 0.076), std::invalid_argument);
  CHECK_THROWS_AS(viscoelasticCoolingTemperature(-1.0, ContactParams{}, 0.076),
                  std::invalid_argument);
  // A restitution function that throws propagates its exception through the quadrature.
  CHECK_THROWS_AS(energyLossFactor([](double) -> double { throw std::invalid_argument("x"); }, 1.0),
                  std::invalid_argument);
}
