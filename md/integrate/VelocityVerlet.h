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

/// One particle's share of the opening pass: [closing kick v = u + (dt/2) f,] opening kick
/// u' = v + (dt/2) f, drift x' = x + dt u' (wrapped; image counts change only on a crossing), and
/// with dq (the charge exchanged at the last force pass, non-null) q' = q + *dq, clearing *dq.
/// Writes u' and x' (with q') and returns |u'|^2. kickDrift() and the fused force pass
/// (ContactStep::advance_dt) both call it: one arithmetic, so the two give identical trajectories.
HD_INLINE double kickDriftParticle(const common::Box& box, double h, double dt, bool close,
                                   const Vec3& f, const Vec3& v, const Scalar4& r, double* dq,
                                   int& ix, int& iy, int& iz, Vec3& u_out, Scalar4& r_out) {
  double u0 = v.x, u1 = v.y, u2 = v.z;
  if (close) {  // v(t) = u(t - dt/2) + (dt/2) f(t)
    u0 += h * f.x;
    u1 += h * f.y;
    u2 += h * f.z;
  }
  u0 += h * f.x;  // u(t + dt/2) = v(t) + (dt/2) f(t)
  u1 += h * f.y;
  u2 += h * f.z;
  u_out = Vec3{u0, u1, u2};
  double q = r.w;
  if (dq && *dq != 0.0) {
    q += *dq;
    *dq = 0.0;
  }
  double a = r.x + dt * u0, b = r.y + dt * u1, c = r.z + dt * u2;
  if (!box.insideAll(a, b, c)) {  // nearly always inside: one test, no branch per component
    const int sa = box.wrap(a), sb = box.wrap(b), sc = box.wrap(c);
    if (sa) ix += sa;
    if (sb) iy += sb;
    if (sc) iz += sc;
  }
  r_out = Scalar4{a, b, c, q};
  return u0 * u0 + u1 * u1 + u2 * u2;
}

/// Opening pass of a step: [if close_pending: v += half_dt f (the previous step's closing kick)];
/// v += half_dt f; x += dt v; wrap into [0, L) and update the image counts; with dq (charging)
/// q += dq and dq = 0, the charges exchanged at the previous force pass.
/// Returns the largest |v|^2 of the drift velocities (a bound on this step's displacements for the
/// neighbour-list check). \param block_max scratch for the per-block maxima.
double kickDrift(ParticleData& p, double half_dt, double dt, const common::Box& box,
                 bool close_pending, double* dq, DVec<double>& block_max);

/// The closing kick alone: v += half_dt f; with dq, q += dq and dq = 0.
void closeKick(ParticleData& p, double half_dt, double* dq);

}  // namespace granagg::md
