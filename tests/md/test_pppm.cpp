// PPPM (md/coulomb/Pppm.h): Madelung constants and the single charge in a background at the default
// accuracy, forces against converged plain Ewald on gas-like random configurations (neutral and
// all-positive) at 1e-3, 1e-4 and 1e-5 with the error estimate within a factor 3, determinism with
// 1 and 2 threads, independence of the storage order, the energy alone, the fixed-point charge
// assignment against the tiles', and input validation.
#include <catch2/catch.hpp>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

#include "CoulombFixtures.h"
#include "md/coulomb/Ewald.h"
#include "md/coulomb/EwaldParams.h"
#include "md/coulomb/Pppm.h"

using namespace granagg::md;
using granagg::md::testing::rmsDifference;
using granagg::md::testing::Charges;
using granagg::md::testing::cscl;
using granagg::md::testing::nacl;

namespace {

/// N unit spheres at filling fraction 0.076 (the paper's gas), random and non-overlapping, with
/// charges +-1 alternating (neutral) or all +1.
Charges gas(int n, bool neutral, unsigned seed) {
  Charges c;
  c.L = std::cbrt(n * M_PI / (6 * 0.076));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, c.L);
  auto mi = [&](double d) { return d - c.L * std::nearbyint(d / c.L); };
  while (static_cast<int>(c.x.size()) < n) {
    const double a = u(rng), b = u(rng), e = u(rng);
    bool ok = true;
    for (std::size_t j = 0; j < c.x.size() && ok; ++j) {
      const double dx = mi(a - c.x[j]), dy = mi(b - c.y[j]), dz = mi(e - c.z[j]);
      ok = dx * dx + dy * dy + dz * dz >= 1.0;
    }
    if (ok) c.add(a, b, e, neutral ? (c.x.size() % 2 ? -1.0 : 1.0) : 1.0);
  }
  return c;
}

/// PPPM total (mesh part + O(N^2) real space with the same RealSpace.h terms the engine uses).
CoulombResult pppmTotal(Pppm& pppm, const Charges& c, double K) {
  CoulombResult r = pppm.computeHost(c.x, c.y, c.z, c.q);
  r.energy_real = EwaldReference::realSpace(
      c.x.data(), c.y.data(), c.z.data(), c.q.data(), c.x.size(), c.L, K, pppm.params().alpha,
      pppm.params().r_cut, r.fx.data(), r.fy.data(), r.fz.data());
  r.energy += r.energy_real;
  return r;
}

/// The particles of `c` stored in reverse order, with their ids (id[s] = the index in c), and
/// zeroed force arrays: a storage order that PPPM must not see (Pppm::compute with ids).
struct Reversed {
  std::vector<double> x, y, z, q, fx, fy, fz;
  std::vector<int> id;
  explicit Reversed(const Charges& c) {
    const std::size_t n = c.x.size();
    for (auto* v : {&x, &y, &z, &q}) v->resize(n);
    for (auto* v : {&fx, &fy, &fz}) v->assign(n, 0.0);
    id.resize(n);
    for (std::size_t s = 0; s < n; ++s) {
      const std::size_t i = n - 1 - s;
      x[s] = c.x[i];
      y[s] = c.y[i];
      z[s] = c.z[i];
      q[s] = c.q[i];
      id[s] = static_cast<int>(i);
    }
  }
  double compute(Pppm& pppm) {
    return pppm.compute(x.data(), y.data(), z.data(), q.data(), x.size(), fx.data(), fy.data(),
                        fz.data(), id.data());
  }
  /// Whether the forces equal r's, particle by particle.
  bool sameForces(const CoulombResult& r) const {
    bool same = true;
    for (std::size_t s = 0; s < x.size(); ++s) {
      const std::size_t i = x.size() - 1 - s;
      same = same && fx[s] == r.fx[i] && fy[s] == r.fy[i] && fz[s] == r.fz[i];
    }
    return same;
  }
};

double rmsForce(const CoulombResult& a) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.fx.size(); ++i)
    s += a.fx[i] * a.fx[i] + a.fy[i] * a.fy[i] + a.fz[i] * a.fz[i];
  return std::sqrt(s / a.fx.size());
}

constexpr double MADELUNG_NACL = 1.747564594633;
constexpr double MADELUNG_CSCL = 1.762674773071;
constexpr double XI_SC = -2.837297479481;
constexpr double DEFAULT_ACCURACY = 1e-4;

/// Gas configurations and their converged Ewald references, computed once per test run.
struct Reference {
  Charges c;
  CoulombResult ewald;
};
const Reference& gasReference(bool neutral) {
  static std::map<bool, Reference> cache;
  auto it = cache.find(neutral);
  if (it == cache.end()) {
    Reference r;
    r.c = gas(1000, neutral, neutral ? 101 : 202);
    const EwaldParams p = chooseEwaldParams(1e-10, r.c.x.size(), r.c.L, r.c.sumQ2());
    r.ewald = EwaldReference(p, r.c.L, 1.0).compute(r.c.x, r.c.y, r.c.z, r.c.q);
    it = cache.emplace(neutral, std::move(r)).first;
  }
  return it->second;
}

}  // namespace

TEST_CASE("PPPM: Madelung constants of NaCl and CsCl at the default accuracy", "[md][coulomb]") {
  // Measured: NaCl 1.747478 (8.7e-5 off, all of it real-space truncation: 30 ions sit exactly at
  // r = r_cut = 3, just outside the cutoff; the mesh part is exact to 2e-8), CsCl 1.762653 (2e-5).
  for (int crystal = 0; crystal < 2; ++crystal) {
    const Charges c = crystal == 0 ? nacl(3) : cscl(4);
    const double M_ref = crystal == 0 ? MADELUNG_NACL : MADELUNG_CSCL;
    const PppmParams p = choosePppmParams(DEFAULT_ACCURACY, c.x.size(), c.L, c.sumQ2(), 0.5 * c.L);
    Pppm pppm(p, c.L, 1.0);
    const CoulombResult r = pppmTotal(pppm, c, 1.0);
    INFO((crystal == 0 ? "NaCl" : "CsCl") << ": mesh " << p.mesh << ", order " << p.order
                                          << ", alpha " << p.alpha << ", r_cut " << p.r_cut);
    CHECK(-r.energy / (c.q.size() / 2) == Approx(M_ref).margin(1e-4));
    WARN((crystal == 0 ? "NaCl" : "CsCl")
         << " Madelung from PPPM: " << -r.energy / (c.q.size() / 2) << " (mesh " << p.mesh << ")");
  }
}

TEST_CASE("PPPM: single charge in a neutralising background", "[md][coulomb]") {
  // E = xi q^2 / (2L); one particle and r_cut <= L/2: the mesh, self and background terms alone.
  // The mesh energy of one charge fluctuates with its position relative to the mesh (the force
  // accuracy does not bound it; with N = 1 the chosen mesh is tiny): its position average, after
  // the mean self-energy correction, is the exact value; a single position is exact to 1e-4 at
  // accuracy 1e-6. Measured: relative sd over positions 5e-4 (L = 5) and 3e-3 (L = 12) at 1e-4,
  // 6e-6 and 2e-5 at 1e-6.
  // ~60 evaluations of tiny meshes: thread start-up would dominate (and on a loaded 2-core machine
  // every parallel region waits for a second core), so this case runs on one thread
  const int threads_before = omp_get_max_threads();
  omp_set_num_threads(1);
  std::mt19937_64 rng(7);
  for (double L : {5.0, 12.0}) {
    std::uniform_real_distribution<double> u(0.0, L);
    const PppmParams p = choosePppmParams(DEFAULT_ACCURACY, 1, L, 1.0, 0.5 * L);
    Pppm pppm(p, L, 1.0);
    // offsets on a regular 3^3 grid within one mesh cell (the fluctuation is periodic in the cell,
    // so this average converges much faster than random sampling)
    const double h = L / p.mesh;
    const double base[3] = {u(rng), u(rng), u(rng)};
    double mean = 0.0, fmax = 0.0;
    int samples = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        for (int c = 0; c < 3; ++c, ++samples) {
          const CoulombResult r = pppm.computeHost({base[0] + a * h / 3}, {base[1] + b * h / 3},
                                                   {base[2] + c * h / 3}, {1.0});
          mean += r.energy / (1.0 / (2.0 * L));
          fmax = std::max({fmax, std::abs(r.fx[0]), std::abs(r.fy[0]), std::abs(r.fz[0])});
        }
    mean /= samples;
    INFO("L " << L << ", mesh " << p.mesh << ", alpha " << p.alpha);
    CHECK(mean == Approx(XI_SC).epsilon(2e-5));
    CHECK(fmax < DEFAULT_ACCURACY);  // no self force (ik-differentiation with a symmetric G)

    const PppmParams tight = choosePppmParams(1e-6, 1, L, 4.0, 0.5 * L);
    Pppm fine(tight, L, 1.0);
    for (int s = 0; s < 4; ++s) {
      const CoulombResult r = fine.computeHost({u(rng)}, {u(rng)}, {u(rng)}, {-2.0});
      CHECK(r.energy / (4.0 / (2.0 * L)) == Approx(XI_SC).epsilon(1e-4));
    }
  }
  omp_set_num_threads(threads_before);
}

TEST_CASE("PPPM forces against converged Ewald: RMS error at or below the requested accuracy",
          "[md][coulomb]") {
  // Error = RMS over particles of |F_pppm - F_ewald| / K (K = force between two unit charges at
  // unit distance; docs/coulomb.md). N = 1000 at phi = 0.076, charges +-1 (neutral) or all +1.
  for (bool neutral : {true, false}) {
    const Reference& ref = gasReference(neutral);
    const Charges& c = ref.c;
    for (double acc : {1e-3, 1e-4, 1e-5}) {
      const double r_cut = std::min(0.5 * c.L, 6.0);
      const PppmParams p = choosePppmParams(acc, c.x.size(), c.L, c.sumQ2(), r_cut);
      Pppm pppm(p, c.L, 1.0);
      const auto t0 = std::chrono::steady_clock::now();
      const CoulombResult mesh = pppm.computeHost(c.x, c.y, c.z, c.q);
      const double t_mesh =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const CoulombResult r = pppmTotal(pppm, c, 1.0);
      const double err = rmsDifference(r, ref.ewald);
      const double est = p.estimatedError();
      INFO((neutral ? "neutral" : "all +1")
           << ", accuracy " << acc << ": mesh " << p.mesh << ", order " << p.order << ", alpha "
           << p.alpha << ", r_cut " << p.r_cut << "; measured " << err
           << " (relative to RMS |F|: " << err / rmsForce(ref.ewald) << "), estimated " << est
           << " (real " << p.estimated_error_real << ", mesh " << p.estimated_error_kspace
           << "), mesh time " << t_mesh);
      CHECK(err <= acc);
      CHECK(err > est / 3.0);
      CHECK(err < est * 3.0);
      // energy per particle, in units of K: within the accuracy for the neutral gas; with all
      // charges +1 the real-space truncation misses a systematic tail, (n/2) int_{r_cut} 4 pi r
      // erfc(alpha r) dr per particle, which does not average out (1.2e-3 measured at 1e-3)
      CHECK(std::abs(r.energy - ref.ewald.energy) / c.x.size() < (neutral ? 1.0 : 3.0) * acc);
      WARN("PPPM " << (neutral ? "neutral" : "all +1") << " acc " << acc << ": mesh " << p.mesh
                   << " P " << p.order << " alpha " << p.alpha << " rc " << p.r_cut << " measured "
                   << err << " (/RMS|F| " << err / rmsForce(ref.ewald) << ") est " << est
                   << " mesh-part time " << t_mesh << " s");
      (void)mesh;
    }
  }
}

TEST_CASE("PPPM: mesh part alone against the Ewald reciprocal part at the same alpha",
          "[md][coulomb]") {
  // Isolates the mesh error from the real-space truncation: Ewald with PPPM's alpha and a large
  // k_max gives the exact reciprocal + self + background part.
  const Reference& ref = gasReference(true);
  const Charges& c = ref.c;
  const PppmParams p = choosePppmParams(1e-4, c.x.size(), c.L, c.sumQ2(), 6.0);
  Pppm pppm(p, c.L, 1.0);
  const CoulombResult mesh = pppm.computeHost(c.x, c.y, c.z, c.q);
  EwaldParams ep{p.alpha, 1e-6 /* no real-space pairs */, 1, 0, 0};
  while (ewaldKspaceError(p.alpha, ep.k_max, c.x.size(), c.L, c.sumQ2()) > 1e-9) ++ep.k_max;
  const CoulombResult rec = EwaldReference(ep, c.L, 1.0).compute(c.x, c.y, c.z, c.q);
  const double err = rmsDifference(mesh, rec);
  INFO("mesh " << p.mesh << ": measured mesh error " << err << ", estimated "
               << p.estimated_error_kspace);
  CHECK(err < 3.0 * p.estimated_error_kspace);
  CHECK(err > p.estimated_error_kspace / 3.0);
  CHECK(mesh.energy_self == Approx(rec.energy_self).epsilon(1e-12));
  CHECK(std::abs(mesh.energy_kspace - rec.energy_kspace) < 1e-4 * c.x.size() * 1e-2);
}

TEST_CASE("PPPM: results identical with 1 and 2 threads and independent of storage order",
          "[md][coulomb]") {
  const Reference& ref = gasReference(false);
  const Charges& c = ref.c;
  const PppmParams p = choosePppmParams(1e-4, c.x.size(), c.L, c.sumQ2(), 6.0);
  const int threads_before = omp_get_max_threads();
  omp_set_num_threads(1);
  Pppm one(p, c.L, 1.0);
  const CoulombResult r1 = one.computeHost(c.x, c.y, c.z, c.q);
  omp_set_num_threads(2);
  Pppm two(p, c.L, 1.0);
  const CoulombResult r2 = two.computeHost(c.x, c.y, c.z, c.q);
  const CoulombResult r1b =
      one.computeHost(c.x, c.y, c.z, c.q);  // plan made for 1 thread, run on 2
  omp_set_num_threads(threads_before);
  const std::size_t bytes = c.x.size() * sizeof(double);
  for (const CoulombResult* r : {&r2, &r1b}) {
    CHECK(std::memcmp(r1.fx.data(), r->fx.data(), bytes) == 0);
    CHECK(std::memcmp(r1.fy.data(), r->fy.data(), bytes) == 0);
    CHECK(std::memcmp(r1.fz.data(), r->fz.data(), bytes) == 0);
    CHECK(r1.energy == r->energy);
  }

#if !defined(GRANAGG_CUDA)  // compute() takes device pointers: host arrays serve only on the OpenMP
                            // backend
  // storage order: the same particles stored reversed, with their ids, give bit-identical forces
  const std::size_t n = c.x.size();
  Reversed rev(c);
  const double e = rev.compute(two);
  CHECK(e == r2.energy);
  // the packed (x, y, z, q) layout of the engine gives the same bits
  std::vector<double> pos4(4 * n), gx(n, 0.0), gy(n, 0.0), gz(n, 0.0);
  for (std::size_t s = 0; s < n; ++s) {
    pos4[4 * s] = rev.x[s];
    pos4[4 * s + 1] = rev.y[s];
    pos4[4 * s + 2] = rev.z[s];
    pos4[4 * s + 3] = rev.q[s];
  }
  CHECK(two.compute(pos4.data(), n, gx.data(), gy.data(), gz.data(), rev.id.data()) == e);
  CHECK(std::memcmp(gx.data(), rev.fx.data(), bytes) == 0);
  CHECK(std::memcmp(gz.data(), rev.fz.data(), bytes) == 0);
  CHECK(rev.sameForces(r2));
  // the energy alone (null forces: the engine's observables) is the same energy, to the bit
  CHECK(two.compute(pos4.data(), n, nullptr, nullptr, nullptr, rev.id.data()) == e);
  CHECK(two.lastEnergies().total() == e);
#endif
}

TEST_CASE("PPPM: the fixed-point charge assignment equals the tiles' to round-off and is "
          "deterministic",
          "[md][coulomb]") {
  // The two assignments (PppmParams::assignment) put the same charges on the mesh; fixed point
  // rounds each term to a unit of at most 2^-60 sqrt(N sum q^2) (4e-16 here, N = 1000, |q| = 1),
  // so mesh values, and the forces and energy that are linear and quadratic in them, agree to
  // ~1e-13 relative. 1e-11 of the largest force leaves room; a missed or misplaced stencil term
  // changes forces by ~1e-2 of it. Tiles are checked against Ewald above.
  const int threads_before = omp_get_max_threads();
  for (bool neutral : {true, false}) {
    const Charges& c = gasReference(neutral).c;
    PppmParams p = choosePppmParams(1e-4, c.x.size(), c.L, c.sumQ2(), 6.0);
    p.assignment = ChargeAssignment::Tiles;
    Pppm tiles(p, c.L, 1.0);
    const CoulombResult rt = tiles.computeHost(c.x, c.y, c.z, c.q);
    p.assignment = ChargeAssignment::FixedPoint;
    omp_set_num_threads(1);
    Pppm fixed(p, c.L, 1.0);
    const CoulombResult r1 = fixed.computeHost(c.x, c.y, c.z, c.q);
    omp_set_num_threads(2);
    const CoulombResult r2 = fixed.computeHost(c.x, c.y, c.z, c.q);
    omp_set_num_threads(threads_before);
    double f_max = 0.0, d_max = 0.0;
    for (std::size_t i = 0; i < c.x.size(); ++i) {
      f_max = std::max({f_max, std::abs(rt.fx[i]), std::abs(rt.fy[i]), std::abs(rt.fz[i])});
      d_max = std::max({d_max, std::abs(r1.fx[i] - rt.fx[i]), std::abs(r1.fy[i] - rt.fy[i]),
                        std::abs(r1.fz[i] - rt.fz[i])});
    }
    INFO((neutral ? "neutral" : "all +1") << ": largest force " << f_max << ", largest difference "
                                          << d_max << "; energies " << r1.energy << " and "
                                          << rt.energy);
    CHECK(f_max > 0.0);
    CHECK(d_max <= 1e-11 * f_max);
    CHECK(std::abs(r1.energy_kspace - rt.energy_kspace) <= 1e-11 * std::abs(rt.energy_kspace));
    // 1 and 2 threads: the same bits (the atomic adds run in another order)
    const std::size_t bytes = c.x.size() * sizeof(double);
    CHECK(std::memcmp(r1.fx.data(), r2.fx.data(), bytes) == 0);
    CHECK(std::memcmp(r1.fy.data(), r2.fy.data(), bytes) == 0);
    CHECK(std::memcmp(r1.fz.data(), r2.fz.data(), bytes) == 0);
    CHECK(r1.energy == r2.energy);
#if !defined(GRANAGG_CUDA)  // compute() takes device pointers (host memory on the OpenMP backend)
    // storage order: reversed, with ids, gives the same bits per particle
    Reversed rev(c);
    CHECK(rev.compute(fixed) == r1.energy);
    CHECK(rev.sameForces(r1));
#endif
  }
  // no charge at all: the scale has no bound to follow, and the mesh stays empty
  const Charges& c = gasReference(true).c;
  PppmParams p = choosePppmParams(1e-4, c.x.size(), c.L, c.sumQ2(), 6.0);
  p.assignment = ChargeAssignment::FixedPoint;
  Pppm fixed(p, c.L, 1.0);
  const std::vector<double> zero(c.x.size(), 0.0);
  const CoulombResult r0 = fixed.computeHost(c.x, c.y, c.z, zero);
  CHECK(r0.energy == 0.0);
  CHECK(*std::max_element(r0.fx.begin(), r0.fx.end()) == 0.0);
}

TEST_CASE("PPPM parameter choice: estimates, cost optimisation and invalid input",
          "[md][coulomb]") {
  const double L = std::cbrt(1e4 * M_PI / (6 * 0.076));
  for (double acc : {1e-3, 1e-4, 1e-5})
    for (int order = 2; order <= 7; ++order) {
      PppmParams p;
      try {
        p = choosePppmParams(acc, 10000, L, 1e4, 5.0, order);
      } catch (const std::invalid_argument&) {
        // low orders need meshes beyond the limit (1024 per edge) at high accuracy: allowed for P
        // <= 3
        CHECK(order <= 3);
        continue;
      }
      CHECK(p.estimated_error_real == Approx(acc / std::sqrt(2.0)).epsilon(1e-9));
      CHECK(p.estimated_error_kspace <= acc / std::sqrt(2.0));
      CHECK(p.mesh >= order);
      CHECK(fftFriendlySize(p.mesh) == p.mesh);
      // the smallest FFT-friendly mesh that meets the target
      int smaller = p.mesh - 1;
      while (smaller >= order && fftFriendlySize(smaller) != smaller) --smaller;
      if (smaller >= order)
        CHECK(pppmKspaceError(p.alpha, smaller, order, 10000, L, 1e4) > acc / std::sqrt(2.0));
    }
  const PppmParams best = optimizePppmParams(1e-4, 10000, L, 1e4, 3.0);
  CHECK(best.estimatedError() <= 1e-4 * (1 + 1e-12));
  CHECK(best.r_cut >= 3.0);
  CHECK(best.r_cut <= 0.5 * L);
  for (double rc : {3.0, 5.0, 8.0})
    for (int order = 4; order <= 7;
         ++order)  // (orders 2 and 3 cannot reach 1e-4 at r_cut = 3 within the mesh limit)
      CHECK(pppmCost(best, 10000, L) <=
            pppmCost(choosePppmParams(1e-4, 10000, L, 1e4, rc, order), 10000, L));
  WARN("optimised PPPM for N = 1e4, 1e-4: r_cut " << best.r_cut << ", mesh " << best.mesh
                                                  << ", order " << best.order << ", alpha "
                                                  << best.alpha);

  CHECK_THROWS_AS(choosePppmParams(0.0, 100, 10.0, 100.0, 4.0), std::invalid_argument);
  CHECK_THROWS_AS(choosePppmParams(1e-4, 100, -10.0, 100.0, 4.0), std::invalid_argument);
  CHECK_THROWS_WITH(choosePppmParams(1e-4, 100, 10.0, 100.0, 5.5), Catch::Contains("r_cut"));
  CHECK_THROWS_WITH(choosePppmParams(1e-4, 100, 10.0, 100.0, 4.0, 8), Catch::Contains("order"));
  CHECK_THROWS_WITH(choosePppmParams(1e-4, 100, 10.0, 100.0, 4.0, 1), Catch::Contains("order"));
  PppmParams bad = choosePppmParams(1e-4, 100, 10.0, 100.0, 4.0);
  bad.mesh = 2;
  CHECK_THROWS_AS(Pppm(bad, 10.0, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(Pppm(choosePppmParams(1e-4, 100, 10.0, 100.0, 4.0), 0.0, 1.0),
                  std::invalid_argument);
  Pppm fresh(choosePppmParams(1e-4, 100, 10.0, 100.0, 4.0), 10.0, 1.0);
  CHECK_THROWS_AS(fresh.lastEnergies(), std::logic_error);
}

TEST_CASE("PPPM: positions outside the box are wrapped", "[md][coulomb]") {
  const Charges c = gas(200, true, 303);
  Pppm pppm(choosePppmParams(1e-4, c.x.size(), c.L, c.sumQ2(), 5.0), c.L, 2.0);
  const CoulombResult a = pppm.computeHost(c.x, c.y, c.z, c.q);
  Charges shifted = c;
  for (std::size_t i = 0; i < c.x.size(); ++i) {
    shifted.x[i] += (i % 3 == 0 ? 3.0 : -2.0) * c.L;  // unwrapped coordinates, as with image counts
    shifted.y[i] -= (i % 2 ? 1.0 : 0.0) * c.L;
    shifted.z[i] += 5.0 * c.L;
  }
  const CoulombResult b = pppm.computeHost(shifted.x, shifted.y, shifted.z, shifted.q);
  CHECK(b.energy == Approx(a.energy).epsilon(1e-10));
  double worst = 0.0;
  for (std::size_t i = 0; i < c.x.size(); ++i)
    worst = std::max({worst, std::abs(a.fx[i] - b.fx[i]), std::abs(a.fy[i] - b.fy[i]),
                      std::abs(a.fz[i] - b.fz[i])});
  CHECK(worst < 1e-9);
}
