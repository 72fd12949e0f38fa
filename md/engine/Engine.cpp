#include "md/engine/Engine.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <variant>

#include <thrust/copy.h>
#include <thrust/execution_policy.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/functional.h>
#include <thrust/gather.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>
#include <thrust/scatter.h>
#include <thrust/sequence.h>
#include <thrust/transform.h>
#include <thrust/transform_reduce.h>

#if defined(__CUDACC__)
#include <cuda_runtime.h>
#else
#include <omp.h>
#endif

#include "common/Box.h"
#include "common/Csv.h"
#include "md/compute/ContactForce.h"
#include "md/compute/CoulombRealSpace.h"
#include "md/coulomb/CoulombDesign.h"
#include "md/coulomb/Ewald.h"
#include "md/coulomb/EwaldParams.h"
#include "md/coulomb/Pppm.h"
#include "md/engine/Launch.h"
#include "md/engine/ParticleData.h"
#include "md/engine/PhaseTimer.h"
#include "md/integrate/SlowSchedule.h"
#include "md/integrate/VelocityVerlet.h"
#include "md/neighbor/NeighborList.h"
#include "md/neighbor/Skin.h"
#include "md/potentials/ContactModels.h"
#include "md/rng/RngStreams.h"

namespace granagg::md {

namespace {
constexpr double M_EFF = 0.5;  // reduced mass of two unit masses

/// |u|^2 of a velocity (the fastest particle, for the slow interval that follows the gas)
struct Speed2 {
  HD double operator()(const Vec3& u) const { return u.x * u.x + u.y * u.y + u.z * u.z; }
};

/// The fastest impact the time step resolves: integrator.impact_speed_max, or "auto": exceeded by
/// a fraction 1e-6 of collisions in a Maxwellian gas at the initial temperature (collision-
/// weighted P(g) = g/(2T) exp(-g^2/(4T)), tail exp(-g^2/(4T))).
double impactSpeedMax(const MdConfig& c) {
  if (c.integrator.impact_speed_max > 0.0) return c.integrator.impact_speed_max;
  return std::sqrt(4.0 * c.system.temperature * std::log(1e6));
}
// integrator.dt = "adaptive" (Engine::adaptiveTimeStep): the margin on the fastest listed pair's
// impact speed (it may still gain speed before the next choice of the step; a speed margin m
// shortens the step by m^{1/5} only, 4.6 % here), and the largest step, in "auto" steps (a
// frozen gas, v -> 0, would otherwise ask for an infinite step)
constexpr double ADAPTIVE_PAIR_MARGIN = 1.25;
constexpr double ADAPTIVE_DT_GROWTH_MAX = 10.0;
// coulomb.every = "auto": time between evaluations of the slow Coulomb part (Engine::coulombEvery)
constexpr double SLOW_INTERVAL = 0.016;
// coulomb.every_max = "auto": the slow interval grows to at most this many times coulomb.every
// (64 steps at the paper preset's dt), so that in the cold gas the interval is set by the gas's
// speeds, not by the cap: ensembles at caps 16, 32 and 64 are indistinguishable from the tight
// reference, and the cold gas's energy drift is at most 3e-5 of E_kin per 1000 steps at each
// (docs/benchmarks-coulomb.md).
constexpr int SLOW_INTERVAL_GROWTH = 16;
// What "auto" means for a checkpoint that does not record its every_max (an older checkpoint
// format; docs/coulomb.md): the cap that wrote it, so that it continues as it ran.
constexpr int SLOW_INTERVAL_GROWTH_BEFORE_RECORDED = 4;
// coulomb.r_fast = "auto" is R_FAST_AUTO (md/coulomb/CoulombDesign.h). What "auto" means for a
// checkpoint that does not record its split (an older format): the split that wrote it.
constexpr double R_FAST_AUTO_BEFORE_RECORDED = 3.5;

/// The run's configuration with the multiple-time-step split that wrote `ck`: its "auto"
/// r_fast and every_max are resolved as recorded in the checkpoint (older ones: as "auto" was
/// resolved then), so a restart continues with the split it was written with even if a later
/// granagg resolves "auto" differently.
MdConfig withRecordedSplit(MdConfig c, const Checkpoint& ck) {
  if (!(c.coulomb.K > 0.0)) return c;
  const auto& reals = ck.engine.reals;
  const auto& ints = ck.engine.ints;
  if (!(c.coulomb.r_fast > 0.0)) {
    const auto r = reals.find("coulomb_r_fast");
    c.coulomb.r_fast = r != reals.end() ? r->second : R_FAST_AUTO_BEFORE_RECORDED;
  }
  if (c.coulomb.every_max == 0) {
    const auto m = ints.find("coulomb_every_max");
    c.coulomb.every_max =
        m != ints.end()
            ? static_cast<int>(m->second)
            : SLOW_INTERVAL_GROWTH_BEFORE_RECORDED *
                  Engine::coulombEvery(c, Engine::chooseTimeStep(c));
  }
  return c;
}

template <class T>
std::vector<T> toHost(const DVec<T>& d) {
  std::vector<T> h(d.size());
  thrust::copy(d.begin(), d.end(), h.begin());
  return h;
}
template <class T>
void toDevice(const std::vector<T>& h, DVec<T>& d) {
  d.assign(h.begin(), h.end());
}
/// Host copy in particle-id order: out[id[slot]] = d[slot].
template <class T>
std::vector<T> toHostById(const DVec<T>& d, const DVec<int>& id) {
  DVec<T> tmp(d.size());
  thrust::scatter(d.begin(), d.end(), id.begin(), tmp.begin());
  return toHost(tmp);
}
/// d = d[order] (storage permutation).
template <class T>
void permute(DVec<T>& d, const DVec<int>& order, DVec<T>& scratch) {
  scratch.resize(d.size());
  thrust::gather(order.begin(), order.end(), d.begin(), scratch.begin());
  d.swap(scratch);
}

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
struct AddScaled {  // a[i] += c (x, y, z)[i]
  Vec3* a;
  const double *x, *y, *z;
  double c;
  HD void operator()(int i) const {
    a[i].x += c * x[i];
    a[i].y += c * y[i];
    a[i].z += c * z[i];
  }
};
struct Axpy {  // v + a f
  double a;
  HD double operator()(double v, double f) const { return v + a * f; }
};
/// Per particle: momentum, v^2 and |v| (sums over particles in id order: Engine::observables).
struct VelocitySums {
  double p[3] = {0.0, 0.0, 0.0}, v2 = 0.0, abs = 0.0;
};
struct VelocitySumsOf {
  const double *vx, *vy, *vz;
  HD VelocitySums operator()(int i) const {
    VelocitySums r;
    r.p[0] = vx[i];
    r.p[1] = vy[i];
    r.p[2] = vz[i];
    r.v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
    r.abs = sqrt(r.v2);
    return r;
  }
};
struct CombineVelocitySums {
  HD VelocitySums operator()(const VelocitySums& a, const VelocitySums& b) const {
    VelocitySums r;
    for (int c = 0; c < 3; ++c) r.p[c] = a.p[c] + b.p[c];
    r.v2 = a.v2 + b.v2;
    r.abs = a.abs + b.abs;
    return r;
  }
};
}  // namespace

struct Engine::Impl {
  MdConfig cfg;
  common::Box box;
  ParticleData p;
  NeighborList nl;
  ContactWork work;
  DVec<double> block_max;  // kickDrift's per-block maximum speeds
  DVec<double> scratch_d;  // for permutations
  DVec<int> scratch_i;
  DVec<Scalar4> scratch4;
  DVec<Vec3> scratch3;
  double dt = 0.0;
  double dt_auto = 0.0;  // the "auto" step (Engine::chooseTimeStep): the adaptive step's reference
  std::int64_t step = 0;
  double time = 0.0;
  // time = time_origin + (step - step_origin) dt: the step and time of the last change of dt
  // (0, 0 for a fixed step), so that t carries no round-off accumulated over steps
  double time_origin = 0.0;
  std::int64_t step_origin = 0;
  std::int64_t collisions = 0;
  bool close_pending = false;  // v holds u = v(t - dt/2): the closing kick is still to apply
  // no step taken since the state was given at full step (construction): the slow force's weight
  // at this step is an opening half only (changeTimeStep)
  bool fresh_start = true;
  // sum over steps of dt * max |u| (+ rounding): bounds every displacement
  double drift_since_build = 0.0;
  bool exchange = false;  // collisional charging on (charging.mode = "exchange")
  ChargeExchange::Params charging{};
  DVec<double> dq;  // charge gained at the last force pass, per slot (exchange only)
  // Coulomb (coulomb.K > 0): the slow force of the impulse multiple-time-step integrator
  // (Engine.h), evaluated every coulomb.every steps into ext_f*: PPPM's real space over its own
  // neighbour list nl_coul plus its mesh part, or a whole plain-Ewald evaluation
  bool coulomb = false;
  // when the slow force was evaluated and is next due (md/integrate/SlowSchedule.h); the next
  // interval is chosen at each evaluation (chooseEvery)
  SlowSchedule slow;
  std::int64_t slow_evaluations = 0;  // in this process (Engine::slowEvaluations)
  CoulombSetup csetup;
  std::unique_ptr<Pppm> pppm;
  std::unique_ptr<EwaldReference> ewald;
  std::unique_ptr<NeighborList> nl_coul;  // pppm: reaches r_cut + coulomb.skin
  RealSpaceSwitch fast_switch{};  // pppm with every > 1: the real space within r_fast is fast
  // ... and the slow and fast pair forces tabulated (PairTable), and the pair energy for the
  // observables
  DVec<double> slow_table, fast_table, energy_table;
  double drift_since_coul_build = 0.0;  // as drift_since_build, for nl_coul
  DVec<double> ext_fx, ext_fy, ext_fz;  // the Coulomb force at the last evaluation, per slot
  double coulomb_ext_energy = 0.0;      // pppm: mesh + self + background; ewald: everything
  ContactModel contact;  // the contact model and its parameters (md/potentials/ContactModels.h)
  PhaseTimer timer;      // Engine::enableProfile

  // Skins that follow the gas (md/neighbor/Skin.h), chosen at each build from the fastest drift
  // velocity of the last step; they change no result, only the cost of the passes and builds
  bool contact_skin_follows = false;  // neighbor.skin "auto" and the list has fast Coulomb pairs
  bool coulomb_skin_follows = false;  // coulomb.skin "auto" with multiple time stepping
  double coulomb_skin_cap = 0.0;      // the Coulomb list's skin when fixed, its largest otherwise
  double u_max_last = -1.0;           // max |u| of the last step; < 0: none in this process yet

  explicit Impl(const MdConfig& c) : cfg(c), nl(1.0, c.neighbor.skinCap()) {
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

  double* dqOrNull() { return exchange ? raw(dq) : nullptr; }

  /// Copies a host state (same N, wrapped, with images and charges) into the device arrays.
  void upload(const Frame& f) {
    p.setPositions(f.x, f.y, f.z, f.charge);
    packVec3(f.vx, f.vy, f.vz, p.vel);
    toDevice(f.ix, p.ix);
    toDevice(f.iy, p.iy);
    toDevice(f.iz, p.iz);
    p.id.resize(f.size());
    thrust::sequence(p.id.begin(), p.id.end());
    if (exchange) dq.assign(f.size(), 0.0);
  }

  /// Stores particles in cell order (memory locality for the neighbour gathers: a particle's
  /// neighbours then sit within a few hundred slots of it). Rows are sorted by particle id, so
  /// forces, and hence trajectories, do not depend on the storage order. The caller rebuilds the
  /// list. Returns false if nothing was sorted (boxes too small for cells).
  bool sortByCell() {
    const DVec<int>& order = nl.computeCellOrder(p, box);
    if (order.size() != p.size()) return false;  // all-pairs builds: nothing to sort
    permute(p.pos, order, scratch4);  // (dq is all zero here: applied by the kick pass before)
    for (auto* v : {&p.vel, &p.force}) permute(*v, order, scratch3);
    if (coulomb)  // the Coulomb forces, used until the next evaluation, follow their particles
      for (auto* v : {&ext_fx, &ext_fy, &ext_fz}) permute(*v, order, scratch_d);
    for (auto* v : {&p.ix, &p.iy, &p.iz, &p.id}) permute(*v, order, scratch_i);
    return true;
  }

  /// Builds the neighbour lists for the current positions (storage first re-sorted by cell: the
  /// cost is a gather per array, far less than the cache misses of neighbours scattered in memory).
  /// A re-sort moves slots, so it rebuilds every list.
  void rebuildList(bool sort) {
    PhaseTimer::Scope phase(&timer, nl_coul ? PhaseTimer::CoulombList : PhaseTimer::ContactList);
    chooseSkins(true, true);
    const bool sorted = sort && sortByCell();
    if (nl_coul) {
      nl_coul->build(p, box);
      drift_since_coul_build = 0.0;
      nl.buildFrom(*nl_coul, p, box);
    } else if (sorted) {
      nl.buildSorted(p, box);  // the storage is in nl's cell order now
    } else {
      nl.build(p, box);
    }
    drift_since_build = 0.0;
  }
  /// Contact list only, when it alone is out of date. With a Coulomb list the storage is not
  /// re-sorted here (that would invalidate the Coulomb list's slots; it is re-sorted when the
  /// Coulomb list is rebuilt, often enough for locality), and the contact list is filtered from
  /// the Coulomb list's rows while that still holds every pair within the contact list's range:
  /// a pair within R now was within R + 2 d when the Coulomb list was built, d bounding every
  /// displacement since.
  void rebuildContactList() {
    chooseSkins(true, false);
    if (!nl_coul) {
      rebuildList(true);
    } else if (nl.listRange() <= nl_coul->listRange() - 2.0 * drift_since_coul_build) {
      PhaseTimer::Scope phase(&timer, PhaseTimer::ContactList);
      nl.buildFrom(*nl_coul, p, box);
      drift_since_build = 0.0;
    } else {
      rebuildList(true);
    }
  }

  /// Sets the skins of the lists about to be rebuilt (only those: a list reports its new skin at
  /// once, NeighborList::setSkin) where they follow the gas: md/neighbor/Skin.h's optimum for the
  /// displacement bound of one use, dt max|u| of the last step for the contact list (used every
  /// step) and `every` times that for the Coulomb list (used at slow steps). Before the first step
  /// of this process (also after a restart) the skins keep their caps.
  void chooseSkins(bool contact_list, bool coulomb_list) {
    if (u_max_last < 0.0) return;
    const double delta = dt * u_max_last;
    if (contact_list && contact_skin_follows)
      nl.setSkin(followingSkin(fast_switch.r2, delta, CONTACT_LIST_BUILD_OVER_USE,
                               NEIGHBOR_SKIN_AUTO_MIN, cfg.neighbor.skinCap()));
    if (coulomb_list && nl_coul && coulomb_skin_follows)
      nl_coul->setSkin(followingSkin(csetup.r_cut, slow.every * delta, COULOMB_LIST_BUILD_OVER_USE,
                                     COULOMB_SKIN_AUTO_MIN, coulomb_skin_cap));
  }

  /// Builds the Coulomb solvers from designCoulomb's parameters for the configured accuracy
  /// (md/coulomb/CoulombDesign.h, docs/coulomb.md); the contact list then reaches r_fast. The
  /// error estimates scale with sum q^2: parameters are chosen for sum_q2_design (the engine uses
  /// the larger of the initial sum q^2 and N, i.e. charges of order the unit q_ref at least, since
  /// an exchanging gas starts neutral) and stored, so that a restart reuses them.
  void setupCoulomb(double sum_q2_design) {
    const CoulombConfig& cc = cfg.coulomb;
    const std::size_t N = p.size();
    const double L = box.L, skin = cfg.neighbor.skinCap();
    const CoulombDesign d =
        designCoulomb(cc, N, L, skin, slow.design_base, slow.design_cap, sum_q2_design);
    csetup = d.setup;
    fast_switch = d.fast_switch;
    pppm.reset();
    ewald.reset();
    nl_coul.reset();
    slow_table.clear();
    fast_table.clear();
    energy_table.clear();
    if (cc.method == "pppm") {
      pppm = std::make_unique<Pppm>(d.pppm, L, cc.K);
      pppm->setPhaseTimer(&timer);
      nl_coul = std::make_unique<NeighborList>(d.pppm.r_cut, d.coulomb_skin);
      coulomb_skin_cap = d.coulomb_skin;
      coulomb_skin_follows = d.coulomb_skin_follows;
      const auto e = energyPairTableValues(d.pppm.alpha, d.pppm.r_cut * d.pppm.r_cut);
      energy_table.assign(e.begin(), e.end());
      if (fast_switch.r2 > 0.0) {
        const auto t = slowPairTableValues(d.pppm.alpha, fast_switch, d.pppm.r_cut * d.pppm.r_cut);
        slow_table.assign(t.begin(), t.end());
        const auto f = fastPairTableValues(fast_switch);
        fast_table.assign(f.begin(), f.end());
      }
    } else {
      ewald = std::make_unique<EwaldReference>(d.ewald, L, cc.K);
    }
    nl = NeighborList(d.contact_list_cutoff, skin);
    nl.keepPairs(d.contact_list_keeps_pairs);
    contact_skin_follows = cfg.neighbor.skin == 0.0 && fast_switch.r2 > 0.0;
    for (auto* v : {&ext_fx, &ext_fy, &ext_fz}) v->assign(N, 0.0);
    slow.eval_step = -1;
  }

  CoulombRealParams realParams() const {
    CoulombRealParams prm{cfg.coulomb.K, csetup.alpha, csetup.r_cut, fast_switch};
    if (!slow_table.empty())
      prm.table =
          pairTable(raw(slow_table), csetup.r_cut * csetup.r_cut, SLOW_PAIR_TABLE_INTERVALS);
    if (!energy_table.empty())
      prm.energy_table =
          pairTable(raw(energy_table), csetup.r_cut * csetup.r_cut, ENERGY_PAIR_TABLE_INTERVALS);
    return prm;
  }

  /// Plain Ewald (the host reference) of the current positions and charges, per slot.
  CoulombResult ewaldOnHost() const {
    const auto pos = toHost(p.pos);
    std::vector<double> x(pos.size()), y(pos.size()), z(pos.size()), q(pos.size());
    for (std::size_t i = 0; i < pos.size(); ++i)
      x[i] = pos[i].x, y[i] = pos[i].y, z[i] = pos[i].z, q[i] = pos[i].w;
    return ewald->compute(x, y, z, q);
  }

  /// The Coulomb force of the current positions into ext_f* (and the energy of everything but the
  /// PPPM real space into coulomb_ext_energy): PPPM real space over nl_coul plus the mesh part, or
  /// everything for plain Ewald (host, O(N^2) real space).
  void evaluateCoulomb() {
    // the interval that ends here (a fresh start has none: its impulse opens an interval only)
    slow.every_prev = slow.eval_step < 0 ? -1.0 : static_cast<double>(step - slow.eval_step);
    slow.eval_step = step;
    slow.every = chooseEvery();
    if (slow.every_prev < 0) slow.every_prev = slow.every;
    evaluateSlowForce();
  }

  /// The slow Coulomb force of the current positions into ext_f* and coulomb_ext_energy
  /// (evaluateCoulomb without the interval's bookkeeping).
  void evaluateSlowForce() {
    const std::size_t N = p.size();
    ++slow_evaluations;
    if (pppm) {
      {
        PhaseTimer::Scope phase(&timer, PhaseTimer::CoulombReal);
        coulombRealForces(p, *nl_coul, box, realParams(), ext_fx, ext_fy, ext_fz);
      }
      coulomb_ext_energy = pppm->compute(reinterpret_cast<const double*>(raw(p.pos)), N,
                                         raw(ext_fx), raw(ext_fy), raw(ext_fz), raw(p.id));
      return;
    }
    // the plain-Ewald reference: all of its evaluation counts as the slow real space
    PhaseTimer::Scope phase(&timer, PhaseTimer::CoulombReal);
    const CoulombResult r = ewaldOnHost();
    toDevice(r.fx, ext_fx);
    toDevice(r.fy, ext_fy);
    toDevice(r.fz, ext_fz);
    coulomb_ext_energy = r.energy;
  }

  /// The next slow interval (Engine.h, "multiple time stepping"). Fixed: every_base. Following
  /// the gas: the interval over which the fastest pair, approaching at 2 max|u| (a bound on every
  /// relative speed), moves as far as a pair at the impact speed the time step resolves
  /// (integrator.impact_speed_max) moves in every_base steps, within [every_base, every_cap].
  /// A maximum is exact, so the choice does not depend on the thread count; it reads only the
  /// drift velocities, which a checkpoint restores to the bit.
  /// An interval never reaches past the next change of the time step (slow_interval_end), so
  /// that the change falls on an evaluation (changeTimeStep).
  int chooseEvery() const {
    if (!slow.follows()) return slow.clamp(slow.every_base, step);
    const double u2 = thrust::transform_reduce(p.vel.begin(), p.vel.end(), Speed2{}, 0.0,
                                               thrust::maximum<double>());
    const double v_rel = 2.0 * std::sqrt(u2);
    return slow.clamp(
        v_rel > 0.0 ? std::floor(slow.every_base * impactSpeedMax(cfg) / v_rel) : slow.every_cap,
        step);
  }

  double slowWeight(std::int64_t at) const { return slow.weight(at); }

  /// \param slow_weight weight of ext_f* in this step's force (0: not added)
  ContactStep makeStep(double dt_taken, double slow_weight, double prev_weight) const {
    ContactStep st;
    st.dt = dt_taken;
    st.max_overlap = cfg.run.max_overlap;
    st.step = step;
    st.charging = charging;
    if (coulomb) {
      st.ext_fx = raw(ext_fx);
      st.ext_fy = raw(ext_fy);
      st.ext_fz = raw(ext_fz);
      st.ext_force_scale = slow_weight;
      // f_old holds prev_weight ext (ContactStep); with k = 1 both weights are 1 (the term
      // vanishes) and f_old's Coulomb part is the trend itself
      st.ext_predict_scale = 0.5 * dt_taken * (slow_weight - prev_weight);
      st.fast = fast_switch;
      st.coulomb_K = cfg.coulomb.K;
      if (!fast_table.empty())
        st.fast_table =
            pairTable(raw(fast_table), fast_switch.r2 * fast_switch.r2, FAST_PAIR_TABLE_INTERVALS);
    }
    return st;
  }

  /// a += c ext_f, per slot (a: the velocities or the forces).
  void addSlow(DVec<Vec3>& a, double c) {
    if (c == 0.0) return;
    thrust::for_each(thrust::counting_iterator<int>(0),
                     thrust::counting_iterator<int>(static_cast<int>(a.size())),
                     AddScaled{raw(a), raw(ext_fx), raw(ext_fy), raw(ext_fz), c});
  }
  void kickSlow(double c) { addSlow(p.vel, c); }
  void addSlowForce(double c) { addSlow(p.force, c); }

  /// The slow interval's bounds in steps of the current dt (SlowSchedule::boundsFor).
  void slowBoundsForStep() {
    if (coulomb) slow.boundsFor(dt);
  }

  /// Continues with the step dt_new from this step on (between steps: v at full step), until
  /// the step next_change (-1: not known). The contact forces need nothing: velocity Verlet with
  /// a step that changes between steps closes with dt_old / 2 and opens with dt_new / 2. The slow
  /// Coulomb impulse does (Engine.h). Its intervals never reach past an announced change
  /// (chooseEvery), so a change announced by the one before falls on an evaluation: Verlet-I
  /// with a varying outer step, exact. The evaluation's closing half, (dt_old / 2) w_old F,
  /// is taken back; the interval that ended here, in steps of dt_new, and the next one, chosen at
  /// dt_new, give the new weight w; and (dt_new / 2) w F is applied, as finishStep would have
  /// had the last step been one of dt_new. A change that cuts an interval (j > 0 steps after its
  /// evaluation; only where the change was not announced) ends it here: the excess of its
  /// opening half, (k - j)/2 dt_old F_e, is taken back from the velocities and the slow force is
  /// evaluated here, but the positions of those j steps keep the excess, an error of first order
  /// in it (md::Simulation always announces the next change). Momentum is kept to round-off
  /// (every impulse is of a force that sums to zero).
  void changeTimeStep(double dt_new, std::int64_t next_change) {
    const double dt_old = dt;
    slow.interval_end = next_change;
    if (coulomb && slow.eval_step >= 0) {  // (< 0: the next force pass evaluates afresh)
      const std::int64_t j = step - slow.eval_step;
      double tau_prev = 0.0, w_old = 0.0;
      if (fresh_start) {  // (j = 0) the opening half alone, never applied to v: a fresh opening
        dt = dt_new;
        slowBoundsForStep();
        w_old = slowWeight(step);
        slow.every = chooseEvery();
        slow.every_prev = slow.every;
        addSlowForce(slowWeight(step) - w_old);
        moveTimeOrigin(dt_old);
        return;
      }
      double taken_back = 0.0;  // the closing half already in v, per unit F at this step
      if (j > 0) {
        kickSlow(-0.5 * static_cast<double>(slow.every - j) * dt_old);
        tau_prev = static_cast<double>(j) * dt_old;
        if (nl_coul && nl_coul->needsRebuild(p, drift_since_coul_build * drift_since_coul_build))
          rebuildList(true);
        evaluateSlowForce();
      } else {
        w_old = slowWeight(step);
        taken_back = 0.5 * dt_old * w_old;
        tau_prev = slow.every_prev * dt_old;
      }
      dt = dt_new;
      slowBoundsForStep();
      slow.eval_step = step;
      if (j > 0 || dt_new != dt_old) slow.every_prev = tau_prev / dt_new;
      slow.every = chooseEvery();
      const double w = slowWeight(step);
      // (one kick: nothing at all when neither the step nor the interval changed)
      kickSlow(0.5 * dt_new * w - taken_back);
      addSlowForce(w - w_old);
    }
    dt = dt_new;
    slowBoundsForStep();
    moveTimeOrigin(dt_old);
  }

  /// After a change of dt: t counts from here. (The same step keeps its origin, so that a run
  /// resumed within an epoch, which re-announces the epoch's end, keeps the uninterrupted run's
  /// times to the bit.)
  void moveTimeOrigin(double dt_old) {
    if (dt == dt_old) return;
    time_origin = time;
    step_origin = step;
  }

  /// The granular temperature T_g = (1/3N) sum (v - <v>)^2 of the integrator's velocities (sums
  /// in id order, as Engine::observables).
  double temperature() const {
    const std::size_t N = p.size();
    DVec<double> vx, vy, vz;
    unpackVec3(p.vel, vx, vy, vz);
    DVec<VelocitySums> per_slot(N);
    thrust::transform(thrust::counting_iterator<int>(0),
                      thrust::counting_iterator<int>(static_cast<int>(N)), per_slot.begin(),
                      VelocitySumsOf{raw(vx), raw(vy), raw(vz)});
    const VelocitySums vs = reduceById(per_slot, p.id, VelocitySums{}, CombineVelocitySums{});
    const double p2 = vs.p[0] * vs.p[0] + vs.p[1] * vs.p[1] + vs.p[2] * vs.p[2];
    return (vs.v2 - p2 / N) / (3.0 * N);
  }

  /// Forces of the current positions into p.f (state as in ContactForce.h; dt_taken = 0 for a
  /// state given at full step); counts collisions; aborts on NaN / deep overlap. With Coulomb, at
  /// every `every`-th step (counted from the last evaluation) the Coulomb force is evaluated first
  /// and enters p.f with weight `every` (the impulse), and between evaluations not at all.
  /// \param advance also complete this step and open the next in the same pass (ContactStep::
  /// advance_dt): afterwards the state is as after openStep(), one step on.
  void computeForces(double dt_taken, bool advance = false) {
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

  /// Forces of a state given at full step (initial or restored state without forces): the
  /// predicted velocities are v itself and no pair counts as a new collision.
  void computeInitialForces() {
    thrust::fill(p.force.begin(), p.force.end(), Vec3{0.0, 0.0, 0.0});
    computeForces(0.0);
    close_pending = false;
  }

  /// Applies a deferred closing kick: afterwards v = v(t).
  void finishStep() {
    if (!close_pending) return;
    PhaseTimer::Scope phase(&timer, PhaseTimer::KickDrift);
    closeKick(p, 0.5 * dt, dqOrNull());
    close_pending = false;
  }

  ContactSummary summary() const { return contactSummary(p, nl, box, contact); }

  /// Velocity offset of the impulse integrator against the smooth trajectory, per unit Coulomb
  /// force: (k/2 - j) dt at j = 1..k-1 steps after an evaluation, 0 at the evaluation step itself
  /// (whose v(t) holds half the impulse) and with k = 1 (Engine.h).
  double velocityOffset() const { return coulomb ? slow.velocityOffset(step, dt) : 0.0; }
  /// v - velocityOffset() * F_coulomb, per slot.
  void smoothVelocities(DVec<double>& sx, DVec<double>& sy, DVec<double>& sz) const {
    const double c = velocityOffset();
    DVec<double> v[3];
    unpackVec3(p.vel, v[0], v[1], v[2]);
    const DVec<double>* ext[3] = {&ext_fx, &ext_fy, &ext_fz};
    DVec<double>* out[3] = {&sx, &sy, &sz};
    for (int a = 0; a < 3; ++a) {
      out[a]->resize(p.size());
      thrust::transform(v[a].begin(), v[a].end(), ext[a]->begin(), out[a]->begin(), Axpy{-c});
    }
  }

  /// The Coulomb energy of the current positions: from the last evaluation when it was at this
  /// step, otherwise evaluated afresh (observables between evaluations; the forces of the run are
  /// not touched, and re-building the Coulomb list changes no result: rows are in id order).
  double coulombEnergyNow() {
    if (!coulomb) return 0.0;
    if (pppm) {
      if (nl_coul->needsRebuild(p, drift_since_coul_build * drift_since_coul_build)) {
        chooseSkins(false, true);
        nl_coul->build(p, box);
        drift_since_coul_build = 0.0;
      }
      double ext = coulomb_ext_energy;
      if (slow.eval_step != step)  // the energy alone: no forces
        ext = pppm->compute(reinterpret_cast<const double*>(raw(p.pos)), p.size(), nullptr, nullptr,
                            nullptr, raw(p.id));
      return coulombRealEnergy(p, *nl_coul, box, realParams()) + ext;
    }
    if (slow.eval_step == step) return coulomb_ext_energy;
    return ewaldOnHost().energy;
  }

  [[noreturn]] void abort(int worst) {
    DVec<double> mx_slots;
    maxOverlapPerParticle(p, nl, box, contact, mx_slots);
    const auto mx = toHostById(mx_slots, p.id);
    // which particles: the force pass's test again, per particle (cold path)
    const auto pos = toHostById(p.pos, p.id);
    DVec<double> dfx, dfy, dfz;
    unpackVec3(p.force, dfx, dfy, dfz);
    const auto fx = toHostById(dfx, p.id), fy = toHostById(dfy, p.id), fz = toHostById(dfz, p.id);
    std::vector<int> bad(pos.size(), 0);
    for (std::size_t i = 0; i < bad.size(); ++i) {
      const bool finite = std::isfinite(pos[i].x + pos[i].y + pos[i].z + fx[i] + fy[i] + fz[i]);
      bad[i] = !finite ? 1 : (mx[i] > cfg.run.max_overlap ? 2 : 0);
    }
    std::ostringstream msg;
    msg << "step " << step << " (t = " << time << "): ";
    msg << (worst == 1 ? "non-finite force or position (NaN/inf)"
                       : "overlap beyond run.max_overlap = ");
    if (worst != 1) msg << cfg.run.max_overlap;
    msg << " for particle(s)";
    int shown = 0;
    for (std::size_t i = 0; i < bad.size() && shown < 8; ++i)
      if (bad[i]) {
        msg << (shown ? ", " : " ") << i;
        if (bad[i] == 2) msg << " (overlap " << mx[i] << ")";
        ++shown;
      }
    msg << "; the time step dt = " << dt << " may be too large for these impacts";
    if (coulomb && worst == 2) {
      // An attractive pair has an equilibrium overlap only up to the contact model's limit.
      std::string how;
      const double hold = std::visit(
          [&how](const auto& m) {
            return std::decay_t<decltype(m)>::Model::attractionLimit(m.params, how);
          },
          contact);
      const char* model =
          std::visit([](const auto& m) { return std::decay_t<decltype(m)>::Model::name; }, contact);
      double worst_qq = 0.0;
      for (std::size_t i = 0; i < bad.size(); ++i)
        if (bad[i] == 2) worst_qq = std::max(worst_qq, pos[i].w * pos[i].w);
      msg << ", or an attractive Coulomb pair beyond what the " << model
          << " contact can hold (K |q_i q_j| > " << how << " = " << hold
          << " has no equilibrium overlap; here K q^2 = " << cfg.coulomb.K * worst_qq
          << " for the largest flagged charge): lower charging.Q (here " << cfg.charging.Q
          << "; recommended: 0.05 at K = 5, docs/validation.md";
      char q[32];  // two digits: a value to type
      std::snprintf(q, sizeof q, "%.2g", recommendedChargeScale(cfg.coulomb.K));
      if (cfg.coulomb.K != 5.0)  // the gas depends on K Q^2 only
        msg << ", so " << q << " at K = " << cfg.coulomb.K << ", the same K Q^2";
      msg << ": --set charging.Q=" << q << ") or coulomb.K";
    }
    throw RunAborted(msg.str());
  }

  /// A drift with drift velocities of largest |u|^2 = max_u2 was taken: bounds and step count.
  /// Each stored position moves by dt u up to the rounding of x + dt u and of the wrap, half an ulp
  /// of L each per component: 2 ulp(L) per step bounds that for the vector, so that the bounds
  /// hold to the last bit, also for a gas so cold that dt |u| is itself of the order of an ulp.
  void driftTaken(double max_u2) {
    const double moved =
        dt * std::sqrt(max_u2) + 2.0 * (std::nextafter(box.L, 2.0 * box.L) - box.L);
    drift_since_build += moved;
    drift_since_coul_build += moved;
    u_max_last = std::sqrt(max_u2);
    fresh_start = false;
    ++step;
    time = time_origin + static_cast<double>(step - step_origin) * dt;
  }

  /// [Previous closing kick +] opening kick + drift (VelocityVerlet.h).
  void openStep() {
    PhaseTimer::Scope phase(&timer, PhaseTimer::KickDrift);
    driftTaken(kickDrift(p, 0.5 * dt, dt, box, close_pending, dqOrNull(), block_max));
    close_pending = false;
  }

  /// `steps` velocity-Verlet steps; afterwards the forces are those of the new positions and the
  /// closing kick is pending. A step is two passes over the particles: the opening pass (kick +
  /// drift) and the force pass. The force pass also completes the step and opens the next
  /// (ContactStep::advance_dt), so the steps in between take one pass each: open, then (forces +
  /// close + open) steps - 1 times, then forces -- the same operations in the same order as
  /// separate passes (VelocityVerlet.h: one arithmetic).
  void advance(std::int64_t steps) {
    if (steps <= 0) return;
    openStep();
    for (std::int64_t s = 1; s < steps; ++s) computeForces(dt, true);
    computeForces(dt);
    close_pending = true;
  }
};

double Engine::chooseTimeStep(const MdConfig& c, std::string* reason) {
  if (c.integrator.dt > 0.0) {
    if (reason) *reason = "fixed by integrator.dt";
    return c.integrator.dt;
  }
  std::ostringstream why;
  std::string model_why;
  const double tc = std::visit(
      [&](const auto& m) {
        using Model = typename std::decay_t<decltype(m)>::Model;
        return Model::autoContactTime(m.params, impactSpeedMax(c), M_EFF, model_why);
      },
      makeContactModel(c.contact, M_EFF));
  why << model_why;
  const double dt = tc / c.integrator.steps_per_contact;
  why << " / " << c.integrator.steps_per_contact << " steps per contact";
  if (reason) *reason = "auto: " + why.str();
  return dt;
}

double Engine::impactSpeedMax(const MdConfig& config) { return md::impactSpeedMax(config); }

double Engine::adaptiveTimeStep(std::string* reason) const {
  const Impl& d = *m_impl;
  const double T = std::max(0.0, d.temperature());
  // the "auto" rule's tail speed at the current temperature (impactSpeedMax scales as sqrt(T))
  const double v_tail = md::impactSpeedMax(d.cfg) * std::sqrt(T / d.cfg.system.temperature);
  const double v_pair = std::sqrt(maxPairImpactSpeed2(d.p, d.nl, d.box, d.contact,
                                                      d.coulomb ? d.cfg.coulomb.K : 0.0, M_EFF));
  const double v = std::max(v_tail, ADAPTIVE_PAIR_MARGIN * v_pair);
  std::string model_why;
  const double tc = std::visit(
      [&](const auto& m) {
        using Model = typename std::decay_t<decltype(m)>::Model;
        return Model::autoContactTime(m.params, v, M_EFF, model_why);
      },
      d.contact);
  const double dt_cap = ADAPTIVE_DT_GROWTH_MAX * d.dt_auto;
  const double dt = std::min(tc / d.cfg.integrator.steps_per_contact, dt_cap);
  if (reason) {
    std::ostringstream why;
    why << "adaptive: " << model_why << " / " << d.cfg.integrator.steps_per_contact
        << " steps per contact (the larger of the T_g tail speed " << v_tail << " and "
        << ADAPTIVE_PAIR_MARGIN << " x the fastest listed pair's impact speed " << v_pair << ")";
    if (dt == dt_cap) why << ", capped at " << ADAPTIVE_DT_GROWTH_MAX << " x the auto step";
    *reason = why.str();
  }
  return dt;
}

void Engine::setTimeStep(double dt, std::int64_t next_change) {
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("Engine::setTimeStep: dt must be positive and finite");
  Impl& d = *m_impl;
  // (the same step: only an evaluation at this step re-chooses its interval for the new end)
  if (dt != d.dt || (d.coulomb && d.slow.eval_step == d.step))
    d.changeTimeStep(dt, next_change);
  else
    d.slow.interval_end = next_change;
}

int Engine::coulombEvery(const MdConfig& c, double dt) {
  // multiple time stepping with PPPM only: the plain-Ewald reference has no fast/slow split
  if (c.coulomb.method != "pppm") return 1;
  if (c.coulomb.every > 0) return c.coulomb.every;
  // auto: the slow part every SLOW_INTERVAL time units, the interval whose accuracy the tests
  // check (8 steps of 0.002: energy drift < 1e-4 at K = 5 with +-1 charges)
  return std::max(1, static_cast<int>(std::floor(SLOW_INTERVAL / dt + 1e-9)));
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

Engine::Engine(const MdConfig& config, const Checkpoint& ck)
    : Engine(withRecordedSplit(config, ck), ck.state, /*allow_contacts=*/true) {
  const EngineState& e = ck.engine;
  Impl& d = *m_impl;
  // The Coulomb parameters first, designed for the "auto" step's slow interval as in the run that
  // wrote it: restore() sizes the multiple-time-step state for them.
  if (const auto design = e.reals.find("coulomb_sum_q2_design"); design != e.reals.end())
    useCoulombDesign(design->second);
  if (config.integrator.adaptive) {
    // the step in force when it was written, and where it took effect (changeTimeStep); a
    // checkpoint of a fixed step (no change recorded: t = step dt) continues adaptively from it
    if (!(ck.dt > 0.0 && std::isfinite(ck.dt)))
      throw std::invalid_argument(
          "integrator.dt = \"adaptive\": the checkpoint lacks the time step in force (dt)");
    const auto t0 = e.reals.find("time_origin");
    const auto s0 = e.ints.find("step_origin");
    d.dt = ck.dt;
    d.time_origin = t0 != e.reals.end() ? t0->second : 0.0;
    d.step_origin = s0 != e.ints.end() ? s0->second : 0;
    d.slowBoundsForStep();
  } else if (ck.dt > 0.0 && ck.dt != d.dt) {
    // a fixed step: the configuration must give the step the checkpoint was written at, or a
    // build whose automatic step differs would continue the run silently on another
    throw std::invalid_argument("integrator.dt: the checkpoint was written at dt = " +
                                common::formatReal(ck.dt) + ", and its configuration now gives " +
                                common::formatReal(d.dt) +
                                "; continue it with the granagg that wrote it");
  }
  const auto collisions = e.ints.find("collisions");
  restore(ck.state, ck.forces, collisions == e.ints.end() ? 0 : collisions->second, e);
}

void Engine::saveCheckpoint(const std::filesystem::path& folder, const RunFields& run_fields) {
  Checkpoint ck = checkpoint();
  ck.run = run_fields;
  writeCheckpoint(checkpointPath(folder).string(), ck);
}

Checkpoint Engine::checkpoint() const {
  Checkpoint ck;
  ck.state = frame(StateKind::Integrator);
  ck.forces = forces(StateKind::Integrator);
  ck.dt = dt();
  ck.engine = engineState();
  ck.engine.ints["collisions"] = m_impl->collisions;
  if (const CoulombSetup* cs = coulombSetup())
    ck.engine.reals["coulomb_sum_q2_design"] = cs->sum_q2_design;
  return ck;
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
    const DVec<double>* ext[3] = {&d.ext_fx, &d.ext_fy, &d.ext_fz};
    for (int a = 0; a < 3; ++a) {
      g[a].resize(d.p.size());
      thrust::transform(f[a]->begin(), f[a]->end(), ext[a]->begin(), g[a].begin(), Axpy{w});
      f[a] = &g[a];
    }
  }
  return {toHostById(*f[0], d.p.id), toHostById(*f[1], d.p.id), toHostById(*f[2], d.p.id)};
}

EngineState Engine::engineState() const {
  const Impl& d = *m_impl;
  EngineState e;
  if (d.cfg.integrator.adaptive) {
    e.reals["time_origin"] = d.time_origin;
    e.ints["step_origin"] = d.step_origin;
    e.ints["fresh_start"] = d.fresh_start ? 1 : 0;  // (a checkpoint before the first step)
  }
  if (!d.coulomb) return e;
  e.arrays["coulomb_fx"] = toHostById(d.ext_fx, d.p.id);
  e.arrays["coulomb_fy"] = toHostById(d.ext_fy, d.p.id);
  e.arrays["coulomb_fz"] = toHostById(d.ext_fz, d.p.id);
  d.slow.save(e);
  e.reals["coulomb_energy_ext"] = d.coulomb_ext_energy;
  // the split as resolved (withRecordedSplit): a restart keeps it whatever "auto" means then
  e.reals["coulomb_r_fast"] = d.csetup.r_fast;
  return e;
}

void Engine::restore(const Frame& s, const Forces& forces, std::int64_t collisions,
                     const EngineState& extra) {
  Impl& d = *m_impl;
  const std::size_t N = d.p.size();
  if (s.size() != N || forces.x.size() != N || forces.y.size() != N || forces.z.size() != N ||
      s.charge.size() != N || s.ix.size() != N)
    throw std::invalid_argument("checkpoint has " + std::to_string(s.size()) +
                                " particles, the run " + std::to_string(N));
  d.upload(s);  // storage in id order again
  packVec3(forces.x, forces.y, forces.z, d.p.force);
  d.step = s.step;
  d.time = d.time_origin + static_cast<double>(s.step - d.step_origin) * d.dt;
  d.collisions = collisions;
  d.close_pending = false;
  // v(t) holds the closing half of the last step's impulse, unless no step was taken yet
  const auto fresh = extra.ints.find("fresh_start");
  d.fresh_start = fresh != extra.ints.end() && fresh->second != 0;
  if (d.coulomb) {
    // the Coulomb force of the last evaluation: the impulse integrator uses it until the next one
    const auto fx = extra.arrays.find("coulomb_fx"), fy = extra.arrays.find("coulomb_fy"),
               fz = extra.arrays.find("coulomb_fz");
    const auto at = extra.ints.find("coulomb_eval_step");
    const auto en = extra.reals.find("coulomb_energy_ext");
    const bool have = fx != extra.arrays.end() && fy != extra.arrays.end() &&
                      fz != extra.arrays.end() && at != extra.ints.end() && en != extra.reals.end();
    if (have) {
      for (const auto* a : {&fx->second, &fy->second, &fz->second})
        if (a->size() != N)
          throw std::invalid_argument("checkpoint: Coulomb force arrays have the wrong length");
      toDevice(fx->second, d.ext_fx);
      toDevice(fy->second, d.ext_fy);
      toDevice(fz->second, d.ext_fz);
      d.coulomb_ext_energy = en->second;
      d.slow.load(extra);  // (older checkpoints have no intervals: fixed, as configured)
    } else if (d.slow.every == 1) {
      d.slow.eval_step = -1;  // evaluated afresh at the next step, as every step
    } else {
      throw std::invalid_argument(
          "checkpoint lacks the Coulomb forces of the multiple-time-step integrator "
          "(coulomb.every > 1): it was written by an older granagg; restart with coulomb.every = "
          "1");
    }
  }
  d.rebuildList(true);  // storage in cell order from the first step on, as after any build
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

const CoulombSetup* Engine::coulombSetup() const {
  return m_impl->coulomb ? &m_impl->csetup : nullptr;
}
int Engine::slowInterval() const { return m_impl->coulomb ? m_impl->slow.every : 0; }
std::int64_t Engine::slowEvaluations() const { return m_impl->slow_evaluations; }

void Engine::useCoulombDesign(double sum_q2_design) {
  Impl& d = *m_impl;
  if (!d.coulomb || d.csetup.sum_q2_design == sum_q2_design) return;
  d.setupCoulomb(sum_q2_design);
  d.rebuildList(false);
}

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
