#pragma once
/// \file ContactForce.h
/// Launchers for normal contact forces (device source; Thrust). Written once for every contact
/// model: the functor gathers, for particle i, the force of every neighbour j in contact and calls
/// Potential::normalForce -- the same HD function the unit tests call. Each thread writes only its
/// own particle: no atomics, and sums in the sorted neighbour order (deterministic).
///
/// State when the pass runs (velocity Verlet with the closing kick deferred, VelocityVerlet.h):
/// positions x(t), velocities u = v(t - dt/2) (the drift velocities of the step just taken), forces
/// f(t - dt). The pass writes f(t) and leaves v alone, so every partner's u is stable while others
/// read it:
/// - Dissipative term: it needs the normal velocity at t, when only u is known. The approach rate
///   uses the predicted v(t) = u + (dt/2) f(t - dt) / m, second order in dt like the rest of the
///   scheme (using u directly, as LAMMPS' fix nve does, is first order in the damping force).
/// - Collisions: a pair in contact at t whose separation one step earlier, r - dt (u_i - u_j), was
///   at least 1 has just collided.
///
/// The pass computes only what every step needs (forces, collisions, the NaN / overlap check);
/// energies, overlaps and contact counts are a separate pass over the same list, run only when
/// observables are sampled (contactSummary).
///
/// Two loop shapes, the same arithmetic (identical results to the bit):
/// - per particle over its row (with the fast Coulomb part, which every listed pair has, and on
///   lists without the compressed pair form);
/// - over the compressed pair form (NeighborList::keepPairs; contacts only), in two passes over
///   blocks of particles: the first computes each pair's contact once (Newton's third law), the
///   second lets every particle gather its pairs' forces over its row. Each pass screens all
///   entries of its block in one branch-free loop and does the work for the hits only: in a
///   dilute gas a row holds one or two entries and about one in eight is in contact, so per-row
///   loops spent their time in mispredicted loop exits and contact tests (docs/benchmarks.md).
///   Both passes write only the block's own pairs and particles: no atomics, and sums in row order.
///   On CUDA a block is one particle. With a bound on the displacements since the list was built
///   (ContactStep::displacement_bound) the first pass skips the pairs that cannot have come into
///   contact since it last looked at them (the same contacts, fewer distance tests).
/// Both shapes can also finish the step and open the next (ContactStep::advance_dt): the pass that
/// completes a particle's force (the row pass, or the gathering pass) advances it at once.
#include <cstdint>

#include "common/Box.h"
#include "md/coulomb/RealSpace.h"
#include "md/engine/ParticleData.h"
#include "md/neighbor/NeighborList.h"
#include "md/potentials/ChargeExchange.h"
#include "md/potentials/ContactModels.h"

namespace granagg::md {

/// What one force pass found.
struct ContactStepResult {
  std::int64_t collisions = 0;  ///< pairs whose contact started at this step
  int worst = 0;  ///< worst particle: 0 all good, 1 non-finite force or position, 2 overlap beyond
                  ///< the bound
  double max_u2 = 0.0;  ///< with ContactStep::advance_dt: largest |u|^2 of the new drift velocities
};

/// Per-block partial result of a force pass (md/engine/Launch.h).
struct StepAccum {
  std::int64_t collisions = 0;
  double probe = 0.0;  ///< sum of forces and positions: not finite iff one of them is not
  double max_overlap = 0.0;
  double max_u2 = 0.0;
};

/// Scratch of the force pass.
struct ContactWork {
  DVec<Vec3> f;                 ///< forces being computed (swapped with ParticleData's)
  DVec<Scalar4> pos;            ///< advance_dt: the next positions (swapped with ParticleData's)
  DVec<Vec3> vel;               ///< advance_dt: the next drift velocities (swapped likewise)
  DVec<StepAccum> block_flags;  ///< per-block partial results (md/engine/Launch.h)
  // compressed pair form (ContactForce.cpp), kept from pass to pass for the list of generation
  // `pairs_of` (NeighborList::generation):
  DVec<unsigned char> pair_hit;   ///< each pair's contact at the last pass
  DVec<unsigned char> entry_hit;  ///< the same per entry (both entries of each pair)
  DVec<Vec3> pair_f;              ///< force on the owner of each pair in contact
  DVec<double> pair_dq;           ///< charge the owner of each pair in contact gains
  /// With ContactStep::displacement_bound: pair p cannot be in contact while the bound stays at
  /// or below pair_next[p]; valid for bounds from `next_bound` on (< 0: not valid).
  DVec<double> pair_next;
  std::uint64_t pairs_of = 0;
  double next_bound = -1.0;
  void resize(std::size_t n);
};

/// What the force pass needs to know about the step.
struct ContactStep {
  double dt = 0.0;  ///< the step just taken (0 for a state given at full step, e.g. an initial
                    ///< state: v is then v(t) itself and no pair counts as a new collision)
  double max_overlap = 1.0;  ///< an overlap beyond this flags the result
  std::int64_t step = 0;     ///< step number (counter of the charge-exchange random numbers)
  ChargeExchange::Params charging{};
  /// Charging on: per-particle charge gained this step, written where nonzero (the caller applies
  /// and clears it before the next pass: kickDrift / closeKick). Null: no charging.
  double* dq = nullptr;
  /// Slow forces computed elsewhere (the Coulomb force: real space + mesh, or a plain-Ewald
  /// evaluation), per slot; null: none. The step's force is f_contact + ext_force_scale * ext, and
  /// the predicted velocities of the dissipative term get ext_predict_scale * ext added. For the
  /// engine's impulse multiple-time-step integrator (Engine.h) with slow weight w_n = k at slow
  /// steps and 0 between: ext_force_scale = w_n and ext_predict_scale = (dt/2)(w_n - w_{n-1}),
  /// because f_old holds w_{n-1} ext (the impulse of the previous step is not part of the
  /// velocity trend) and this step's half impulse belongs to v(t). With every step slow (k = 1)
  /// the weight is 1 and the prediction needs no correction.
  const double *ext_fx = nullptr, *ext_fy = nullptr, *ext_fz = nullptr;
  double ext_force_scale = 1.0, ext_predict_scale = 0.0;
  /// Fast part of the Coulomb force, added at every step: the bare pair force S(r) K q_i q_j / r^2
  /// for r < fast.r2 <= the real-space cutoff (md/coulomb/RealSpace.h; the slow part is the Ewald
  /// total minus this), from fast_table (fastPairTableValues on [0, fast.r2^2]); fast.r2 = 0: none.
  /// The list must reach that range.
  RealSpaceSwitch fast{};
  PairTable fast_table{};
  double coulomb_K = 0.0;
  /// > 0: the pass also completes the step and opens the next one (velocity Verlet,
  /// VelocityVerlet.h) for each particle as soon as its force f(t) is known: closing kick v(t) = u
  /// + (dt/2) f(t), opening kick u' = v(t) + (dt/2) f(t), drift x' = x + dt u' (wrapped, images
  /// counted), and with charging q' = q + dq. The same arithmetic as kickDrift() after the pass, in
  /// one sweep over the particles instead of two; the new positions and velocities go to
  /// ContactWork and are swapped in after the pass, so every partner's x and u stay those of t
  /// while others read them. dt must equal this value (fixed step). On a non-finite force or
  /// deep overlap nothing is advanced (the forces are stored, positions and velocities stay those
  /// of t, for the error report; image counts may already have moved).
  double advance_dt = 0.0;
  /// >= 0: a bound on every particle's displacement since the list was built, non-decreasing from
  /// pass to pass while the list stays the same (the engine's sum of dt max|u| plus rounding).
  /// The compressed-pair pass then screens a pair only once the bound has grown by half the
  /// pair's distance from contact at its last screening: before that neither partner can have
  /// closed the gap. < 0 (unknown): every pair is screened at every pass.
  double displacement_bound = -1.0;
};

/// Contact forces of the current positions into p.force (state as described above),
/// collisions, and with charging the charge each particle gains at its new contacts.
ContactStepResult computeContactForces(ParticleData& p, const NeighborList& nl,
                                       const common::Box& box, const ContactModel& model,
                                       const ContactStep& step, ContactWork& work);

/// Contact statistics of the current positions (positions only: no velocities needed).
struct ContactSummary {
  double elastic_energy = 0.0;  ///< sum over pairs in contact
  double overlap_sum = 0.0;     ///< sum of overlaps over pairs in contact (each pair once)
  double max_overlap = 0.0;
  std::int64_t contacts = 0;  ///< sum over particles of partners in contact (2 x pairs)
};
ContactSummary contactSummary(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                              const ContactModel& model);
/// The largest v_pair^2 over the pairs of the list (md/potentials/ImpactSpeed.h): the adaptive
/// time step's pair criterion, from the positions, the charges and the velocities p.vel (at full
/// step: call between steps). `coulomb_K` is K (0 without Coulomb forces). A maximum is exact,
/// so the result does not depend on the thread count or the storage order.
double maxPairImpactSpeed2(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                           const ContactModel& model, double coulomb_K, double m_eff);
/// Largest overlap of each particle (storage order), for error messages.
void maxOverlapPerParticle(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                           const ContactModel& model, DVec<double>& out);

}  // namespace granagg::md
