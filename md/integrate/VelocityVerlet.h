#pragma once
/// \file VelocityVerlet.h
/// Velocity Verlet for unit masses (device source). One step is
///     v += (dt/2) f(t);  x += dt v;  [wrap, images];  f(t + dt);  v += (dt/2) f(t + dt)
/// -- symplectic and time-reversible for conservative forces: energy errors O(dt^2), no drift
/// (Swope et al., J. Chem. Phys. 76, 637 (1982)).
///
/// The engine runs the first half (kick and drift) as one pass, kickDrift(), which also stores the
/// predicted full-step velocity the dissipative contact force needs (ContactForce.h), and the
/// closing kick inside the force pass (computeContactForces) as soon as a particle's new force is
/// known: two passes over the particles per step instead of five, with the same arithmetic in the
/// same order (bit-identical to separate kick / drift / predict / kick passes).
#include "common/Box.h"
#include "md/engine/ParticleData.h"

namespace granagg::md {

/// Predicted full-step velocities vp = v + half_dt f (packed; w unused).
void predictVelocities(const ParticleData& p, double half_dt, DVec<Scalar4>& vp);

/// Opening half of a step: v += half_dt f; vp = v + half_dt f (prediction of v(t + dt));
/// pos_prev = pos; x += dt v; wrap into [0, L) and update the image counts.
/// Returns the largest squared displacement from `reference` (the neighbour list's positions at its
/// last build, NeighborList::referencePositions(); 0 if null), computed in the same pass.
/// \param block_max scratch for the per-block maxima.
double kickDrift(ParticleData& p, double half_dt, double dt, const common::Box& box, DVec<Scalar4>& vp,
                 const Scalar4* reference, DVec<double>& block_max);

}  // namespace granagg::md
