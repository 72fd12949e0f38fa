/// \file Engine.cpp
/// md::Engine's public API (construction, run, state, observables, threads) and the per-step core
/// of Engine::Impl (EngineImpl.h): force pass, kick and drift. The neighbour lists (cell sort,
/// builds, skins) are in EngineLists.cpp, the checkpoint (its fields and the restart from it) in
/// EngineCheckpoint.cpp, the abort message in EngineAbort.cpp, the Coulomb part in
/// EngineCoulomb.cpp, the time-step control in EngineTimeStep.cpp.
#include "md/engine/Engine.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <thrust/fill.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/sequence.h>
#include <thrust/transform.h>

#if defined(__CUDACC__)
#include <cuda_runtime.h>
#else
#include <omp.h>
#endif

#include "common/Csv.h"
#include "md/engine/EngineImpl.h"
#include "md/engine/Launch.h"
#include "md/integrate/VelocityVerlet.h"

namespace granagg::md {

using engine_detail::CombineVelocitySums;
using engine_detail::M_EFF;
using engine_detail::toDevice;
using engine_detail::toHost;
using engine_detail::toHostById;
using engine_detail::VelocitySums;
using engine_detail::VelocitySumsOf;

namespace {
// coulomb.every_max = "auto": the slow interval grows to at most this many times coulomb.every
// (64 steps at the paper preset's dt), so that in the cold gas the interval is set by the gas's
// speeds, not by the cap: ensembles at caps 16, 32 and 64 are indistinguishable from the tight
// reference, and the cold gas's energy drift is at most 3e-5 of E_kin per 1000 steps at each
// (docs/benchmarks-coulomb.md).
constexpr int SLOW_INTERVAL_GROWTH = 16;

struct ChargeSums {
  double total = 0.0, abs_sum = 0.0, abs_max = 0.0;
};
struct ChargeOf {
  HD ChargeSums operator()(const Scalar4& r) const {
    const double a = r.w < 0.0 ? -r.w : r.w;
    return ChargeSums{r.w, a, a};
  }
};
struct CombineCharges {
  HD ChargeSums operator()(const ChargeSums& a, const ChargeSums& b) const {
    return ChargeSums{a.total + b.total, a.abs_sum + b.abs_sum,
                      a.abs_max > b.abs_max ? a.abs_max : b.abs_max};
  }
};
struct Axpy {  // v + a f
  double a;
  HD double operator()(double v, double f) const { return v + a * f; }
};
}  // namespace

Engine::Impl::Impl(const MdConfig& c) : cfg(c), nl(1.0, c.neighbor.skinCap()) {
  // contacts only: the force pass walks the compressed list (ContactForce.cpp)
  nl.keepPairs(true);
  exchange = c.charging.mode == "exchange";
  charging.seed = c.system.seed;
  charging.Q = c.charging.Q;
  charging.kappa = c.charging.kappa;
  charging.psi1_min = c.charging.psi1_min;
  charging.psi1_max = c.charging.psi1_max;
  charging.psi2_half_width = c.charging.psi2_fraction * c.charging.kappa;
  charging.m_eff = M_EFF;
}

void Engine::Impl::upload(const Frame& f) {
  p.setPositions(f.x, f.y, f.z, f.charge);
  packVec3(f.vx, f.vy, f.vz, p.vel);
  toDevice(f.ix, p.ix);
  toDevice(f.iy, p.iy);
  toDevice(f.iz, p.iz);
  p.id.resize(f.size());
  thrust::sequence(p.id.begin(), p.id.end());
  if (exchange) dq.assign(f.size(), 0.0);
}

ContactStep Engine::Impl::makeStep(double dt_taken, double slow_weight, double prev_weight) const {
  ContactStep st;
  st.dt = dt_taken;
  st.max_overlap = cfg.run.max_overlap;
  st.step = step;
  st.charging = charging;
  if (coulomb) {
    st.ext_fx = raw(slow_coulomb->force(0));
    st.ext_fy = raw(slow_coulomb->force(1));
    st.ext_fz = raw(slow_coulomb->force(2));
    st.ext_force_scale = slow_weight;
    // f_old holds prev_weight ext (ContactStep); with k = 1 both weights are 1 (the term
    // vanishes) and f_old's Coulomb part is the trend itself
    st.ext_predict_scale = 0.5 * dt_taken * (slow_weight - prev_weight);
    st.fast = slow_coulomb->fastSwitch();
    st.coulomb_K = cfg.coulomb.K;
    PairTable table;
    if (slow_coulomb->fastTable(table)) st.fast_table = table;
  }
  return st;
}

void Engine::Impl::computeForces(double dt_taken, bool advance) {
  // Displacements since the last build are at most the sum of dt max|u| over the steps (a
  // rigorous bound that needs no stored reference positions).
  const bool slow_due = coulomb && (slow.eval_step < 0 || step - slow.eval_step >= slow.every);
  const double prev_weight = coulomb ? slowWeight(step - 1) : 0.0;
  if (slow_due && nl_coul &&
      nl_coul->needsRebuild(p, drift_since_coul_build * drift_since_coul_build))
    rebuildList(true);
  else if (nl.needsRebuild(p, drift_since_build * drift_since_build))
    rebuildContactList();
  if (slow_due) evaluateCoulomb();
  ContactStep st = makeStep(dt_taken, coulomb ? slowWeight(step) : 0.0, prev_weight);
  st.dq = dqOrNull();
  st.displacement_bound = drift_since_build;
  if (advance) st.advance_dt = dt;
  PhaseTimer::Scope phase(&timer, PhaseTimer::ContactPass);
  const ContactStepResult r = computeContactForces(p, nl, box, contact, st, work);
  if (r.worst != 0) abort(r.worst);
  collisions += r.collisions;
  if (advance) driftTaken(r.max_u2);
}

void Engine::Impl::computeInitialForces() {
  thrust::fill(p.force.begin(), p.force.end(), Vec3{0.0, 0.0, 0.0});
  computeForces(0.0);
  close_pending = false;
}

void Engine::Impl::finishStep() {
  if (!close_pending) return;
  PhaseTimer::Scope phase(&timer, PhaseTimer::KickDrift);
  closeKick(p, 0.5 * dt, dqOrNull());
  close_pending = false;
}

void Engine::Impl::smoothVelocities(DVec<double>& sx, DVec<double>& sy, DVec<double>& sz) const {
  const double c = velocityOffset();
  DVec<double> v[3];
  unpackVec3(p.vel, v[0], v[1], v[2]);
  DVec<double>* out[3] = {&sx, &sy, &sz};
  for (int a = 0; a < 3; ++a) {
    out[a]->resize(p.size());
    const DVec<double>& f = slow_coulomb->force(a);
    thrust::transform(v[a].begin(), v[a].end(), f.begin(), out[a]->begin(), Axpy{-c});
  }
}

void Engine::Impl::driftTaken(double max_u2) {
  const double moved = dt * std::sqrt(max_u2) + 2.0 * (std::nextafter(box.L, 2.0 * box.L) - box.L);
  drift_since_build += moved;
  drift_since_coul_build += moved;
  tuner.observe(std::sqrt(max_u2));
  fresh_start = false;
  ++step;
  time = time_origin + static_cast<double>(step - step_origin) * dt;
}

void Engine::Impl::openStep() {
  PhaseTimer::Scope phase(&timer, PhaseTimer::KickDrift);
  driftTaken(kickDrift(p, 0.5 * dt, dt, box, close_pending, dqOrNull(), block_max));
  close_pending = false;
}

void Engine::Impl::advance(std::int64_t steps) {
  if (steps <= 0) return;
  openStep();
  for (std::int64_t s = 1; s < steps; ++s) computeForces(dt, true);
  computeForces(dt);
  close_pending = true;
}

Engine::Engine(const MdConfig& config, const Frame& init, bool allow_contacts)
    : m_impl(std::make_unique<Impl>(config)) {
  Impl& d = *m_impl;
  const std::size_t N = init.size();
  if (N < 2)
    throw std::invalid_argument("the initial state needs at least 2 particles (got " +
                                std::to_string(N) + ").");
  for (const auto* v : {&init.y, &init.z, &init.vx, &init.vy, &init.vz})
    if (v->size() != N)
      throw std::invalid_argument("initial state: position and velocity arrays differ in length.");
  if (!(init.box > 0.0) || !std::isfinite(init.box))
    throw std::invalid_argument("initial state: box edge must be positive.");
  d.box.L = init.box;
  d.contact = makeContactModel(config.contact, M_EFF);
  d.dt = d.dt_auto = chooseTimeStep(config);
  {
    const int k = coulombEvery(config, d.dt);
    d.slow = SlowSchedule::start(
        k, config.coulomb.every_max > 0 ? config.coulomb.every_max : SLOW_INTERVAL_GROWTH * k,
        d.dt);
  }

  Frame f = init;
  if (f.charge.size() != N) f.charge.assign(N, 0.0);
  for (auto* v : {&f.ix, &f.iy, &f.iz})
    if (v->size() != N) v->assign(N, 0);
  for (std::size_t i = 0; i < N; ++i) {
    for (double v : {f.x[i], f.y[i], f.z[i], f.vx[i], f.vy[i], f.vz[i], f.charge[i]})
      if (!std::isfinite(v))
        throw std::invalid_argument("initial state: non-finite value for particle " +
                                    std::to_string(i) + ".");
    f.ix[i] += d.box.wrap(f.x[i]);
    f.iy[i] += d.box.wrap(f.y[i]);
    f.iz[i] += d.box.wrap(f.z[i]);
  }
  d.p.resize(N);
  d.upload(f);
  d.step = init.step;
  d.time = init.step * d.dt;

  d.coulomb = config.coulomb.K > 0.0;
  if (d.coulomb) {
    double sum_q2 = 0.0;
    for (double q : f.charge) sum_q2 += q * q;
    d.setupCoulomb(std::max(sum_q2, static_cast<double>(N)));
  }

  // overlapping initial states are refused (docs/model.md section 5; bad input)
  d.rebuildList(false);
  if (allow_contacts) {
    d.computeInitialForces();
    return;
  }
  const auto rows =
      toHost(DVec<int>(d.nl.rows(), d.nl.rows() + N * static_cast<std::size_t>(d.nl.capacity())));
  const auto counts = toHost(DVec<int>(d.nl.counts(), d.nl.counts() + N));
  for (std::size_t i = 0; i < N; ++i)
    for (int k = 0; k < counts[i]; ++k) {
      const std::size_t j = rows[i * d.nl.capacity() + k];
      if (j <= i) continue;
      const double rx = d.box.minimumImage(f.x[i] - f.x[j]),
                   ry = d.box.minimumImage(f.y[i] - f.y[j]),
                   rz = d.box.minimumImage(f.z[i] - f.z[j]);
      const double r = std::sqrt(rx * rx + ry * ry + rz * rz);
      if (r < 1.0)
        throw std::invalid_argument("initial state: particles " + std::to_string(i) + " and " +
                                    std::to_string(j) + " overlap (distance " +
                                    common::formatReal(r) + " < diameter 1).");
    }
  d.computeInitialForces();
}

Engine::~Engine() = default;

void Engine::run(std::int64_t steps) {
  m_impl->advance(steps);
  m_impl->finishStep();  // callers see full-step velocities
}

Frame Engine::frame(StateKind kind) const {
  const Impl& d = *m_impl;
  const DVec<int>& id = d.p.id;
  Frame f;
  f.step = d.step;
  f.time = d.time;
  f.box = d.box.L;
  const auto pos = toHostById(d.p.pos, id);
  const std::size_t N = pos.size();
  f.x.resize(N);
  f.y.resize(N);
  f.z.resize(N);
  f.charge.resize(N);
  for (std::size_t i = 0; i < N; ++i) {
    f.x[i] = pos[i].x;
    f.y[i] = pos[i].y;
    f.z[i] = pos[i].z;
    f.charge[i] = pos[i].w;
  }
  if (kind == StateKind::Physical && d.velocityOffset() != 0.0) {
    DVec<double> sx, sy, sz;
    d.smoothVelocities(sx, sy, sz);
    f.vx = toHostById(sx, id);
    f.vy = toHostById(sy, id);
    f.vz = toHostById(sz, id);
  } else {
    DVec<double> vx, vy, vz;
    unpackVec3(d.p.vel, vx, vy, vz);
    f.vx = toHostById(vx, id);
    f.vy = toHostById(vy, id);
    f.vz = toHostById(vz, id);
  }
  f.ix = toHostById(d.p.ix, id);
  f.iy = toHostById(d.p.iy, id);
  f.iz = toHostById(d.p.iz, id);
  return f;
}

Forces Engine::forces(StateKind kind) const {
  const Impl& d = *m_impl;
  DVec<double> comp[3];
  unpackVec3(d.p.force, comp[0], comp[1], comp[2]);
  const DVec<double>* f[3] = {&comp[0], &comp[1], &comp[2]};
  DVec<double> g[3];
  // physical: contact + Coulomb once
  const double w = d.coulomb ? 1.0 - d.slowWeight(d.step) : 0.0;
  if (kind == StateKind::Physical && w != 0.0) {
    for (int a = 0; a < 3; ++a) {
      g[a].resize(d.p.size());
      const DVec<double>& ext = d.slow_coulomb->force(a);
      thrust::transform(f[a]->begin(), f[a]->end(), ext.begin(), g[a].begin(), Axpy{w});
      f[a] = &g[a];
    }
  }
  return {toHostById(*f[0], d.p.id), toHostById(*f[1], d.p.id), toHostById(*f[2], d.p.id)};
}

void Engine::enableProfile(bool on) { m_impl->timer.enable(on); }
std::vector<std::pair<std::string, double>> Engine::phaseSeconds() const {
  return m_impl->timer.seconds();
}

Observables Engine::observables() const {
  const Impl& d = *m_impl;
  const std::size_t N = d.p.size();
  Observables o;
  o.step = d.step;
  o.time = d.time;
  // velocities of the smooth trajectory between Coulomb impulses (Engine.h)
  DVec<double> sx, sy, sz;
  if (d.velocityOffset() == 0.0) unpackVec3(d.p.vel, sx, sy, sz);
  const DVec<double>* v[3] = {&sx, &sy, &sz};
  if (d.velocityOffset() != 0.0) {
    d.smoothVelocities(sx, sy, sz);
    v[0] = &sx, v[1] = &sy, v[2] = &sz;
  }
  // Every sum runs over the particles in id order (reduceById): a restart, whose storage order
  // differs from the uninterrupted run's, then samples the same observables to the bit.
  DVec<VelocitySums> per_slot(N);
  thrust::transform(thrust::counting_iterator<int>(0),
                    thrust::counting_iterator<int>(static_cast<int>(N)), per_slot.begin(),
                    VelocitySumsOf{raw(*v[0]), raw(*v[1]), raw(*v[2])});
  const VelocitySums vs = reduceById(per_slot, d.p.id, VelocitySums{}, CombineVelocitySums{});
  for (int c = 0; c < 3; ++c) o.momentum[c] = vs.p[c];
  const double sum2 = vs.v2;
  o.kinetic_energy = 0.5 * sum2;
  const double p2 =
      o.momentum[0] * o.momentum[0] + o.momentum[1] * o.momentum[1] + o.momentum[2] * o.momentum[2];
  o.temperature = (sum2 - p2 / N) / (3.0 * N);  // (1/3N) sum (v - <v>)^2, unit mass
  o.momentum_abs_sum = vs.abs;
  const ContactSummary c = d.summary();
  // (a cache: re-evaluating the energy, or re-building the Coulomb list, changes no trajectory)
  o.coulomb_energy = const_cast<Impl&>(d).coulombEnergyNow();
  o.elastic_energy = c.elastic_energy;
  o.contacts_per_particle = static_cast<double>(c.contacts) / N;
  o.collisions = d.collisions;
  o.mean_overlap = c.contacts > 0 ? c.overlap_sum / (0.5 * c.contacts) : 0.0;
  o.max_overlap = c.max_overlap;
  DVec<ChargeSums> q_slot(N);
  thrust::transform(d.p.pos.begin(), d.p.pos.end(), q_slot.begin(), ChargeOf{});
  const ChargeSums q = reduceById(q_slot, d.p.id, ChargeSums{}, CombineCharges{});
  o.total_charge = q.total;
  o.mean_abs_charge = q.abs_sum / N;
  o.max_abs_charge = q.abs_max;
  return o;
}

double Engine::dt() const { return m_impl->dt; }
std::int64_t Engine::step() const { return m_impl->step; }
double Engine::time() const { return m_impl->time; }
double Engine::box() const { return m_impl->box.L; }
std::size_t Engine::size() const { return m_impl->p.size(); }
std::int64_t Engine::neighborBuilds() const { return m_impl->nl.builds(); }
double Engine::contactListSkin() const { return m_impl->nl.skin(); }
double Engine::coulombListSkin() const { return m_impl->nl_coul ? m_impl->nl_coul->skin() : 0.0; }

void Engine::setThreads(int n) {
  if (n < 1)
    throw std::invalid_argument("the number of threads must be >= 1 (got " + std::to_string(n) +
                                ")");
#if !defined(__CUDACC__)
  omp_set_num_threads(n);
#endif
}

std::string Engine::backendDescription() {
#if defined(__CUDACC__)
  int dev = 0;
  cudaDeviceProp prop;
  if (cudaGetDevice(&dev) == cudaSuccess && cudaGetDeviceProperties(&prop, dev) == cudaSuccess)
    return std::string("Thrust CUDA backend on ") + prop.name;
  return "Thrust CUDA backend (no device found)";
#else
  return "Thrust OpenMP backend, " + std::to_string(omp_get_max_threads()) + " thread(s)";
#endif
}

std::string Engine::description() const { return backendDescription(); }

}  // namespace granagg::md
