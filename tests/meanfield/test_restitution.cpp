// Viscoelastic restitution coefficient e(v) (meanfield/kinetic/Restitution.h) against the
// docs/model.md reference values, closed forms of the elastic Hertz contact, the published
// small-damping series (Ramirez et al., PRE 60, 4465 (1999)) and an independent fixed-step
// integration in physical units.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <boost/numeric/odeint.hpp>

#include "meanfield/kinetic/Restitution.h"

using namespace granagg::meanfield;

namespace {

/// Independent reference: classical RK4 with a fixed step in physical units (no scaling, no
/// start-up series, no dense output), m_eff xi'' = -F, F = E xi^{3/2} + D xi^{1/2} xi' (clamped
/// at 0 or not), from xi = 0, xi' = v until xi < 0; the crossing is interpolated linearly.
/// Its error comes from the xi^{1/2} singularity at both ends and falls roughly as steps^{-3/2}:
/// against the library at v = 0.05 it is 5e-8 / 1.6e-9 / 2e-10 (clamped) and 9e-8 / 5e-9 / 5e-10
/// (unclamped) at 1e4 / 1e5 / 4e5 steps per elastic contact time (measured); 4e5 are used.
double referenceRestitution(double E, double D, double v, bool clamped) {
  using State = std::array<double, 2>;
  const double tc = HERTZ_CONTACT_TIME_FACTOR * std::pow(M_EFF * M_EFF / (E * E * v), 0.2);
  const double dt = tc / 4e5;
  auto rhs = [&](const State& y, State& dy, double) {
    const double xi = std::max(y[0], 0.0);
    double F = E * std::pow(xi, 1.5) + D * std::sqrt(xi) * y[1];
    if (clamped) F = std::max(F, 0.0);
    dy[0] = y[1];
    dy[1] = -F / M_EFF;
  };
  boost::numeric::odeint::runge_kutta4<State> rk;
  State y{0.0, v};
  for (long k = 0; k < 100000000L; ++k) {
    const State prev = y;
    rk.do_step(rhs, y, k * dt, dt);
    if (y[0] < 0.0) {
      const double w = prev[0] / (prev[0] - y[0]);
      return -(prev[1] + w * (y[1] - prev[1])) / v;
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

TEST_CASE("restitution at v = 0.05 matches the model's reference values, clamped and unclamped",
          "[meanfield][kinetic][restitution]") {
  // docs/model.md section 3 quotes e(0.05) = 0.506 (clamped) and 0.469 (unclamped); the brief gives
  // 0.5055 and 0.4691 and asks for 1e-3, the precision to which they are quoted.
  ContactParams clamped;  // defaults E = 278.6, D = 27.7
  ContactParams unclamped;
  unclamped.clamped = false;
  const double ec = Restitution(clamped).restitution(0.05);
  const double eu = Restitution(unclamped).restitution(0.05);
  CHECK(ec == Approx(0.5055).epsilon(0).margin(1e-3));
  CHECK(eu == Approx(0.4691).epsilon(0).margin(1e-3));
  // Independent fixed-step integration in physical units (error ~5e-10, see above): 1e-8 leaves
  // a factor 20 of margin.
  CHECK(ec == Approx(referenceRestitution(278.6, 27.7, 0.05, true)).epsilon(0).margin(1e-8));
  CHECK(eu == Approx(referenceRestitution(278.6, 27.7, 0.05, false)).epsilon(0).margin(1e-8));
  // docs/model.md section 3: e is about 0.3 to 0.5 for impact speeds 0.05 to 1 at these parameters.
  CHECK(Restitution(clamped).restitution(1.0) == Approx(0.33).epsilon(0).margin(0.01));
}

TEST_CASE("restitution rises monotonically towards 1 as the impact speed falls",
          "[meanfield][kinetic][restitution]") {
  for (bool c : {true, false}) {
    ContactParams p;
    p.clamped = c;
    const Restitution R(p);
    double previous = 1.0;
    for (int k = 0; k <= 22; ++k) {
      const double v = std::pow(10.0, -10.0 + 0.5 * k);  // 1e-10 ... 10
      const double e = R.restitution(v);
      CHECK(e > 0.0);
      CHECK(e < previous);  // strictly decreasing in v
      previous = e;
    }
    // e -> 1 only as v^{1/5}: 1 - e = C1 b to first order, b = 1.2471 v^{1/5} (0.031 at 1e-8).
    CHECK(R.restitution(1e-8) > 0.95);
    // Clamping can only remove the attractive tail, so it never lowers e.
    if (!c) {
      ContactParams q;
      CHECK(Restitution(q).restitution(0.3) > R.restitution(0.3));
    }
  }
}

TEST_CASE("elastic Hertz contact: e = 1, contact time and largest overlap in closed form",
          "[meanfield][kinetic][restitution]") {
  // Closed form of the dimensionless contact time (Hertz): (4/5)(5/4)^{2/5} B(2/5, 1/2).
  const double beta = std::tgamma(0.4) * std::tgamma(0.5) / std::tgamma(0.9);
  const double factor = 0.8 * std::pow(1.25, 0.4) * beta;
  CHECK(HERTZ_CONTACT_TIME_FACTOR == Approx(factor).epsilon(1e-15));
  CHECK(factor == Approx(3.218065).epsilon(2e-7));  // docs/model.md section 6, rounded to 7 digits
  for (bool c : {true, false}) {
    ContactParams p;
    p.D = 0.0;
    p.clamped = c;
    const Restitution R(p);
    for (double v : {1e-3, 0.05, 1.6}) {
      const CollisionResult r = R.collide(v);
      // Energy conservation; the integrator is run at 1e-12, so 1e-8 is a loose bound.
      CHECK(r.restitution == Approx(1.0).epsilon(0).margin(1e-8));
      // docs/model.md section 6: t_c = 3.218065 (m_eff^2/(E^2 v))^{1/5}, to 1e-6 relative as asked;
      // against the closed form to 1e-10 (the dense-output crossing is accurate to ~1e-12,
      // measured).
      CHECK(r.contact_time ==
            Approx(3.218065 * std::pow(M_EFF * M_EFF / (p.E * p.E * v), 0.2)).epsilon(1e-6));
      CHECK(r.contact_time ==
            Approx(factor * std::pow(M_EFF * M_EFF / (p.E * p.E * v), 0.2)).epsilon(1e-10));
      CHECK(r.contact_time == Approx(R.elasticContactTime(v)).epsilon(1e-6));
      // Largest overlap from (1/2) m_eff v^2 = (2/5) E xi_max^{5/2}.
      CHECK(r.max_overlap == Approx(std::pow(1.25 * M_EFF * v * v / p.E, 0.4)).epsilon(1e-9));
    }
    // docs/model.md section 6: 0.23 for v = 1.6 at the defaults.
    CHECK(R.elasticContactTime(1.6) == Approx(0.23).epsilon(0).margin(0.005));
  }
}

TEST_CASE("restitution depends on E, D and v only through b = D m_eff^-2/5 E^-3/5 v^1/5",
          "[meanfield][kinetic][restitution]") {
  // (E, D, v) and (8E, D 8^{3/5} / 2, 32 v) share b; the reference integration in physical units
  // knows nothing about the scaling, so agreement of both with the scaled solver checks it.
  const double E = 278.6, D = 27.7, v = 0.05;
  const double E2 = 8.0 * E, D2 = D * std::pow(8.0, 0.6) / 2.0, v2 = 32.0 * v;
  ContactParams p1{E, D, true}, p2{E2, D2, true};
  const Restitution R1(p1), R2(p2);
  CHECK(R1.scalingParameter(v) == Approx(R2.scalingParameter(v2)).epsilon(1e-14));
  CHECK(R1.scalingParameter(v) == Approx(1.247105 * std::pow(v, 0.2)).epsilon(1e-6));
  const double e1 = R1.restitution(v), e2 = R2.restitution(v2);
  CHECK(e1 == Approx(e2).epsilon(0).margin(1e-12));
  CHECK(referenceRestitution(E2, D2, v2, true) ==
        Approx(e1).epsilon(0).margin(1e-8));  // reference error 2e-10
  // The contact time scales with tau = m_eff^{2/5} E^{-2/5} v^{-1/5}.
  CHECK(R2.contactTime(v2) / R1.contactTime(v) ==
        Approx(std::pow(8.0, -0.4) * std::pow(32.0, -0.2)).epsilon(1e-10));
}

TEST_CASE("restitution integration is converged", "[meanfield][kinetic][restitution]") {
  // The start-up series and the dense-output crossing leave e unchanged when the tolerance is
  // tightened by 100: the default 1e-12 is converged to ~1e-12 (bound 1e-10 for margin).
  for (bool c : {true, false}) {
    RestitutionOptions tight;
    tight.tolerance = 1e-14;
    for (double b : {1e-3, 0.685, 3.0}) {
      const CollisionResult a = collideScaled(b, c);
      const CollisionResult t = collideScaled(b, c, tight);
      CHECK(a.restitution == Approx(t.restitution).epsilon(0).margin(1e-10));
      CHECK(a.contact_time == Approx(t.contact_time).epsilon(1e-10));
    }
  }
}

TEST_CASE("small-damping series agrees with the integration only where damping is small",
          "[meanfield][kinetic][restitution]") {
  // Published constants (Ramirez et al. 1999): C1 = 1.15344, C2 = 0.79826, and their closed
  // forms C1 = Gamma(3/5) sqrt(pi) / (2^{1/5} 5^{2/5} Gamma(21/10)), C2 = 3 C1^2 / 5.
  const double c1 = std::tgamma(0.6) * std::sqrt(std::acos(-1.0)) /
                    (std::pow(2.0, 0.2) * std::pow(5.0, 0.4) * std::tgamma(2.1));
  CHECK(RESTITUTION_C1 == Approx(c1).epsilon(1e-15));
  CHECK(RESTITUTION_C1 == Approx(1.15344).epsilon(0).margin(1e-5));  // published to 5 decimals
  CHECK(RESTITUTION_C2 == Approx(0.79826).epsilon(0).margin(1e-5));

  // The integration recovers the coefficients: at b = 1e-4, (1 - e)/b = C1 - C2 b + O(b^{3/2})
  // with the next term 0.25 b^{3/2} = 2.5e-7 (clamped, measured) and an integration error
  // ~1e-12/b = 1e-8, hence 1e-6; for the unclamped force (e - 1 + C1 b)/b^2 -> C2 with a next
  // term ~ -0.5 b (measured), hence 1e-3 at b = 1e-3.
  for (bool c : {true, false}) {
    const double b = 1e-4;
    CHECK((1.0 - collideScaled(b, c).restitution) / b ==
          Approx(RESTITUTION_C1 - RESTITUTION_C2 * b).epsilon(0).margin(1e-6));
  }
  {
    const double b = 1e-3;
    const double e = collideScaled(b, false).restitution;
    CHECK((e - 1.0 + RESTITUTION_C1 * b) / (b * b) ==
          Approx(RESTITUTION_C2).epsilon(0).margin(1e-3));
  }

  // D / 100: b = 0.0125 v^{1/5} <= 0.015 for v <= 2, 1 - e < 0.02. The neglected terms are
  // h5 b^{5/2} with h5 ~ 0.26 (clamped: the delayed-recovery term of Schwager & Poeschel,
  // PRE 78, 051304 (2008)) and ~0.5 b^3 (unclamped), measured; the bound b^{5/2} covers both
  // with margin, and the first-order series alone misses by ~C2 b^2 (much more).
  for (bool c : {true, false}) {
    ContactParams p;
    p.D = 27.7 / 100.0;
    p.clamped = c;
    const Restitution R(p);
    for (double v : {1e-6, 1e-3, 0.05, 1.0, 2.0}) {
      const double b = R.scalingParameter(v);
      const double e = R.restitution(v);
      REQUIRE(1.0 - e < 0.1);
      CHECK(std::fabs(e - R.seriesRestitution(v)) < std::pow(b, 2.5));
      CHECK(std::fabs(e - (1.0 - RESTITUTION_C1 * b)) > 0.5 * RESTITUTION_C2 * b * b);
    }
  }

  // Documentation: at the defaults (b = 0.685 at v = 0.05) the series is far outside its range.
  const Restitution R;
  CHECK(std::fabs(R.restitution(0.05) - R.seriesRestitution(0.05)) > 0.05);
  CHECK(std::fabs(R.restitution(1.0) - R.seriesRestitution(1.0)) > 0.4);
}

TEST_CASE("tabulated restitution matches direct integration", "[meanfield][kinetic][restitution]") {
  // Spline in ln b with 600 knots: measured interpolation error 1e-9 (clamped), 1e-8
  // (unclamped); bounds 1e-8 and 1e-7. Below b_min the series (error O(b^{5/2}) < 1e-14).
  for (bool c : {true, false}) {
    ContactParams p;
    p.clamped = c;
    const RestitutionTable T(p);
    const Restitution R(p);
    for (double v : {1e-30, 1e-12, 3.3e-5, 0.05, 0.77, 2.0, 13.0, 1e5}) {
      CHECK(T.restitution(v) == Approx(R.restitution(v)).epsilon(0).margin(c ? 1e-8 : 1e-7));
    }
    CHECK(T(0.0) == 1.0);
    // above the table (b > 20, v > 3.3e6) the contact is integrated directly
    CHECK(T.restitution(1e8) == Approx(R.restitution(1e8)).epsilon(0).margin(1e-12));
  }
}

TEST_CASE("restitution rejects bad parameters", "[meanfield][kinetic][restitution]") {
  CHECK_THROWS_AS(Restitution(ContactParams{0.0, 27.7, true}), std::invalid_argument);
  CHECK_THROWS_AS(Restitution(ContactParams{-1.0, 27.7, true}), std::invalid_argument);
  CHECK_THROWS_AS(Restitution(ContactParams{278.6, -0.1, true}), std::invalid_argument);
  CHECK_THROWS_AS(Restitution(ContactParams{std::nan(""), 27.7, true}), std::invalid_argument);
  CHECK_THROWS_WITH(Restitution(ContactParams{278.6, -2.0, true}),
                    Catch::Contains("D") && Catch::Contains("-2"));
  const Restitution R;
  CHECK_THROWS_AS(R.restitution(0.0), std::invalid_argument);
  CHECK_THROWS_AS(R.restitution(-0.05), std::invalid_argument);
  CHECK_THROWS_AS(R.restitution(std::numeric_limits<double>::infinity()), std::invalid_argument);
  CHECK_THROWS_WITH(R.restitution(-0.05),
                    Catch::Contains("impact speed") && Catch::Contains("-0.05"));
  CHECK_THROWS_AS(collideScaled(-1.0, true), std::invalid_argument);
  RestitutionOptions bad;
  bad.tolerance = 0.0;
  CHECK_THROWS_AS(Restitution(ContactParams{}, bad), std::invalid_argument);
  CHECK_THROWS_AS(RestitutionTable(ContactParams{}, 0.0, 20.0), std::invalid_argument);
  CHECK_THROWS_AS(RestitutionTable(ContactParams{}, 1.0, 0.5), std::invalid_argument);
  CHECK_THROWS_AS(RestitutionTable(ContactParams{}, 1e-6, 20.0, 4), std::invalid_argument);
}
