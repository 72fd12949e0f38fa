// Homogeneous cooling of the MD gas against kinetic theory (meanfield/kinetic), fixed seeds.
//
// Two clocks. In time t, kinetic theory assumes the Enskog collision frequency of hard spheres.
// Soft spheres spend a fraction ~ omega t_c of their time in contact, and collide less often by
// about that fraction: 4 % for the spring-dashpot at k = 5000 (t_c = 0.031), 12 % for the paper's
// Hertz parameters (t_c ~ 0.3, 0.23 contacts per particle measured at T ~ 1). In collision time
// tau = collisions per particle, the energy lost per collision alone sets dT/dtau, and kinetic
// theory applies without that correction: dT/dtau = -(1/12) <g^2 (1 - e(g)^2)> = -T L(T) / 3.
#include <catch2/catch.hpp>

#include <boost/numeric/odeint.hpp>

#include <cmath>
#include <vector>

#include "md/config/MdConfig.h"
#include "md/engine/Engine.h"
#include "md/io/InitialState.h"
#include "meanfield/kinetic/Cooling.h"
#include "meanfield/kinetic/Restitution.h"

using namespace granagg;
using namespace granagg::md;

namespace {
struct Sample {
  double t, T, tau;
  double contacts;  // contacts per particle in progress
};
/// T_g and collisions per particle of an MD run at `times`.
std::vector<Sample> mdCooling(const MdConfig& c, const std::vector<double>& times) {
  Engine e(c, randomInitialState(c));
  std::vector<Sample> out;
  for (double t : times) {
    e.run(static_cast<std::int64_t>(std::llround(t / e.dt())) - e.step());
    const auto o = e.observables();
    out.push_back(
        {o.time, o.temperature, 2.0 * o.collisions / c.system.N, o.contacts_per_particle});
  }
  return out;
}

/// Kinetic theory in collision time: T(tau) from dT/dtau = -T L(T)/3 (Boost.Odeint).
double temperatureAtCollisions(const meanfield::RestitutionFunction& e, double tau) {
  using namespace boost::numeric::odeint;
  std::vector<double> T{1.0};
  integrate_adaptive(
      make_controlled<runge_kutta_dopri5<std::vector<double>>>(1e-10, 1e-10),
      [&](const std::vector<double>& y, std::vector<double>& dy, double) {
        dy[0] = -y[0] * meanfield::energyLossFactor(e, y[0], 1e-10) / 3.0;
      },
      T, 0.0, tau, 0.01);
  return T[0];
}
}  // namespace

TEST_CASE("constant-restitution gas follows Haff's law while homogeneous", "[md][cooling]") {
  // Spring-dashpot eps = 0.9, N = 2000, phi = 0.076. Haff: 1/tau0 = (1 - eps^2) omega0 / 6 with
  // the Enskog omega0 = 1.25490; in collision time T = exp(-(1 - eps^2) tau / 3) exactly.
  // Statistical spread of T_g for N = 2000: sqrt(2/(3N)) = 1.8 % (one sigma, instantaneous);
  // the Sonine correction for eps = 0.9 is a2 = -0.015 and changes the rate by 0.3 %.
  MdConfig c;
  c.system.N = 2000;
  c.system.seed = 21;
  c.contact.model = "spring_dashpot";
  c.contact.restitution = 0.9;
  c.contact.stiffness = 5000;
  c.contact.clamp = false;
  const auto s = mdCooling(c, {2.0, 5.0, 10.0});
  for (const auto& x : s) {
    const double haff = meanfield::haffTemperature(x.t, 0.9, 0.076);
    const double per_collision = std::exp(-(1.0 - 0.81) * x.tau / 3.0);
    INFO("t = " << x.t << ": MD " << x.T << ", Haff " << haff << "; after " << x.tau
                << " collisions per particle: theory " << per_collision);
    // in time: 2 sigma statistics + the 4 % lower collision frequency of contacts lasting 0.03
    CHECK(x.T == Approx(haff).epsilon(0.05));
    // per collision: statistics only (3 sigma of the instantaneous T_g)
    CHECK(x.T == Approx(per_collision).epsilon(0.03));
  }
  CHECK(s.back().T < 0.6);  // it does cool; a test that ignored dissipation would fail here
}

TEST_CASE("viscoelastic gas follows the kinetic-theory cooling built on the exact e(v)",
          "[md][cooling]") {
  // Hertz E = 278.6, D = 27.7, clamped; N = 2000. Early times (T >~ 0.4, about 2-3 collisions per
  // particle): the theory assumes a Maxwellian (a2 = 0), the correction it neglects grows as the
  // strongly dissipative collisions (e ~ 0.3-0.5) distort f(v); 5 % covers it and 3 sigma of T_g.
  MdConfig c;
  c.system.N = 2000;
  c.system.seed = 22;
  const meanfield::RestitutionTable table({c.contact.E, c.contact.D, true});
  const meanfield::RestitutionFunction e = [&table](double g) { return table(g); };
  const auto s = mdCooling(c, {0.5, 1.0, 2.0});
  for (const auto& x : s) {
    // A collision is counted when it starts; the ~0.2 contacts per particle in progress are on
    // average half done, so the collisions whose dissipation has happened are tau - contacts/2.
    const double theory = temperatureAtCollisions(e, x.tau - 0.5 * x.contacts);
    INFO("t = " << x.t << ", " << x.tau << " collisions per particle: MD " << x.T
                << ", kinetic theory " << theory);
    CHECK(x.T == Approx(theory).epsilon(0.05));
  }
  // and in time, the MD gas cools more slowly than the hard-sphere collision rate predicts, by
  // the contact-duration effect described above (a check that the clock difference is real)
  const auto theory_t =
      meanfield::solveViscoelasticCooling({c.contact.E, c.contact.D, true}, {2.0});
  CHECK(s.back().T > theory_t[0].T);
}
