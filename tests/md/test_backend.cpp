// The engine's backends on the same states (issue 15). These test bodies run on whichever backend
// the test binary was built for: OpenMP threads in the CPU build (ctest, CI) and the GPU in the
// CUDA build (scripts/gpu_check.sh). Two references:
//   - a host brute-force sum of the contact law over all pairs (independent of the neighbour list,
//     the cell sort and the device code), for the engine's contact forces;
//   - golden values written by the CPU backend, as text a person can read and review as a diff
//     (tests/data/backend/<case>.toml, in the manner of LAMMPS's force-style YAML files): the
//     forces and energies of the initial state, and the state (unwrapped positions, velocities,
//     charges), forces and energies after a short run, of a dense neutral gas and a charged gas
//     (PPPM, multiple time stepping, charge exchange), with the case's tolerances. Reals are
//     written with 17 significant digits, which read back to the same bits. The CPU build must
//     match them to the bit (it wrote them: a change there is a change of the trajectory, and
//     needs a reason); the CUDA build to the file's tolerances, which leave room for fused
//     multiply-adds and cuFFT's round-off, not for a different algorithm.
// Regenerate the files (CPU build only) after an intended change of the trajectory with
//     bash scripts/write_reference_states.sh [BUILD_DIR]
// (`test_md --write-reference "[backend]"`), and review `git diff`.
#include <catch2/catch.hpp>

#include <toml++/toml.h>

#include "TestUtil.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/Box.h"
#include "md/config/MdConfig.h"
#include "md/engine/Engine.h"
#include "md/io/InitialState.h"
#include "md/potentials/HertzViscoelastic.h"
#include "md/potentials/SpringDashpot.h"

using namespace granagg;
using namespace granagg::md;

namespace {

#ifdef GRANAGG_CUDA
constexpr bool CUDA_BUILD = true;
#else
constexpr bool CUDA_BUILD = false;
#endif

/// A dense jittered cubic block (spacing 0.97 d: neighbours overlap by ~0.03 d) of side^3
/// particles centred on the box corner, so that contacts wrap across faces, edges and the corner,
/// plus `gas` free particles elsewhere; velocities uniform in [-1, 1]. Deterministic in seed.
Frame denseBlock(int side, int gas, double L, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01), v(-1.0, 1.0), u(0.0, 1.0);
  Frame f;
  f.box = L;
  common::Box box{L};
  auto add = [&](double x, double y, double z) {
    f.x.push_back(x);
    f.y.push_back(y);
    f.z.push_back(z);
    f.vx.push_back(v(rng));
    f.vy.push_back(v(rng));
    f.vz.push_back(v(rng));
  };
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j)
      for (int k = 0; k < side; ++k) {
        double p[3] = {(i - side / 2) * 0.97 + jitter(rng), (j - side / 2) * 0.97 + jitter(rng),
                       (k - side / 2) * 0.97 + jitter(rng)};
        for (double& c : p) box.wrap(c);
        add(p[0], p[1], p[2]);
      }
  // free particles in the half of the box away from the corner, with no overlaps at all
  while (static_cast<int>(f.x.size()) < side * side * side + gas) {
    const double p[3] = {L * (0.25 + 0.5 * u(rng)), L * (0.25 + 0.5 * u(rng)),
                         L * (0.25 + 0.5 * u(rng))};
    bool free = true;
    for (std::size_t j = 0; j < f.x.size() && free; ++j) {
      const double dx = box.minimumImage(p[0] - f.x[j]), dy = box.minimumImage(p[1] - f.y[j]),
                   dz = box.minimumImage(p[2] - f.z[j]);
      free = dx * dx + dy * dy + dz * dz > 1.0;
    }
    if (free) add(p[0], p[1], p[2]);
  }
  return f;
}

/// Contact forces by a sum over all pairs (minimum image), at the velocities of the state itself:
/// what the engine computes for a state given at full step (Engine with allow_contacts).
template <class Law, class Params>
std::vector<double> bruteForceContacts(const Frame& f, const Params& prm, int& pairs) {
  const std::size_t n = f.size();
  common::Box box{f.box};
  std::vector<double> out(3 * n, 0.0);
  pairs = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      const double rx = box.minimumImage(f.x[i] - f.x[j]), ry = box.minimumImage(f.y[i] - f.y[j]),
                   rz = box.minimumImage(f.z[i] - f.z[j]);
      const double r = std::sqrt(rx * rx + ry * ry + rz * rz);
      if (r >= 1.0) continue;
      ++pairs;
      const double nx = rx / r, ny = ry / r, nz = rz / r;
      // overlap rate xi' = -(v_i - v_j) . n
      const double xi_dot =
          -((f.vx[i] - f.vx[j]) * nx + (f.vy[i] - f.vy[j]) * ny + (f.vz[i] - f.vz[j]) * nz);
      const double F = Law::normalForce(1.0 - r, xi_dot, prm);
      const double d[3] = {F * nx, F * ny, F * nz};
      for (int c = 0; c < 3; ++c) {
        out[c * n + i] += d[c];
        out[c * n + j] -= d[c];
      }
    }
  return out;
}

double maxAbs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::fabs(x));
  return m;
}

double maxAbsDiff(const std::vector<double>& a, const std::vector<double>& b) {
  REQUIRE(a.size() == b.size());
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::fabs(a[i] - b[i]));
  return m;
}

/// Unwrapped positions x + image L, as one array (x, then y, then z); no images: zero.
std::vector<double> unwrapped(const Frame& f) {
  std::vector<double> u;
  const std::vector<double>* pos[3] = {&f.x, &f.y, &f.z};
  const std::vector<std::int32_t>* img[3] = {&f.ix, &f.iy, &f.iz};
  for (int c = 0; c < 3; ++c)
    for (std::size_t i = 0; i < f.size(); ++i)
      u.push_back((*pos[c])[i] + (img[c]->empty() ? 0 : (*img[c])[i]) * f.box);
  return u;
}

std::vector<double> velocities(const Frame& f) {
  std::vector<double> v = f.vx;
  v.insert(v.end(), f.vy.begin(), f.vy.end());
  v.insert(v.end(), f.vz.begin(), f.vz.end());
  return v;
}

std::vector<double> slice(const std::vector<double>& v, std::size_t c, std::size_t n) {
  return {v.begin() + c * n, v.begin() + (c + 1) * n};
}

/// The energies a reference case records (Observables, totals).
struct Energies {
  double kinetic = 0.0, elastic = 0.0, coulomb = 0.0;
};

Energies energiesOf(const Engine& e) {
  const Observables o = e.observables();
  return {o.kinetic_energy, o.elastic_energy, o.coulomb_energy};
}

/// A reference case's outcome: the initial forces and energies, and the state, forces and
/// energies after `steps` steps.
struct Outcome {
  std::vector<double> f0, f1;
  Energies e0, e1;
  Frame end;
};

/// x, then y, then z, as one array.
std::vector<double> joined(const Forces& f) {
  std::vector<double> v = f.x;
  v.insert(v.end(), f.y.begin(), f.y.end());
  v.insert(v.end(), f.z.begin(), f.z.end());
  return v;
}

Outcome runCase(const MdConfig& c, const Frame& init, bool allow_contacts, std::int64_t steps,
                bool with_energies = false) {
  Engine e(c, init, allow_contacts);
  Outcome o;
  o.f0 = joined(e.forces());
  e.run(steps);
  o.end = e.frame();
  o.f1 = joined(e.forces());
  if (with_energies) {
    // after the state is taken (the observables may rebuild a list), and for the initial state
    // from an engine of its own, so that the trajectory is the one without observables
    o.e1 = energiesOf(e);
    o.e0 = energiesOf(Engine(c, init, allow_contacts));
  }
  return o;
}

/// The reference cases, one file each: per contact model a dense neutral gas (Hertz, 300 steps;
/// spring-dashpot, 300 steps) and per Coulomb method a charged gas (K = 5, bipolar charges changed
/// by exchange: PPPM with multiple time stepping, 200 steps; plain Ewald, 100 steps).
struct ReferenceCase {
  std::string name;
  MdConfig config;
  Frame init;
  bool allow_contacts;
  std::int64_t steps;
};

std::vector<ReferenceCase> referenceCases() {
  std::vector<ReferenceCase> cases(4);
  ReferenceCase& a = cases[0];
  a.name = "contacts";
  a.init = denseBlock(8, 200, 16.0, 3);
  a.config.system.N = static_cast<int>(a.init.size());
  a.config.system.seed = 5;
  a.allow_contacts = true;
  a.steps = 300;
  ReferenceCase& b = cases[1];
  b.name = "coulomb";
  b.config.system.N = 600;
  b.config.system.phi = 0.15;
  b.config.system.seed = 9;
  b.config.charging.initial = "bipolar";
  b.config.charging.q0 = 0.3;
  b.config.charging.Q = 0.05;
  b.config.coulomb.K = 5.0;
  // the split the reference was written with ("auto" before issue 15 made it 2 d): the file keeps
  // guarding the rest of the trajectory to the bit
  b.config.coulomb.r_fast = 3.5;
  b.init = randomInitialState(b.config);
  assignInitialCharges(b.config, b.init);
  b.allow_contacts = false;
  b.steps = 200;
  ReferenceCase& c = cases[2];
  c.name = "spring_dashpot";
  c.init = a.init;
  c.config = a.config;
  c.config.contact.model = "spring_dashpot";
  // softer than the default 2e4, so that the block's overlaps (up to ~0.03 d) hold forces of the
  // Hertz case's size rather than releasing a hundred times its elastic energy
  c.config.contact.stiffness = 500.0;
  c.allow_contacts = true;
  c.steps = 300;
  ReferenceCase& d = cases[3];
  d.name = "ewald";
  d.config = b.config;
  d.config.system.N = 300;
  d.config.coulomb.method = "ewald";
  d.init = randomInitialState(d.config);
  assignInitialCharges(d.config, d.init);
  d.allow_contacts = false;
  d.steps = 100;
  return cases;
}

/// The reference file; GRANAGG_TEST_SOURCE_DIR overrides the source tree compiled in (a test
/// binary built on one machine and run on another: scripts/gpu_check.sh --bundle).
std::string referencePath(const std::string& name) {
  const char* root = std::getenv("GRANAGG_TEST_SOURCE_DIR");
  return std::string(root ? root : GRANAGG_SOURCE_DIR) + "/tests/data/backend/" + name + ".toml";
}

/// The CUDA build's bounds, per case (the CPU build must match to the bit). The GPU runs the
/// same algorithm and summation order with different round-off (FMA contraction, cuFFT against
/// FFTW). A relative 1e-15 in the positions changes the initial Hertz forces by ~1e-12 relative
/// (F ~ xi^1.5 at overlaps xi ~ 0.03 d) and the state after these short runs by less than 100
/// times itself (the last test case; measured 24 and 6.5 on the CPU). The bounds leave a factor
/// >= 100 above that, and are far below any algorithmic difference (a missed contact changes a
/// force by order 1, a PPPM mesh difference at accuracy 1e-4 by ~1e-4). Energies: relative, as
/// the final forces.
struct Tolerance {
  double initial_forces = 1e-10;  ///< max |dF| / max |F|
  double positions = 1e-9;        ///< max |dx| (d)
  double velocities = 1e-8;       ///< max |dv| / max |v|
  double charges = 1e-10;         ///< max |dq|
  double forces = 1e-7;           ///< max |dF| / max |F| after the run
  double energies = 1e-7;         ///< |dE| / max(|E|, kinetic energy)
};

/// A real with 17 significant digits (reads back to the same bits), always with a '.' or an
/// exponent, so that TOML reads it as a float.
std::string real(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  std::string t = buf;
  if (t.find_first_of(".eEn") == std::string::npos) t += ".0";
  return t;
}

/// A tolerance: 3 significant digits.
std::string bound(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

std::string energiesText(const Energies& e) {
  return "{ kinetic = " + real(e.kinetic) + ", elastic = " + real(e.elastic) +
         ", coulomb = " + real(e.coulomb) + " }";
}

/// One row per particle id of the columns `cols` (each of size n), with a trailing "# id".
std::string rowsText(const std::vector<const std::vector<double>*>& cols, std::size_t n) {
  std::string t = "[\n";
  for (std::size_t i = 0; i < n; ++i) {
    t += "  [";
    for (std::size_t c = 0; c < cols.size(); ++c) t += (c ? ", " : "") + real((*cols[c])[i]);
    t += "],  # " + std::to_string(i) + "\n";
  }
  return t + "]\n";
}

/// The text of a reference file.
std::string referenceText(const ReferenceCase& rc, const Outcome& o) {
  const std::size_t n = o.end.size();
  const Tolerance tol;
  const std::vector<double> f0x = slice(o.f0, 0, n), f0y = slice(o.f0, 1, n),
                            f0z = slice(o.f0, 2, n), f1x = slice(o.f1, 0, n),
                            f1y = slice(o.f1, 1, n), f1z = slice(o.f1, 2, n);
  const std::vector<double> u = unwrapped(o.end);
  const std::vector<double> ux = slice(u, 0, n), uy = slice(u, 1, n), uz = slice(u, 2, n);
  const std::vector<double> q = o.end.charge.empty() ? std::vector<double>(n, 0.0) : o.end.charge;
  std::ostringstream t;
  t << "# Golden values of the CPU backend for tests/md/test_backend.cpp, case \"" << rc.name
    << "\" (its\n# set-up: referenceCases() there). Written by\n"
    << "#     bash scripts/write_reference_states.sh\n"
    << "# after an intended change of the trajectory; review the change as a diff and say why in\n"
    << "# the commit. Reals have 17 significant digits: they read back to the same bits, and the\n"
    << "# CPU build must reproduce them exactly; the CUDA build within [tolerance].\n\n"
    << "case = \"" << rc.name << "\"\n"
    << "N = " << n << "\nsteps = " << rc.steps << "\n\n"
    << "[tolerance]  # the CUDA build's bounds (test_backend.cpp, Tolerance)\n"
    << "initial_forces = " << bound(tol.initial_forces) << "  # max |dF| / max |F|\n"
    << "positions = " << bound(tol.positions) << "  # max |dx| (d)\n"
    << "velocities = " << bound(tol.velocities) << "  # max |dv| / max |v|\n"
    << "charges = " << bound(tol.charges) << "  # max |dq|\n"
    << "forces = " << bound(tol.forces) << "  # after the run: max |dF| / max |F|\n"
    << "energies = " << bound(tol.energies) << "  # |dE| / max(|E|, E_kin)\n\n"
    << "[initial]  # the state given (step 0)\n"
    << "energies = " << energiesText(o.e0) << "\n"
    << "# per particle id: fx, fy, fz\n"
    << "forces = " << rowsText({&f0x, &f0y, &f0z}, n) << "\n"
    << "[final]  # after `steps` steps\n"
    << "step = " << o.end.step << "\ntime = " << real(o.end.time) << "\n"
    << "energies = " << energiesText(o.e1) << "\n"
    << "# per particle id: x, y, z (unwrapped: x + image L), vx, vy, vz, q, fx, fy, fz\n"
    << "particles = "
    << rowsText({&ux, &uy, &uz, &o.end.vx, &o.end.vy, &o.end.vz, &q, &f1x, &f1y, &f1z}, n);
  return t.str();
}

/// A reference file read back.
struct Reference {
  std::int64_t step = 0;
  std::vector<double> f0, f1, x, v, q;  // x, y, z blocks as unwrapped() and velocities() give
  Energies e0, e1;
  Tolerance tol;
};

double number(const toml::node_view<const toml::node>& node, const std::string& what) {
  const auto x = node.value<double>();
  if (!x) FAIL("reference file: " << what << " is not a number");
  return *x;
}

Energies readEnergies(const toml::node_view<const toml::node>& t, const std::string& what) {
  return {number(t["kinetic"], what + ".kinetic"), number(t["elastic"], what + ".elastic"),
          number(t["coulomb"], what + ".coulomb")};
}

/// Columns [first, first + count) of a per-particle table, as blocks of n values each.
std::vector<double> columns(const toml::array& rows, std::size_t first, std::size_t count) {
  const std::size_t n = rows.size();
  std::vector<double> out(count * n);
  for (std::size_t i = 0; i < n; ++i) {
    const toml::array* row = rows[i].as_array();
    if (!row || row->size() < first + count)
      FAIL("reference file: row " << i << " has fewer than " << first + count << " values");
    for (std::size_t c = 0; c < count; ++c)
      out[c * n + i] = number(toml::node_view<const toml::node>(row->get(first + c)), "a value");
  }
  return out;
}

Reference readReference(const std::string& path) {
  const toml::table t = toml::parse_file(path);
  Reference r;
  const auto* f0 = t["initial"]["forces"].as_array();
  const auto* rows = t["final"]["particles"].as_array();
  REQUIRE(f0);
  REQUIRE(rows);
  r.f0 = columns(*f0, 0, 3);
  r.x = columns(*rows, 0, 3);
  r.v = columns(*rows, 3, 3);
  r.q = columns(*rows, 6, 1);
  r.f1 = columns(*rows, 7, 3);
  r.step = t["final"]["step"].value_or<std::int64_t>(-1);
  r.e0 = readEnergies(t["initial"]["energies"], "initial.energies");
  r.e1 = readEnergies(t["final"]["energies"], "final.energies");
  const auto tol = t["tolerance"];
  r.tol = {number(tol["initial_forces"], "tolerance.initial_forces"),
           number(tol["positions"], "tolerance.positions"),
           number(tol["velocities"], "tolerance.velocities"),
           number(tol["charges"], "tolerance.charges"), number(tol["forces"], "tolerance.forces"),
           number(tol["energies"], "tolerance.energies")};
  return r;
}

/// The largest relative energy difference, against max(|E|, the kinetic energy).
double energyDifference(const Energies& a, const Energies& b) {
  const double scale = std::max(std::fabs(b.kinetic), 1e-300);
  double d = 0.0;
  for (auto m : {&Energies::kinetic, &Energies::elastic, &Energies::coulomb})
    d = std::max(d, std::fabs(a.*m - b.*m) / std::max(std::fabs(b.*m), scale));
  return d;
}

/// Compares an outcome with the CPU backend's reference file (or writes the file when
/// the test binary runs with --write-reference, CPU build only).
void checkAgainstReference(const ReferenceCase& rc, const Outcome& o) {
  const std::string path = referencePath(rc.name);
  if (granagg::test::writeReference()) {
    REQUIRE_FALSE(CUDA_BUILD);  // the reference is the CPU backend's by definition
    std::ofstream(path) << referenceText(rc, o);
    WARN("wrote the reference " << path);
    return;
  }
  const Reference ref = readReference(path);
  const std::size_t n = o.end.size();
  REQUIRE(ref.x.size() == 3 * n);
  REQUIRE(ref.step == o.end.step);
  const std::vector<double> q = o.end.charge.empty() ? std::vector<double>(n, 0.0) : o.end.charge;

  const double f0 = maxAbsDiff(o.f0, ref.f0) / maxAbs(ref.f0);
  const double f1 = maxAbsDiff(o.f1, ref.f1) / maxAbs(ref.f1);
  const double dx = maxAbsDiff(unwrapped(o.end), ref.x);
  const double dv = maxAbsDiff(velocities(o.end), ref.v) / maxAbs(ref.v);
  const double dq = maxAbsDiff(q, ref.q);
  const double de = std::max(energyDifference(o.e0, ref.e0), energyDifference(o.e1, ref.e1));
  INFO(rc.name << " against the CPU reference: initial forces " << f0 << ", forces after "
               << o.end.step << " steps " << f1 << " (max |dF| / max |F|); positions " << dx
               << " d; velocities " << dv << " (relative); charges " << dq << "; energies " << de
               << " (relative)");
  if (!CUDA_BUILD) {
    // the build that wrote the reference: the same bits (positions, velocities, charges, forces,
    // energies)
    CHECK(f0 == 0.0);
    CHECK(f1 == 0.0);
    CHECK(dx == 0.0);
    CHECK(dv == 0.0);
    CHECK(dq == 0.0);
    CHECK(de == 0.0);
    return;
  }
  CHECK(f0 <= ref.tol.initial_forces);
  CHECK(dx <= ref.tol.positions);
  CHECK(dv <= ref.tol.velocities);
  CHECK(dq <= ref.tol.charges);
  CHECK(f1 <= ref.tol.forces);
  CHECK(de <= ref.tol.energies);
}

}  // namespace

TEST_CASE("engine contact forces equal a host brute-force sum over all pairs",
          "[md][backend][gpu]") {
  // 8^3 particles in a block wrapped around the box corner (every particle in contact with up to
  // 6 others, across faces, edges and the corner) plus 200 free ones; both contact laws.
  const Frame init = denseBlock(8, 200, 16.0, 3);
  MdConfig c;
  c.system.N = static_cast<int>(init.size());
  for (const std::string model : {"hertz", "spring_dashpot"}) {
    c.contact.model = model;
    Engine e(c, init, /*allow_contacts=*/true);
    const std::vector<double> f = joined(e.forces());
    int pairs = 0;
    const std::vector<double> ref =
        model == "hertz"
            ? bruteForceContacts<HertzViscoelastic>(
                  init, HertzViscoelastic::Params{c.contact.E, c.contact.D, c.contact.clamp}, pairs)
            : bruteForceContacts<SpringDashpot>(
                  init,
                  SpringDashpot::makeParams(c.contact.stiffness, c.contact.restitution,
                                            c.contact.clamp),
                  pairs);
    REQUIRE(pairs > 1000);  // 3 x 7 x 8 x 8 face neighbours in the block
    const double err = maxAbsDiff(f, ref) / maxAbs(ref);
    INFO(model << ": " << pairs << " pairs in contact; max |F_engine - F_brute| / max |F| = " << err
               << " on " << Engine::backendDescription());
    CHECK(err <= 1e-12);
  }
}

TEST_CASE("forces and a short trajectory equal the CPU backend's reference", "[md][backend][gpu]") {
  for (const ReferenceCase& rc : referenceCases()) {
    INFO(rc.name);
    checkAgainstReference(rc, runCase(rc.config, rc.init, rc.allow_contacts, rc.steps,
                                      /*with_energies=*/true));
  }
}

TEST_CASE("the reference runs are short enough for a round-off difference to stay small",
          "[md][backend][gpu]") {
  // The basis of the GPU tolerances above: perturb every coordinate by a relative 1e-15 (random
  // sign; the size of one rounding) and run each reference case again on this backend. Measured on
  // the CPU: the largest position difference grows 24-fold (dense gas, 300 steps) and 6.5-fold
  // (charged gas, 200 steps). Round-off injected at every step adds at most steps x that, far
  // below the 1e-9 d allowed. Fails if a change of the cases makes them chaotic on this scale.
  for (const ReferenceCase& rc : referenceCases()) {
    const Outcome a = runCase(rc.config, rc.init, rc.allow_contacts, rc.steps);
    Frame p = rc.init;
    std::mt19937_64 rng(1);
    for (auto* v : {&p.x, &p.y, &p.z})
      for (double& x : *v) x *= 1.0 + ((rng() & 1) ? 1e-15 : -1e-15);
    const Outcome b = runCase(rc.config, p, rc.allow_contacts, rc.steps);
    const double d0 = maxAbsDiff(unwrapped(rc.init), unwrapped(p));
    const double d1 = maxAbsDiff(unwrapped(a.end), unwrapped(b.end));
    INFO(rc.name << ": position difference " << d0 << " -> " << d1 << " d after " << rc.steps
                 << " steps (t = " << a.end.time << ")");
    CHECK(d1 <= 100 * d0);
  }
}
