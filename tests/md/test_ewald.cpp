// Plain Ewald reference (md/coulomb/Ewald.h) and the parameter choice (EwaldParams.h): against
// independent numbers (Madelung constants, the Wigner-type constant of a single charge in a
// neutralising background), alpha independence of the converged total, F = -grad E, and the
// published error estimates against measured errors.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "CoulombFixtures.h"
#include "md/coulomb/Ewald.h"
#include "md/coulomb/EwaldParams.h"
#include "md/coulomb/RealSpace.h"

using namespace granagg::md;
using granagg::md::testing::rmsDifference;
using granagg::md::testing::Charges;
using granagg::md::testing::cscl;
using granagg::md::testing::nacl;

namespace {

Charges randomCharges(int n, double L, bool neutral, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, L);
  Charges c;
  c.L = L;
  for (int i = 0; i < n; ++i) c.add(u(rng), u(rng), u(rng), neutral ? (i % 2 ? -1.0 : 1.0) : 1.0);
  return c;
}

CoulombResult ewald(const Charges& c, double accuracy, double r_cut = 0.0, double K = 1.0) {
  const EwaldParams p = chooseEwaldParams(accuracy, c.x.size(), c.L, c.sumQ2(), r_cut);
  return EwaldReference(p, c.L, K).compute(c.x, c.y, c.z, c.q);
}

constexpr double MADELUNG_NACL = 1.747564594633;
constexpr double MADELUNG_CSCL = 1.762674773071;
constexpr double XI_SC = -2.837297479481;  // single charge + background, E = xi q^2 / (2L)

}  // namespace

TEST_CASE("Ewald real-space pair term: closed form and F = -dE/dr", "[md][coulomb]") {
  const double K = 2.5, alpha = 0.7;
  for (double r : {0.3, 1.0, 2.2, 4.0}) {
    // erfc(alpha r) via the complementary series-free identity erfc = 1 - erf (independent of
    // ::erfc)
    const double e_expected = K * -2.0 * (1.0 - std::erf(alpha * r)) / r;
    CHECK(ewaldRealEnergy(-2.0, r, alpha, K) == Approx(e_expected).epsilon(1e-12));
    const double dr = 1e-6 * r;
    const double dEdr =
        (ewaldRealEnergy(-2.0, r + dr, alpha, K) - ewaldRealEnergy(-2.0, r - dr, alpha, K)) /
        (2 * dr);
    CHECK(ewaldRealForceOverR(-2.0, r, alpha, K) * r == Approx(-dEdr).epsilon(1e-7));
  }
  // alpha -> 0: the bare Coulomb force K q q / r^2 (repulsive for like charges)
  CHECK(ewaldRealForceOverR(1.0, 2.0, 1e-12, 3.0) * 2.0 == Approx(3.0 / 4.0).epsilon(1e-12));
}

TEST_CASE(
    "fast real-space force (Abramowitz-Stegun erfc) within 1.5e-7 K qq / r^2 of the exact one",
    "[md][coulomb]") {
  // A&S 7.1.26 bounds the absolute erfc error by 1.5e-7; the force term erfc(alpha r) / r^2 then
  // errs by at most 1.5e-7 / r^2 per unit K qq.
  const double K = 5.0;
  for (double alpha : {0.3, 0.58, 1.2})
    for (double r = 0.05; r < 8.0; r += 0.01) {
      const double exact = ewaldRealForceOverR(-1.0, r, alpha, K) * r;  // force magnitude
      const double fast = ewaldRealForceOverRFast(-1.0, r, alpha, K) * r;
      INFO("alpha " << alpha << ", r " << r);
      REQUIRE(std::fabs(fast - exact) <= 1.5e-7 * K / (r * r) * 1.0001);
    }
}

TEST_CASE("Ewald parameter choice meets the requested estimate and rejects unphysical input",
          "[md][coulomb]") {
  for (double acc : {1e-3, 1e-5, 1e-8}) {
    const EwaldParams p = chooseEwaldParams(acc, 1000, 19.0, 1000.0);
    CHECK(p.r_cut == 9.5);
    CHECK(p.estimated_error_real == Approx(acc / std::sqrt(2.0)).epsilon(1e-9));
    CHECK(p.estimated_error_kspace <= acc / std::sqrt(2.0));
    CHECK(ewaldKspaceError(p.alpha, p.k_max - 1, 1000, 19.0, 1000.0) >
          acc / std::sqrt(2.0));  // smallest k_max
    CHECK(p.estimatedError() <= acc * (1 + 1e-12));
  }
  CHECK(fftFriendlySize(7) == 8);
  CHECK(fftFriendlySize(31) == 32);
  CHECK(fftFriendlySize(49) == 50);
  CHECK(fftFriendlySize(121) == 125);
  CHECK_THROWS_AS(chooseEwaldParams(0.0, 10, 5.0, 10.0), std::invalid_argument);
  CHECK_THROWS_AS(chooseEwaldParams(-1e-4, 10, 5.0, 10.0), std::invalid_argument);
  CHECK_THROWS_AS(chooseEwaldParams(1e-4, 10, 0.0, 10.0), std::invalid_argument);
  CHECK_THROWS_AS(chooseEwaldParams(1e-4, 10, 5.0, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(chooseEwaldParams(1e-4, 0, 5.0, 1.0), std::invalid_argument);
  CHECK_THROWS_WITH(chooseEwaldParams(1e-4, 10, -2.0, 10.0), Catch::Contains("L"));
  CHECK_THROWS_AS(EwaldReference(EwaldParams{0.0, 1.0, 3, 0, 0}, 5.0, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(EwaldReference(EwaldParams{1.0, 1.0, 3, 0, 0}, -5.0, 1.0), std::invalid_argument);
}

TEST_CASE("Ewald reference: Madelung constants of NaCl and CsCl", "[md][coulomb]") {
  // E per ion pair = -M q^2 / r0 with r0 = 1 and K = 1 (Madelung constants from the literature,
  // e.g. Zucker, J. Phys. A 8, 1734 (1975)); tight accuracy: the reference must reach 1e-6.
  const Charges a = nacl(2);
  const CoulombResult ra = ewald(a, 1e-12);
  CHECK(-ra.energy / (a.q.size() / 2) == Approx(MADELUNG_NACL).margin(1e-6));
  const Charges b = cscl(3);
  const CoulombResult rb = ewald(b, 1e-12);
  CHECK(-rb.energy / (b.q.size() / 2) == Approx(MADELUNG_CSCL).margin(1e-6));
  // the same with a real-space cutoff beyond L/2 (explicit images) and another alpha
  const CoulombResult rc = ewald(b, 1e-12, 0.9 * b.L);
  CHECK(-rc.energy / (b.q.size() / 2) == Approx(MADELUNG_CSCL).margin(1e-6));
  // in a perfect crystal every ion is at a centre of symmetry: zero force
  double fmax = 0.0;
  for (std::size_t i = 0; i < ra.fx.size(); ++i)
    fmax = std::max({fmax, std::abs(ra.fx[i]), std::abs(ra.fy[i]), std::abs(ra.fz[i])});
  CHECK(fmax < 1e-9);
}

TEST_CASE("Ewald reference: single charge in a neutralising background", "[md][coulomb]") {
  // E = xi q^2 / (2L) with the simple-cubic constant xi = -2.837297479481 (Nijboer & De Wette 1957;
  // Hummer, Pratt & Garcia 1996): self energy and background term together.
  for (double L : {3.0, 10.0})
    for (double q : {1.0, -2.0}) {
      Charges c;
      c.L = L;
      c.add(0.3 * L, 0.1 * L, 0.77 * L, q);
      for (double rc : {0.5 * L, 1.3 * L}) {  // minimum image and explicit self-images
        const CoulombResult r = ewald(c, 1e-12, rc, 1.0);
        CHECK(r.energy / (q * q / (2.0 * L)) == Approx(XI_SC).epsilon(1e-9));
        CHECK(std::abs(r.fx[0]) + std::abs(r.fy[0]) + std::abs(r.fz[0]) < 1e-10);
      }
    }
}

TEST_CASE("Ewald reference: total energy and forces do not depend on alpha", "[md][coulomb]") {
  for (bool neutral : {true, false}) {
    const Charges c = randomCharges(60, 7.0, neutral, neutral ? 11 : 12);
    // different cutoffs give different alpha; beyond L/2 images are summed explicitly
    const CoulombResult r0 = ewald(c, 1e-11, 0.5 * c.L);
    for (double rc_over_L : {0.3, 0.4, 0.8, 1.2}) {
      const EwaldParams p = chooseEwaldParams(1e-11, c.x.size(), c.L, c.sumQ2(), rc_over_L * c.L);
      const CoulombResult r = EwaldReference(p, c.L, 1.0).compute(c.x, c.y, c.z, c.q);
      INFO("neutral " << neutral << ", alpha " << p.alpha << ", r_cut " << p.r_cut << ", k_max "
                      << p.k_max);
      CHECK(r.energy == Approx(r0.energy).epsilon(1e-9));
      CHECK(rmsDifference(r, r0) < 1e-9);
      // the pieces do depend on alpha (otherwise this test would prove nothing)
      CHECK(std::abs(r.energy_self - r0.energy_self) > 1e-3);
    }
  }
}

TEST_CASE("Ewald reference: forces are minus the gradient of the energy", "[md][coulomb]") {
  Charges c = randomCharges(20, 5.0, false, 3);
  c.q = {1,  -2, 0.5, 1,  1,   -1, 3,  -0.25, 1, 1,
         -1, 2,  1,   -1, 0.5, 1,  -3, 1,     1, -1};  // non-neutral, mixed
  const EwaldParams p = chooseEwaldParams(1e-12, c.x.size(), c.L, c.sumQ2());
  const EwaldReference ew(p, c.L, 1.7);
  const CoulombResult r = ew.compute(c.x, c.y, c.z, c.q);
  const double d = 1e-5;
  for (int i : {0, 6, 13}) {
    std::vector<double>* pos[3] = {&c.x, &c.y, &c.z};
    const double f[3] = {r.fx[i], r.fy[i], r.fz[i]};
    for (int dim = 0; dim < 3; ++dim) {
      Charges cp = c, cm = c;
      std::vector<double>* pp[3] = {&cp.x, &cp.y, &cp.z};
      std::vector<double>* pm[3] = {&cm.x, &cm.y, &cm.z};
      (*pp[dim])[i] = (*pos[dim])[i] + d;
      (*pm[dim])[i] = (*pos[dim])[i] - d;
      const double ep = ew.compute(cp.x, cp.y, cp.z, cp.q).energy,
                   em = ew.compute(cm.x, cm.y, cm.z, cm.q).energy;
      CHECK(f[dim] == Approx(-(ep - em) / (2 * d)).margin(1e-6 * (1.0 + std::abs(f[dim]))));
    }
  }
  // Newton's third law for the total force (the background exerts none)
  double sx = 0, sy = 0, sz = 0;
  for (std::size_t i = 0; i < r.fx.size(); ++i) {
    sx += r.fx[i];
    sy += r.fy[i];
    sz += r.fz[i];
  }
  CHECK(std::abs(sx) + std::abs(sy) + std::abs(sz) < 1e-9);
}

TEST_CASE("Kolafa-Perram estimates predict the measured Ewald force error", "[md][coulomb]") {
  // N = 300 random +-1 charges at the gas density of the paper's box (phi = 0.076):
  // error of Ewald at accuracy a against a converged reference, within a factor 3 of the
  // estimate and at most a.
  const int n = 300;
  const double L = std::cbrt(n * M_PI / (6 * 0.076));
  const Charges c = randomCharges(n, L, true, 5);
  const CoulombResult ref = ewald(c, 1e-12);
  for (double acc : {1e-3, 1e-4, 1e-5}) {
    for (double rc : {0.3 * L, 0.5 * L}) {
      const EwaldParams p = chooseEwaldParams(acc, n, L, c.sumQ2(), rc);
      const CoulombResult r = EwaldReference(p, L, 1.0).compute(c.x, c.y, c.z, c.q);
      const double err = rmsDifference(r, ref);
      INFO("accuracy " << acc << ", r_cut " << rc << ": measured " << err << ", estimated "
                       << p.estimatedError() << ", alpha " << p.alpha << ", k_max " << p.k_max);
      CHECK(err <= acc);
      CHECK(err > p.estimatedError() / 3.0);
      CHECK(err < p.estimatedError() * 3.0);
    }
  }
}
