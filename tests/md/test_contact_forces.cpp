// Contact physics: the HD potential functions against closed forms, and the neighbour-list
// launcher against a brute-force O(N^2) host loop calling the same functions.
#include <catch2/catch.hpp>

#include <variant>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "common/Box.h"
#include "md/compute/ContactForce.h"
#include "md/coulomb/RealSpace.h"
#include "md/integrate/VelocityVerlet.h"
#include "md/neighbor/NeighborList.h"
#include "md/potentials/ContactModels.h"
#include "md/potentials/HertzViscoelastic.h"
#include "md/potentials/SpringDashpot.h"

using namespace granagg;
using namespace granagg::md;

TEST_CASE("contact potentials: force is -dV/dxi, clamping, spring-dashpot restitution",
          "[md][potential]") {
  const HertzViscoelastic::Params h{278.6, 0.0, true};
  for (double xi : {1e-4, 1e-3, 0.01, 0.05}) {
    const double dx = 1e-6 * xi;
    const double dV = (HertzViscoelastic::elasticEnergy(xi + dx, h) -
                       HertzViscoelastic::elasticEnergy(xi - dx, h)) /
                      (2 * dx);
    CHECK(HertzViscoelastic::normalForce(xi, 0.0, h) == Approx(dV).epsilon(1e-8));
    CHECK(HertzViscoelastic::normalForce(xi, 0.0, h) ==
          Approx(278.6 * std::pow(xi, 1.5)).epsilon(1e-14));
  }
  const HertzViscoelastic::Params hc{278.6, 27.7, true}, hu{278.6, 27.7, false};
  // receding fast near the end of the contact: E xi^{3/2} + D xi^{1/2} xi' < 0
  CHECK(HertzViscoelastic::normalForce(1e-4, -1.0, hc) == 0.0);
  CHECK(HertzViscoelastic::normalForce(1e-4, -1.0, hu) ==
        Approx(std::sqrt(1e-4) * (278.6e-4 - 27.7)).epsilon(1e-14));
  // docs/model.md section 6: t_c = 0.23 for v = 1.6 at the defaults
  CHECK(HertzViscoelastic::contactTime(1.6, hc) == Approx(0.233).margin(0.001));

  const auto sd = SpringDashpot::makeParams(1e4, 0.9, false);
  // closed form epsilon = exp(-pi zeta / omega) with zeta = gamma/(2 m_eff), omega^2 = k/m_eff -
  // zeta^2
  const double zeta = sd.gamma, omega = std::sqrt(2 * sd.k - zeta * zeta);
  CHECK(std::exp(-M_PI * zeta / omega) == Approx(0.9).epsilon(1e-14));
  CHECK(SpringDashpot::contactTime(sd) == Approx(M_PI / omega).epsilon(1e-14));
  CHECK_THROWS_AS(SpringDashpot::makeParams(1e4, 1.5, false), std::invalid_argument);
  CHECK_THROWS_AS(SpringDashpot::makeParams(-1, 0.5, false), std::invalid_argument);
}

namespace {
ContactModel hertzModel(const HertzViscoelastic::Params& p) {
  return Contact<HertzViscoelastic>{p};
}
ParticleData makeParticles(const std::vector<double>& pos, const std::vector<double>& vel) {
  const std::size_t n = pos.size() / 3;
  ParticleData p;
  p.resize(n);
  std::vector<double> P[3], V[3];
  for (int c = 0; c < 3; ++c)
    for (std::size_t i = 0; i < n; ++i) {
      P[c].push_back(pos[3 * i + c]);
      V[c].push_back(vel[3 * i + c]);
    }
  packVec3(V[0], V[1], V[2], p.vel);
  p.setPositions(P[0], P[1], P[2], {});
  return p;
}

/// Brute-force reference: every pair, minimum image, the same HD function.
void bruteForce(const std::vector<double>& pos, const std::vector<double>& vel, double L,
                const HertzViscoelastic::Params& prm, std::vector<double>& f, int& pairs) {
  const std::size_t n = pos.size() / 3;
  common::Box box{L};
  f.assign(3 * n, 0.0);
  pairs = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      double r[3], g[3];
      for (int c = 0; c < 3; ++c) {
        r[c] = box.minimumImage(pos[3 * i + c] - pos[3 * j + c]);
        g[c] = vel[3 * i + c] - vel[3 * j + c];
      }
      const double d = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      if (d >= 1.0) continue;
      pairs += (j > i);
      const double xi_dot = -(g[0] * r[0] + g[1] * r[1] + g[2] * r[2]) / d;
      const double F = HertzViscoelastic::normalForce(1.0 - d, xi_dot, prm);
      for (int c = 0; c < 3; ++c) f[3 * i + c] += F * r[c] / d;
    }
}

void compareWithBruteForce(const std::vector<double>& pos, const std::vector<double>& vel, double L,
                           bool flat, std::vector<double>& out);

/// Both force passes (per-row loops, and one loop over the compressed list per block) against
/// the reference, and against each other to the bit.
void compareWithBruteForce(const std::vector<double>& pos, const std::vector<double>& vel,
                           double L) {
  std::vector<double> forces[2];
  for (bool flat : {false, true}) {
    INFO((flat ? "compressed-list pass" : "per-row pass"));
    compareWithBruteForce(pos, vel, L, flat, forces[flat]);
  }
  CHECK(forces[0] == forces[1]);
}

void compareWithBruteForce(const std::vector<double>& pos, const std::vector<double>& vel, double L,
                           bool flat, std::vector<double>& out) {
  const HertzViscoelastic::Params prm{278.6, 27.7, true};
  ParticleData p = makeParticles(pos, vel);
  common::Box box{L};
  NeighborList nl(1.0, 0.3);
  nl.keepPairs(flat);
  nl.build(p, box);
  REQUIRE(nl.hasPairs() == flat);
  ContactWork w;
  // dt = 0: a state at full step, so the predicted velocities equal v, as in the reference. Overlap
  // bound 1 (no bound: random placements overlap deeply), so a flag can only mean a non-finite
  // force.
  ContactStep st;
  st.dt = 0.0;
  st.max_overlap = 1.0;
  const auto flags = computeContactForces(p, nl, box, hertzModel(prm), st, w);
  CHECK(flags.worst == 0);
  std::vector<double> ref;
  int pairs;
  bruteForce(pos, vel, L, prm, ref, pairs);
  REQUIRE(pairs > 10);  // the configuration must actually test contacts
  const std::size_t n = pos.size() / 3;
  std::vector<double> fx(n), fy(n), fz(n);
  DVec<double> dfx, dfy, dfz;
  unpackVec3(p.force, dfx, dfy, dfz);
  thrust::copy(dfx.begin(), dfx.end(), fx.begin());
  thrust::copy(dfy.begin(), dfy.end(), fy.begin());
  thrust::copy(dfz.begin(), dfz.end(), fz.begin());
  out = fx;
  out.insert(out.end(), fy.begin(), fy.end());
  out.insert(out.end(), fz.begin(), fz.end());
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double a[3] = {fx[i], fy[i], fz[i]};
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, std::fabs(a[c] - ref[3 * i + c]));
      scale = std::max(scale, std::fabs(ref[3 * i + c]));
    }
  }
  INFO("pairs in contact: " << pairs << ", max |F_nl - F_brute| / max |F| = " << worst / scale);
  CHECK(worst <= 1e-12 * scale);
  // Newton's third law: the total force vanishes
  double tot[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    tot[0] += fx[i];
    tot[1] += fy[i];
    tot[2] += fz[i];
  }
  for (double t : tot) CHECK(std::fabs(t) <= 1e-12 * scale * n);
}
/// n particles placed independently at random in [0, L)^3 (overlaps included) with velocity
/// components uniform in [-2, 2], from seed.
void randomGas(unsigned seed, int n, double L, std::vector<double>& pos, std::vector<double>& vel) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, L), v(-2.0, 2.0);
  pos.clear();
  vel.clear();
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      pos.push_back(u(rng));
      vel.push_back(v(rng));
    }
}
}  // namespace

TEST_CASE("neighbour-list forces equal brute force on a random configuration", "[md][neighbor]") {
  // 600 particles placed independently at random (phi ~ 0.1): many overlapping pairs, some across
  // every periodic face; random velocities exercise the dissipative term.
  const double L = 14.5;
  std::vector<double> pos, vel;
  randomGas(11, 600, L, pos, vel);
  compareWithBruteForce(pos, vel, L);
}

TEST_CASE("neighbour-list forces equal brute force in dense clusters across the boundary",
          "[md][neighbor]") {
  // Dense blobs (many neighbours per particle, exercising row-capacity growth) centred on a corner
  // and on a face, so that contacts wrap across faces, edges and the corner.
  std::mt19937_64 rng(5);
  const double L = 12.0;
  std::normal_distribution<double> g(0.0, 0.9);
  std::uniform_real_distribution<double> v(-1.0, 1.0);
  std::vector<double> pos, vel;
  const double centres[2][3] = {{0.0, 0.0, 0.0}, {6.0, 6.0, L - 0.2}};
  for (const auto& c : centres)
    for (int i = 0; i < 250; ++i)
      for (int k = 0; k < 3; ++k) {
        double x = std::fmod(c[k] + g(rng) + 10 * L, L);
        pos.push_back(x);
        vel.push_back(v(rng));
      }
  compareWithBruteForce(pos, vel, L);
}

TEST_CASE("the pair-form pass equals the per-row pass to the bit, collisions and charging included",
          "[md][neighbor]") {
  // The compressed pair form computes each contact once and hands the owner's force, negated, to
  // the partner; the per-row pass computes every contact from both sides. Both must give the same
  // forces, collision count and exchanged charges to the last bit (the contact arithmetic is
  // antisymmetric in i and j). A large step (dt = 0.15) makes many overlapping pairs count as
  // collisions that started this step, so the charge exchange runs for many pairs.
  const double L = 14.5;
  std::vector<double> pos, vel;
  randomGas(17, 600, L, pos, vel);
  const HertzViscoelastic::Params prm{278.6, 27.7, true};
  const common::Box box{L};
  std::vector<double> force[2], charge[2];
  std::int64_t collisions[2];
  for (bool paired : {false, true}) {
    ParticleData p = makeParticles(pos, vel);
    NeighborList nl(1.0, 0.3);
    nl.keepPairs(paired);
    nl.build(p, box);
    REQUIRE(nl.hasPairs() == paired);
    DVec<double> dq(p.size(), 0.0);
    ContactStep st;
    st.dt = 0.15;
    st.step = 123;
    st.charging.seed = 99;
    st.dq = raw(dq);
    ContactWork w;
    const ContactStepResult r = computeContactForces(p, nl, box, hertzModel(prm), st, w);
    REQUIRE(r.worst == 0);
    collisions[paired] = r.collisions;
    DVec<double> fx, fy, fz;
    unpackVec3(p.force, fx, fy, fz);
    for (auto* c : {&fx, &fy, &fz}) force[paired].insert(force[paired].end(), c->begin(), c->end());
    charge[paired].assign(dq.begin(), dq.end());
  }
  INFO("collisions this step: " << collisions[0]);
  REQUIRE(collisions[0] > 20);
  CHECK(collisions[1] == collisions[0]);
  CHECK(force[1] == force[0]);
  CHECK(charge[1] == charge[0]);
  int charged = 0;
  double total = 0.0, magnitude = 0.0;
  for (double q : charge[1]) {
    charged += q != 0.0;
    total += q;
    magnitude += std::fabs(q);
  }
  CHECK(charged > 20);
  CHECK(std::fabs(total) <=
        1e-14 * magnitude);  // every transfer leaves one partner and reaches the other
}

TEST_CASE("advancing the step in the force pass equals the separate kick-drift pass to the bit",
          "[md][neighbor][coulomb]") {
  // The force pass can also close the step and open the next (ContactStep::advance_dt), in the
  // per-row pass and in the pair form's gathering pass. Over three steps, each shape -- per row,
  // per row advancing, pair form, pair form advancing -- must give the forces, collisions,
  // exchanged charges, positions and velocities of the per-row pass followed by kickDrift(), to
  // the last bit, without and with the fast Coulomb part (which the per-row pass computes; the
  // pair form then falls back to it). Random charges of both signs, a slow force as the engine
  // passes it, a list out to r2 = 3.5 for the fast part (about 30 entries per row) and a large
  // step (dt = 0.05, many pairs overlapping) make every branch run: attraction, repulsion and
  // contacts that start this step, with the charge exchange.
  const double L = 14.5, dt = 0.05;
  std::vector<double> pos, vel;
  randomGas(23, 600, L, pos, vel);
  std::mt19937_64 rng(37);
  std::uniform_real_distribution<double> uq(-1.0, 1.0);
  std::vector<double> q(600), x[3];
  for (double& c : q) c = uq(rng);
  DVec<double> ext[3];  // a slow force, as the engine always passes with the fast part
  for (auto& e : ext)
    for (std::size_t i = 0; i < q.size(); ++i) e.push_back(0.1 * uq(rng));
  for (int c = 0; c < 3; ++c)
    for (std::size_t i = 0; i < q.size(); ++i) x[c].push_back(pos[3 * i + c]);
  const HertzViscoelastic::Params prm{278.6, 27.7, true};
  const common::Box box{L};
  const auto values = fastPairTableValues(RealSpaceSwitch{2.5, 3.5});
  const DVec<double> table(values.begin(), values.end());
  const auto same3 = [](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const Vec3& u, const Vec3& v) {
      return u.x == v.x && u.y == v.y && u.z == v.z;
    });
  };
  const auto same4 = [](const std::vector<Scalar4>& a, const std::vector<Scalar4>& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                      [](const Scalar4& u, const Scalar4& v) {
                        return u.x == v.x && u.y == v.y && u.z == v.z && u.w == v.w;
                      });
  };
  std::vector<Vec3> vel_without_fast;
  for (bool fast : {false, true}) {
    const RealSpaceSwitch sw = fast ? RealSpaceSwitch{2.5, 3.5} : RealSpaceSwitch{};
    struct Outcome {
      std::vector<Vec3> force, vel;
      std::vector<Scalar4> pos;
      std::vector<double> charge;
      std::int64_t collisions = 0;
    } out[4];
    for (int shape = 0; shape < 4; ++shape) {  // per row, advancing; pair form, advancing
      INFO("fast Coulomb part " << fast << ", pass shape " << shape);
      const bool paired = shape >= 2, advancing = shape % 2 == 1;
      ParticleData p = makeParticles(pos, vel);
      p.setPositions(x[0], x[1], x[2], q);
      NeighborList nl(fast ? sw.r2 : 1.0, 0.3);
      nl.keepPairs(paired);
      nl.build(p, box);
      DVec<double> dq(p.size(), 0.0), block_max;
      ContactWork w;
      ContactStep st;
      st.max_overlap = 2.0;
      st.charging.seed = 99;
      st.charging.Q = 0.05;
      st.charging.kappa = 0.83;
      st.dq = raw(dq);
      st.ext_fx = raw(ext[0]);
      st.ext_fy = raw(ext[1]);
      st.ext_fz = raw(ext[2]);
      st.ext_predict_scale = 0.25 * dt;  // as at a step after a slow one (ContactStep)
      if (fast) {
        st.fast = sw;
        st.fast_table = pairTable(raw(table), sw.r2 * sw.r2, FAST_PAIR_TABLE_INTERVALS);
        st.coulomb_K = 5.0;
      }
      // a state given at full step, the opening pass, then three steps
      REQUIRE(computeContactForces(p, nl, box, hertzModel(prm), st, w).worst == 0);
      kickDrift(p, 0.5 * dt, dt, box, false, raw(dq), block_max);
      st.dt = dt;
      for (int s = 1; s <= 3; ++s) {
        st.step = 100 + s;
        st.advance_dt = advancing ? dt : 0.0;
        const ContactStepResult r = computeContactForces(p, nl, box, hertzModel(prm), st, w);
        REQUIRE(r.worst == 0);
        out[shape].collisions += r.collisions;
        if (!advancing) kickDrift(p, 0.5 * dt, dt, box, true, raw(dq), block_max);
      }
      out[shape].force.assign(p.force.begin(), p.force.end());
      out[shape].vel.assign(p.vel.begin(), p.vel.end());
      out[shape].pos.assign(p.pos.begin(), p.pos.end());
      out[shape].charge.assign(dq.begin(), dq.end());
    }
    INFO("fast Coulomb part " << fast << "; collisions in three steps: " << out[0].collisions);
    REQUIRE(out[0].collisions > 20);
    int moved = 0;  // the exchange ran: kickDrift applied dq to the charges (pos.w)
    for (std::size_t i = 0; i < q.size(); ++i) moved += out[0].pos[i].w != q[i];
    CHECK(moved > 20);
    if (fast) {  // the fast part acts: the same steps without it end elsewhere
      CHECK_FALSE(same3(out[0].vel, vel_without_fast));
    } else {
      vel_without_fast = out[0].vel;
    }
    for (int shape = 1; shape < 4; ++shape) {
      INFO("pass shape " << shape << " against the per-row pass and kickDrift()");
      CHECK(out[shape].collisions == out[0].collisions);
      CHECK(same3(out[shape].force, out[0].force));
      CHECK(same3(out[shape].vel, out[0].vel));
      CHECK(same4(out[shape].pos, out[0].pos));
      CHECK(out[shape].charge == out[0].charge);
    }
  }
}

TEST_CASE(
    "a non-finite contact force is flagged by every pass shape, and an advancing pass then moves "
    "nothing",
    "[md][neighbor]") {
  // Two particles at the same point: r = 0, so the unit vector and the force are NaN. The pair-form
  // passes check the finiteness of the contact forces where they compute them, the per-row pass
  // that of every force and position; all must flag it.
  const double L = 14.5;
  std::vector<double> pos, vel;
  randomGas(41, 200, L, pos, vel);
  for (int c = 0; c < 3; ++c) pos[3 * 7 + c] = pos[3 * 3 + c];  // particle 7 on top of particle 3
  const HertzViscoelastic::Params prm{278.6, 27.7, true};
  const common::Box box{L};
  for (int shape = 0; shape < 3; ++shape) {  // per row; pair form; pair form advancing the step
    INFO("pass shape " << shape);
    ParticleData p = makeParticles(pos, vel);
    NeighborList nl(1.0, 0.3);
    nl.keepPairs(shape > 0);
    nl.build(p, box);
    ContactWork w;
    ContactStep st;
    st.dt = 0.002;
    st.max_overlap = 2.0;  // no overlap bound: only the NaN can flag
    st.displacement_bound = 0.0;
    if (shape == 2) st.advance_dt = st.dt;
    const std::vector<Scalar4> before(p.pos.begin(), p.pos.end());
    const ContactStepResult r = computeContactForces(p, nl, box, hertzModel(prm), st, w);
    CHECK(r.worst == 1);
    const std::vector<Scalar4> after(p.pos.begin(), p.pos.end());
    bool unchanged = true;
    for (std::size_t i = 0; i < after.size(); ++i)
      unchanged = unchanged && after[i].x == before[i].x;
    CHECK(unchanged);
    const std::vector<Vec3> f(p.force.begin(), p.force.end());
    CHECK(std::isnan(f[3].x + f[3].y + f[3].z));
    CHECK(std::isnan(f[7].x + f[7].y + f[7].z));
  }
}

TEST_CASE("pairs screened only once the displacement bound allows a contact: no contact is missed",
          "[md][neighbor]") {
  // With ContactStep::displacement_bound the pair-form pass skips a pair until the bound has grown
  // by half its gap to contact. Every particle moves at the same speed v0 in a random direction,
  // so head-on pairs close at nearly 2 v0, the rate the factor 1/2 is there for. The particles
  // drift freely (no forces applied: the screening, not the physics, is under test) and pass
  // through one another, so contacts start and end all the time. At every step the pass with the
  // bound must give exactly the forces and collisions of the pass that screens every pair; the list
  // is rebuilt whenever the bound reaches skin / 2, as in the engine.
  const double L = 14.5, v0 = 2.0, dt = 0.01, skin = 0.4;
  std::vector<double> pos, vel;
  randomGas(29, 600, L, pos, vel);
  std::mt19937_64 rng(31);
  std::normal_distribution<double> g(0.0, 1.0);
  for (std::size_t i = 0; i < vel.size(); i += 3) {
    double d[3] = {g(rng), g(rng), g(rng)};
    const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; ++c) vel[i + c] = v0 * d[c] / norm;
  }
  const HertzViscoelastic::Params prm{278.6, 27.7, true};
  const common::Box box{L};
  ParticleData screened = makeParticles(pos, vel), every = makeParticles(pos, vel);
  NeighborList nl(1.0, skin);
  nl.keepPairs(true);
  ContactWork w_screened, w_every;
  const double rounding =
      2.0 * (std::nextafter(L, 2.0 * L) - L);  // as the engine's bound (Engine.cpp)
  double bound = 0.0;
  std::int64_t collisions = 0;
  int builds = 0;
  for (int step = 0; step < 300; ++step) {
    if (step == 0 || bound > 0.5 * skin) {
      nl.build(screened, box);
      bound = 0.0;
      ++builds;
    }
    ContactStep st;
    st.dt = step == 0 ? 0.0 : dt;
    st.max_overlap = 2.0;  // free flight overlaps deeply
    st.displacement_bound = bound;
    const ContactStepResult a =
        computeContactForces(screened, nl, box, hertzModel(prm), st, w_screened);
    st.displacement_bound = -1.0;
    const ContactStepResult b = computeContactForces(every, nl, box, hertzModel(prm), st, w_every);
    REQUIRE(a.worst == 0);
    REQUIRE(a.collisions == b.collisions);
    const std::vector<Vec3> fa(screened.force.begin(), screened.force.end()),
        fb(every.force.begin(), every.force.end());
    bool same = true;
    for (std::size_t i = 0; i < fa.size(); ++i)
      same = same && fa[i].x == fb[i].x && fa[i].y == fb[i].y && fa[i].z == fb[i].z;
    INFO("step " << step);
    REQUIRE(same);
    collisions += a.collisions;
    for (std::size_t k = 0; k < pos.size(); ++k) pos[k] = std::fmod(pos[k] + dt * vel[k] + L, L);
    std::vector<double> P[3];
    for (int c = 0; c < 3; ++c)
      for (std::size_t i = 0; i < pos.size() / 3; ++i) P[c].push_back(pos[3 * i + c]);
    screened.setPositions(P[0], P[1], P[2], {});
    every.setPositions(P[0], P[1], P[2], {});
    bound += dt * v0 + rounding;
  }
  INFO("collisions " << collisions << ", list builds " << builds);
  CHECK(collisions > 500);
  CHECK(builds > 10);
}

TEST_CASE("the build on cell-sorted storage (the engine's) finds exactly the pairs within range",
          "[md][neighbor]") {
  // The engine stores particles in cell order and builds with buildSorted, whose cell search reads
  // candidates from consecutive slots and skips the minimum image for particles away from the
  // faces. Rows are compared, in particle ids, with an O(N^2) search; a gas plus blobs at a corner
  // (contacts across faces, edges and the corner) and in the middle of the box.
  std::mt19937_64 rng(23);
  const double L = 11.0;
  const common::Box box{L};
  std::uniform_real_distribution<double> u(0.0, L);
  std::normal_distribution<double> g(0.0, 0.7);
  std::vector<double> pos;
  for (int k = 0; k < 3 * 150; ++k) pos.push_back(u(rng));
  for (double centre : {0.0, 5.5})
    for (int k = 0; k < 3 * 120; ++k) pos.push_back(std::fmod(centre + g(rng) + 10 * L, L));
  const std::size_t n = pos.size() / 3;
  const std::vector<double> zero(pos.size(), 0.0);
  NeighborList nl(1.0, 0.3);
  nl.keepPairs(true);
  ParticleData unsorted = makeParticles(pos, zero);
  const DVec<int>& order_d = nl.computeCellOrder(unsorted, box);
  REQUIRE(order_d.size() == n);
  const std::vector<int> order(order_d.begin(), order_d.end());  // slot s holds particle order[s]
  std::vector<double> sorted_pos;
  for (std::size_t s = 0; s < n; ++s)
    for (int c = 0; c < 3; ++c) sorted_pos.push_back(pos[3 * order[s] + c]);
  ParticleData p = makeParticles(sorted_pos, zero);
  p.id.assign(order.begin(), order.end());
  nl.buildSorted(p, box);
  std::vector<int> rows(n * nl.capacity()), counts(n);
  thrust::copy(thrust::device_pointer_cast(nl.rows()),
               thrust::device_pointer_cast(nl.rows()) + rows.size(), rows.begin());
  thrust::copy(thrust::device_pointer_cast(nl.counts()),
               thrust::device_pointer_cast(nl.counts()) + n, counts.begin());
  std::size_t entries = 0;
  for (std::size_t s = 0; s < n; ++s) {
    const int i = order[s];
    std::vector<int> got, expected;
    for (int k = 0; k < counts[s]; ++k) got.push_back(order[rows[s * nl.capacity() + k]]);
    for (std::size_t j = 0; j < n; ++j) {
      if (static_cast<int>(j) == i) continue;
      double r2 = 0.0;
      for (int c = 0; c < 3; ++c) {
        const double d = box.minimumImage(pos[3 * i + c] - pos[3 * j + c]);
        r2 += d * d;
      }
      if (r2 < 1.3 * 1.3) expected.push_back(static_cast<int>(j));
    }
    INFO("particle " << i << " in slot " << s);
    CHECK(std::is_sorted(got.begin(), got.end()));  // rows in id order (fixed sum order)
    CHECK(got == expected);
    entries += got.size();
  }
  CHECK(entries > 2 * n);  // the blobs give long rows
  REQUIRE(nl.hasPairs());
  CHECK(2 * nl.pairCount() == entries);
}

TEST_CASE("a box too small for the neighbour range is refused", "[md][neighbor]") {
  ParticleData p = makeParticles({0.1, 0.1, 0.1, 1.5, 0.1, 0.1}, {0, 0, 0, 0, 0, 0});
  NeighborList nl(1.0, 0.3);
  CHECK_THROWS_WITH(nl.build(p, common::Box{2.4}),
                    Catch::Contains("smaller than twice the neighbour range"));
}

TEST_CASE("neighbour rows hold exactly the pairs within range across capacity shrinks and growth",
          "[md][neighbor]") {
  // Rows are checked entry by entry against an O(N^2) pair search, on one list object that first
  // sees a sparse gas (its row capacity shrinks after the first build, which must only affect the
  // next build's layout), then a dense blob (capacity grows).
  std::mt19937_64 rng(3);
  const double L = 10.0;
  NeighborList nl(1.0, 0.3);
  nl.keepPairs(true);
  const common::Box box{L};
  auto check = [&](const std::vector<double>& pos) {
    ParticleData p = makeParticles(pos, std::vector<double>(pos.size(), 0.0));
    nl.build(p, box);
    const std::size_t n = pos.size() / 3;
    std::vector<int> rows(n * nl.capacity()), counts(n);
    thrust::copy(thrust::device_pointer_cast(nl.rows()),
                 thrust::device_pointer_cast(nl.rows()) + rows.size(), rows.begin());
    thrust::copy(thrust::device_pointer_cast(nl.counts()),
                 thrust::device_pointer_cast(nl.counts()) + n, counts.begin());
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<int> expected,
          got(rows.begin() + i * nl.capacity(), rows.begin() + i * nl.capacity() + counts[i]);
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i) continue;
        double r2 = 0.0;
        for (int c = 0; c < 3; ++c) {
          const double d = box.minimumImage(pos[3 * i + c] - pos[3 * j + c]);
          r2 += d * d;
        }
        if (r2 < 1.3 * 1.3) expected.push_back(static_cast<int>(j));
      }
      std::sort(got.begin(), got.end());  // rows are sorted by id = slot here anyway
      INFO("particle " << i << ", capacity " << nl.capacity());
      REQUIRE(got == expected);
    }
    // the compressed pair form (keepPairs): the rows back to back as entries, each pair once
    // (owned by its lower slot, in the owner's row order), and every entry mapped to its pair
    REQUIRE(nl.hasPairs());
    auto fetch = [](const int* d, std::size_t count) {
      std::vector<int> h(count);
      thrust::copy(thrust::device_pointer_cast(d), thrust::device_pointer_cast(d) + count,
                   h.begin());
      return h;
    };
    const std::vector<int> eoff = fetch(nl.entryOffsets(), n + 1),
                           poff = fetch(nl.pairOffsets(), n + 1);
    REQUIRE(eoff[n] == 2 * poff[n]);
    REQUIRE(nl.pairCount() == static_cast<std::size_t>(poff[n]));
    const std::vector<int> eowners = fetch(nl.entryOwners(), eoff[n]),
                           epairs = fetch(nl.entryPairs(), eoff[n]);
    const std::vector<int> powners = fetch(nl.pairOwners(), poff[n]),
                           ppartners = fetch(nl.pairPartners(), poff[n]);
    const std::vector<int> pentries = fetch(nl.pairEntries(), 2 * poff[n]);
    std::vector<int> seen(poff[n], 0);
    for (std::size_t i = 0; i < n; ++i) {
      REQUIRE(eoff[i + 1] - eoff[i] == counts[i]);
      std::vector<int> owned;
      for (int k = 0; k < counts[i]; ++k) {
        const int e = eoff[i] + k, j = rows[i * nl.capacity() + k];
        CHECK(eowners[e] == static_cast<int>(i));
        const int q = epairs[e], pr = q < 0 ? ~q : q;
        REQUIRE(pr < poff[n]);
        ++seen[pr];
        CHECK((q >= 0) == (j > static_cast<int>(i)));  // owned by the lower slot
        CHECK(powners[pr] == std::min(static_cast<int>(i), j));
        CHECK(ppartners[pr] == std::max(static_cast<int>(i), j));
        CHECK(pentries[2 * pr + (q < 0)] == e);  // and the pair knows this entry
        if (j > static_cast<int>(i)) owned.push_back(pr);
      }
      std::vector<int> range(poff[i + 1] - poff[i]);
      std::iota(range.begin(), range.end(), poff[i]);
      CHECK(owned == range);  // the owner's pairs, in its row order
    }
    for (int c : seen) CHECK(c == 2);  // each pair reached from both rows
  };
  std::uniform_real_distribution<double> u(0.0, L);
  std::vector<double> sparse;
  for (int k = 0; k < 3 * 60; ++k) sparse.push_back(u(rng));
  check(sparse);
  check(sparse);  // second build with the shrunk capacity
  std::normal_distribution<double> g(5.0, 0.8);
  std::vector<double> dense = sparse;
  for (int k = 0; k < 3 * 200; ++k) dense.push_back(std::fmod(g(rng) + L, L));
  check(dense);  // overflow: capacity grows, list rebuilt
  check(sparse);
  // A row filled exactly to the capacity, with candidates out of range scanned after its last
  // entry: the cell search appends without branching (a miss is written past the entries and not
  // counted) and must never write into a full row. Particle 0 gets `cap` partners at 1.25 (1.3
  // apart or more from each other), and 14 particles at 1.9-2.0 (in its 27 cells, out of range;
  // far from each other) are scanned around and after them.
  check(sparse);  // capacity shrunk again
  const int cap = nl.capacity();
  REQUIRE(cap < 16);
  std::vector<double> full = {5.0, 5.0, 5.0};
  for (int k = 0; k < cap; ++k) {  // golden-angle spiral on the sphere of radius 1.25
    const double z = -1.0 + (2.0 * k + 1.0) / cap, phi = 2.39996 * k, s = std::sqrt(1.0 - z * z);
    for (double c : {s * std::cos(phi), s * std::sin(phi), z}) full.push_back(5.0 + 1.25 * c);
  }
  for (int a = 0; a < 3; ++a)
    for (double sign : {-1.0, 1.0})
      for (int c = 0; c < 3; ++c) full.push_back(5.0 + (c == a ? 1.9 * sign : 0.0));
  for (int k = 0; k < 8; ++k)
    for (int c = 0; c < 3; ++c) full.push_back(5.0 + ((k >> c) & 1 ? 1.155 : -1.155));
  check(full);
  CHECK(nl.capacity() == cap);  // the row fitted exactly: no growth
}

TEST_CASE("contact.model selects a model from the one list, by its name", "[md][contact]") {
  CHECK(contactModelNames() == "\"hertz\", \"spring_dashpot\"");
  CHECK(isContactModel("hertz"));
  CHECK_FALSE(isContactModel("Hertz"));
  ContactConfig c;
  c.E = 100.0;
  c.D = 2.0;
  const ContactModel h = makeContactModel(c, 0.5);
  REQUIRE(std::holds_alternative<Contact<HertzViscoelastic>>(h));
  CHECK(std::get<Contact<HertzViscoelastic>>(h).params.E == 100.0);
  c.model = "spring_dashpot";
  c.stiffness = 1e4;
  c.restitution = 0.9;
  const ContactModel s = makeContactModel(c, 0.5);
  REQUIRE(std::holds_alternative<Contact<SpringDashpot>>(s));
  const auto& sd = std::get<Contact<SpringDashpot>>(s).params;
  CHECK(sd.k == 1e4);  // and the damping that gives restitution 0.9 (tested above)
  CHECK(sd.gamma == SpringDashpot::makeParams(1e4, 0.9, true, 0.5).gamma);
  c.model = "jkr";
  CHECK_THROWS_WITH(makeContactModel(c, 0.5), Catch::Contains("jkr"));
}
