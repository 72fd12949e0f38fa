#pragma once
/// \file ContactForce.h
/// Launcher for normal contact forces (device source; Thrust). Written once for every contact
/// model: the functor gathers, for particle i, the force of every neighbour j in contact and calls
/// Potential::normalForce -- the same HD function the unit tests call. Each thread writes only its
/// own particle: no atomics, and sums in the sorted neighbour order (deterministic).
///
/// Velocities in the dissipative term: velocity Verlet evaluates forces after the drift, when
/// only the half-step velocity v(t+dt/2) is known. The approach rate uses the predicted
/// v(t+dt) = v(t+dt/2) + (dt/2) f(t) / m, second order in dt like the rest of the scheme (using
/// v(t+dt/2) directly, as LAMMPS' fix nve does, is first order in the damping force).
#include <cstdint>

#include "common/Box.h"
#include "md/engine/ParticleData.h"
#include "md/neighbor/NeighborList.h"

namespace granagg::md {

/// Per-particle results of one force evaluation, besides the forces themselves.
struct ContactWork {
  DVec<double> fx, fy, fz;        ///< new forces (swapped into ParticleData by the engine)
  DVec<double> energy;            ///< half the elastic energy of each contact of i
  DVec<double> overlap_upper;     ///< sum of overlaps with partners j > i (pairs counted once)
  DVec<double> max_overlap;       ///< largest overlap of i (0 without contacts)
  DVec<int> contacts;             ///< partners in contact with i
  DVec<int> new_contacts_upper;   ///< partners j > i whose contact started this step (collisions)
  DVec<int> bad;                  ///< 1: non-finite force, 2: overlap beyond the bound
  DVec<double> vpx, vpy, vpz;     ///< predicted velocities v + (dt/2) f, once per particle per step
  void resize(std::size_t n);
};

/// Evaluates contact forces of the current positions into `work` for Potential (HertzViscoelastic
/// or SpringDashpot). \param half_dt dt/2, for the predicted velocities; \param max_overlap bound
/// that flags a particle in work.bad.
template <class Potential>
void computeContactForces(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                          const typename Potential::Params& params, double half_dt, double max_overlap,
                          ContactWork& work);

}  // namespace granagg::md
