#pragma once
/// \file EngineImpl.h
/// Engine::Impl, the engine's state and its step protocol, and the helpers that more than one of
/// its sources needs. Private to md/engine/Engine*.cpp (Engine.h stays free of Thrust).
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <thrust/copy.h>
#include <thrust/scatter.h>

#include "common/Box.h"
#include "common/HostDevice.h"
#include "md/compute/ContactForce.h"
#include "md/engine/Engine.h"
#include "md/engine/ListTuner.h"
#include "md/engine/ParticleData.h"
#include "md/engine/PhaseTimer.h"
#include "md/engine/SlowCoulomb.h"
#include "md/integrate/SlowSchedule.h"
#include "md/neighbor/NeighborList.h"
#include "md/potentials/ChargeExchange.h"
#include "md/potentials/ContactModels.h"

namespace granagg::md {

namespace engine_detail {
constexpr double M_EFF = 0.5;  // reduced mass of two unit masses

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
}  // namespace engine_detail

struct Engine::Impl {
  MdConfig cfg;
  common::Box box;
  ParticleData p;
  NeighborList nl;
  ContactWork work;
  ListTuner tuner;         // the storage order and the skins that follow the gas
  DVec<double> block_max;  // kickDrift's per-block maximum speeds
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
  // (Engine.h), evaluated every coulomb.every steps by slow_coulomb: PPPM's real space over its
  // own neighbour list nl_coul plus its mesh part, or a whole plain-Ewald evaluation
  bool coulomb = false;
  // when the slow force was evaluated and is next due (md/integrate/SlowSchedule.h); the next
  // interval is chosen at each evaluation (chooseEvery)
  SlowSchedule slow;
  std::int64_t slow_evaluations = 0;          // in this process (Engine::slowEvaluations)
  std::unique_ptr<SlowCoulomb> slow_coulomb;  // the solvers and the last evaluation's force
  std::unique_ptr<NeighborList> nl_coul;      // pppm: reaches r_cut + coulomb.skin
  double drift_since_coul_build = 0.0;        // as drift_since_build, for nl_coul
  ContactModel contact;  // the contact model and its parameters (md/potentials/ContactModels.h)
  PhaseTimer timer;      // Engine::enableProfile

  explicit Impl(const MdConfig& c);

  double* dqOrNull() { return exchange ? raw(dq) : nullptr; }

  /// Copies a host state (same N, wrapped, with images and charges) into the device arrays.
  void upload(const Frame& f);

  /// Builds the neighbour lists for the current positions, their skins first set by the tuner
  /// (storage first re-sorted by cell, ListTuner::sortByCell: the cost is a gather per array, far
  /// less than the cache misses of neighbours scattered in memory). A re-sort moves slots, so it
  /// rebuilds every list.
  void rebuildList(bool sort);
  /// Contact list only, when it alone is out of date. With a Coulomb list the storage is not
  /// re-sorted here (that would invalidate the Coulomb list's slots; it is re-sorted when the
  /// Coulomb list is rebuilt, often enough for locality), and the contact list is filtered from
  /// the Coulomb list's rows while that still holds every pair within the contact list's range:
  /// a pair within R now was within R + 2 d when the Coulomb list was built, d bounding every
  /// displacement since.
  void rebuildContactList();

  /// Builds the Coulomb solvers from designCoulomb's parameters for the configured accuracy
  /// (md/coulomb/CoulombDesign.h, docs/coulomb.md); the contact list then reaches r_fast. The
  /// error estimates scale with sum q^2: parameters are chosen for sum_q2_design (the engine uses
  /// the larger of the initial sum q^2 and N, i.e. charges of order the unit q_ref at least, since
  /// an exchanging gas starts neutral) and stored, so that a restart reuses them.
  void setupCoulomb(double sum_q2_design);

  /// The slow Coulomb force of the current positions (SlowCoulomb::evaluate), with the
  /// interval's bookkeeping: the interval that ends here and the next one (chooseEvery).
  void evaluateCoulomb();

  /// The slow Coulomb force of the current positions, without the interval's bookkeeping.
  void evaluateSlowForce();

  /// The next slow interval (Engine.h, "multiple time stepping"). Fixed: every_base. Following
  /// the gas: the interval over which the fastest pair, approaching at 2 max|u| (a bound on every
  /// relative speed), moves as far as a pair at the impact speed the time step resolves
  /// (integrator.impact_speed_max) moves in every_base steps, within [every_base, every_cap].
  /// A maximum is exact, so the choice does not depend on the thread count; it reads only the
  /// drift velocities, which a checkpoint restores to the bit.
  /// An interval never reaches past the next change of the time step (slow_interval_end), so
  /// that the change falls on an evaluation (changeTimeStep).
  int chooseEvery() const;

  double slowWeight(std::int64_t at) const { return slow.weight(at); }

  /// \param slow_weight weight of the slow Coulomb force in this step's force (0: not added)
  ContactStep makeStep(double dt_taken, double slow_weight, double prev_weight) const;

  /// a += c F_slow, per slot (a: the velocities or the forces).
  void addSlow(DVec<Vec3>& a, double c);
  void kickSlow(double c) { addSlow(p.vel, c); }
  void addSlowForce(double c) { addSlow(p.force, c); }

  /// The slow interval's bounds in steps of the current dt (SlowSchedule::boundsFor).
  void slowBoundsForStep();

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
  void changeTimeStep(double dt_new, std::int64_t next_change);

  /// After a change of dt: t counts from here. (The same step keeps its origin, so that a run
  /// resumed within an epoch, which re-announces the epoch's end, keeps the uninterrupted run's
  /// times to the bit.)
  void moveTimeOrigin(double dt_old);

  /// The granular temperature T_g = (1/3N) sum (v - <v>)^2 of the integrator's velocities (sums
  /// in id order, as Engine::observables).
  double temperature() const;

  /// Forces of the current positions into p.f (state as in ContactForce.h; dt_taken = 0 for a
  /// state given at full step); counts collisions; aborts on NaN / deep overlap. With Coulomb, at
  /// every `every`-th step (counted from the last evaluation) the Coulomb force is evaluated first
  /// and enters p.f with weight `every` (the impulse), and between evaluations not at all.
  /// \param advance also complete this step and open the next in the same pass (ContactStep::
  /// advance_dt): afterwards the state is as after openStep(), one step on.
  void computeForces(double dt_taken, bool advance = false);

  /// Forces of a state given at full step (initial or restored state without forces): the
  /// predicted velocities are v itself and no pair counts as a new collision.
  void computeInitialForces();

  /// Applies a deferred closing kick: afterwards v = v(t).
  void finishStep();

  ContactSummary summary() const { return contactSummary(p, nl, box, contact); }

  /// Velocity offset of the impulse integrator against the smooth trajectory, per unit Coulomb
  /// force: (k/2 - j) dt at j = 1..k-1 steps after an evaluation, 0 at the evaluation step itself
  /// (whose v(t) holds half the impulse) and with k = 1 (Engine.h).
  double velocityOffset() const { return coulomb ? slow.velocityOffset(step, dt) : 0.0; }
  /// v - velocityOffset() * F_coulomb, per slot.
  void smoothVelocities(DVec<double>& sx, DVec<double>& sy, DVec<double>& sz) const;

  /// The Coulomb energy of the current positions: from the last evaluation when it was at this
  /// step, otherwise evaluated afresh (observables between evaluations; the forces of the run are
  /// not touched, and re-building the Coulomb list changes no result: rows are in id order).
  double coulombEnergyNow();

  [[noreturn]] void abort(int worst);

  /// A drift with drift velocities of largest |u|^2 = max_u2 was taken: bounds and step count.
  /// Each stored position moves by dt u up to the rounding of x + dt u and of the wrap, half an ulp
  /// of L each per component: 2 ulp(L) per step bounds that for the vector, so that the bounds
  /// hold to the last bit, also for a gas so cold that dt |u| is itself of the order of an ulp.
  void driftTaken(double max_u2);

  /// [Previous closing kick +] opening kick + drift (VelocityVerlet.h).
  void openStep();

  /// `steps` velocity-Verlet steps; afterwards the forces are those of the new positions and the
  /// closing kick is pending. A step is two passes over the particles: the opening pass (kick +
  /// drift) and the force pass. The force pass also completes the step and opens the next
  /// (ContactStep::advance_dt), so the steps in between take one pass each: open, then (forces +
  /// close + open) steps - 1 times, then forces -- the same operations in the same order as
  /// separate passes (VelocityVerlet.h: one arithmetic).
  void advance(std::int64_t steps);
};

}  // namespace granagg::md
