#pragma once
/// \file ContactForce.h
/// Launchers for normal contact forces (device source; Thrust). Written once for every contact
/// model: the functor gathers, for particle i, the force of every neighbour j in contact and calls
/// Potential::normalForce -- the same HD function the unit tests call. Each thread writes only its
/// own particle: no atomics, and sums in the sorted neighbour order (deterministic).
///
/// Velocities in the dissipative term: velocity Verlet evaluates forces after the drift, when
/// only the half-step velocity v(t+dt/2) is known. The approach rate uses the predicted
/// v(t+dt) = v(t+dt/2) + (dt/2) f(t) / m (computed by kickDrift or predictVelocities), second
/// order in dt like the rest of the scheme (using v(t+dt/2) directly, as LAMMPS' fix nve does, is
/// first order in the damping force).
///
/// The per-step pass computes only what every step needs (forces, collisions, the NaN / overlap
/// check) and closes the velocity-Verlet step; energies, overlaps and contact counts are a separate
/// pass over the same list, run only when observables are sampled (contactSummary).
#include <cstdint>

#include "common/Box.h"
#include "md/engine/ParticleData.h"
#include "md/neighbor/NeighborList.h"

namespace granagg::md {

/// What one force pass found.
struct ContactStepResult {
  std::int64_t collisions = 0;  ///< pairs whose contact started at this step
  int worst = 0;                ///< max of ContactWork::bad (0: all good)
};

/// Per-particle scratch of the force pass.
struct ContactWork {
  DVec<Scalar4> vp;               ///< predicted velocities v(t+dt) (input, see above; w unused)
  DVec<int> bad;                  ///< 1: non-finite force or position, 2: overlap beyond the bound
  DVec<ContactStepResult> block_flags;  ///< per-block partial results (md/engine/Launch.h)
  void resize(std::size_t n);
};

/// Contact forces of the current positions into p.fx, p.fy, p.fz (approach rates from work.vp),
/// then the closing kick v += close_half_dt * f (pass 0 to leave v alone, e.g. for the forces of an
/// initial state). \param max_overlap bound that flags a particle in work.bad.
template <class Potential>
ContactStepResult computeContactForces(ParticleData& p, const NeighborList& nl, const common::Box& box,
                                       const typename Potential::Params& params, double max_overlap,
                                       double close_half_dt, ContactWork& work);

/// Contact statistics of the current positions (positions only: no velocities needed).
struct ContactSummary {
  double elastic_energy = 0.0;  ///< sum over pairs in contact
  double overlap_sum = 0.0;     ///< sum of overlaps over pairs in contact (each pair once)
  double max_overlap = 0.0;
  std::int64_t contacts = 0;    ///< sum over particles of partners in contact (2 x pairs)
};
template <class Potential>
ContactSummary contactSummary(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                              const typename Potential::Params& params);
/// Largest overlap of each particle (storage order), for error messages.
template <class Potential>
void maxOverlapPerParticle(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                           const typename Potential::Params& params, DVec<double>& out);

}  // namespace granagg::md
