#pragma once
/// \file VelocityVerlet.h
/// Velocity Verlet for unit masses (device source). One step is
///     v += (dt/2) f(t);  x += dt v;  [wrap, images];  f(t + dt);  v += (dt/2) f(t + dt)
/// -- symplectic and time-reversible for conservative forces: energy errors O(dt^2), no drift
/// (Swope et al., J. Chem. Phys. 76, 637 (1982)).
///
/// The engine runs a step as two passes over the particles: kickDrift() (opening kick and drift)
/// and the force pass (ContactForce.h). The closing kick of a step is deferred to the opening pass
/// of the next one, which applies both kicks, (v + (dt/2) f) + (dt/2) f, in the same order as
/// separate passes would (bit-identical); when a full-step velocity is wanted between steps
/// (output, observables, checkpoints) closeKick() applies it alone. Between the passes v therefore
/// holds the drift velocity u = v(t - dt/2), which the force pass reads for neighbours while
/// writing the new forces elsewhere: no particle's data changes while others read it.
/// Contact-only force passes can take over the kicks and the drift themselves (ContactStep::
/// advance_dt), writing the next positions and velocities to second buffers: the steps between
/// the first and the last of Engine::run are then one pass each, with this file's arithmetic.
#include "common/Box.h"
#include "md/engine/ParticleData.h"

namespace granagg::md {

/// Opening pass of a step: [if close_pending: v += half_dt f (the previous step's closing kick)];
/// v += half_dt f; x += dt v; wrap into [0, L) and update the image counts; with dq (charging)
/// q += dq and dq = 0, the charges exchanged at the previous force pass.
/// Returns the largest |v|^2 of the drift velocities (a bound on this step's displacements for the
/// neighbour-list check). \param block_max scratch for the per-block maxima.
double kickDrift(ParticleData& p, double half_dt, double dt, const common::Box& box, bool close_pending, double* dq,
                 DVec<double>& block_max);

/// The closing kick alone: v += half_dt f; with dq, q += dq and dq = 0.
void closeKick(ParticleData& p, double half_dt, double* dq);

}  // namespace granagg::md
