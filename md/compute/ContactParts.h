#pragma once
/// \file ContactParts.h
/// The parts the contact force pass (ContactForce.cpp) is composed of, one job each:
/// - Geometry: positions and the minimum image;
/// - StepState: the integrator's side of a contact (predicted velocities, the collision test);
/// - SlowForce: forces computed elsewhere, added to the step's force and to the prediction;
/// - Charging: collisional charge exchange at new contacts;
/// - FastCoulomb: the fast part of the Coulomb force;
/// - StepAdvance: the step completed and the next one opened in the same pass;
/// - PairScreen: the compressed pair form's screening by the displacement bound.
/// The contact law itself is the Potential's (ContactModels.h).
///
/// The pass stays one fused loop (ContactForce.h). Its functor keeps the parts' fields in one flat
/// record and hands out each part as a view: a small value of pointers and references to the
/// functor's own fields, made at the call and folded away by the compiler (every method here is
/// HD_INLINE). Views refer to the functor's fields and never copy them: an out-of-line call
/// (the charge exchange's random numbers, in the row passes) would otherwise get a copy built on
/// the stack at every contact. So the passes compile to the instructions of the functor written
/// without parts, up to register allocation and the order of a few instructions
/// (scripts/contact_codegen.py); a record regrouped by part changed the neutral passes' code
/// (docs/ARCHITECTURE.md, "The contact pass"). A part that a pass does not use is compiled out by
/// its template switch (ON = false). Device source (Thrust types): included by ContactForce.cpp.
#include <cstdint>

#include "common/Box.h"
#include "common/HostDevice.h"
#include "md/coulomb/RealSpace.h"
#include "md/engine/ParticleData.h"
#include "md/integrate/VelocityVerlet.h"
#include "md/potentials/ChargeExchange.h"

namespace granagg::md::contact {

/// Positions and the minimum image.
struct Geometry {
  const Scalar4* pos;
  const common::Box& box;
  /// Separation r_i - r_j (minimum image; positions are wrapped into [0, L), so one conditional
  /// shift per component is enough) and its square.
  HD_INLINE double separation(const Scalar4& ri, const Scalar4& rj, double& rx, double& ry,
                              double& rz) const {
    rx = box.minimumImageWrapped(ri.x - rj.x);
    ry = box.minimumImageWrapped(ri.y - rj.y);
    rz = box.minimumImageWrapped(ri.z - rj.z);
    return rx * rx + ry * ry + rz * rz;
  }
};

/// The integrator's side of a contact (ContactForce.h): velocity Verlet with the closing kick
/// deferred, so the pass sees the drift velocities u = v(t - dt/2) and the forces f(t - dt).
struct StepState {
  const Vec3* vel;    // drift velocities u = v(t - dt/2) of the step just taken
  const Vec3* f_old;  // f(t - dt), which kicked u
  double h_pred;      // dt/2
  double dt_prev;     // the step just taken
  /// The predicted full-step velocity u + (dt/2) f_old of particle k (second order in dt; the
  /// slow forces' correction is SlowForce::addToPrediction).
  HD_INLINE void predicted(int k, double& a, double& b, double& c) const {
    const Vec3 u = vel[k], f = f_old[k];
    a = u.x + h_pred * f.x;
    b = u.y + h_pred * f.y;
    c = u.z + h_pred * f.z;
  }
  /// Whether the pair at separation r (in contact now) was apart one step earlier, i.e. its
  /// contact started this step. The earlier separation is r - dt (u_i - u_j), the drift undone:
  /// antisymmetric in i and j to the last bit, so both partners agree, as they must for the
  /// charge exchange.
  HD_INLINE bool apartBefore(int i, int j, double rx, double ry, double rz) const {
    const Vec3 ui = vel[i], uj = vel[j];
    const double px = rx - dt_prev * (ui.x - uj.x), py = ry - dt_prev * (ui.y - uj.y),
                 pz = rz - dt_prev * (ui.z - uj.z);
    return px * px + py * py + pz * pz >= 1.0;
  }
};

/// Slow forces computed elsewhere (ContactStep::ext_*): weight `force_scale` in this step's force
/// and `predict_scale` in the predicted velocity (the multiple-time-step impulse, ContactStep).
/// ON = false: none.
template <bool ON>
struct SlowForce {
  const double *fx, *fy, *fz;
  double force_scale, predict_scale;
  HD_INLINE void addToPrediction(int k, double& a, double& b, double& c) const {
    if (ON && predict_scale != 0.0) {
      a += predict_scale * fx[k];
      b += predict_scale * fy[k];
      c += predict_scale * fz[k];
    }
  }
  HD_INLINE void addToForce(int i, double& f0, double& f1, double& f2) const {
    if (ON && force_scale != 0.0) {
      f0 += force_scale * fx[i];
      f1 += force_scale * fy[i];
      f2 += force_scale * fz[i];
    }
  }
};

/// Collisional charging at new contacts (ChargeExchange.h). ON = false: compiled out, so the
/// neutral pass keeps the random-number code out of its registers.
template <bool ON>
struct Charging {
  const int* id;
  const ChargeExchange::Params& params;
  std::int64_t step;  // the counter of the charge exchange's random numbers
  double* dq;         // the charge each particle gains at this step's new contacts
  /// The charge i gains at a new contact with j (xi_dot is the same for both partners: g and n
  /// both change sign).
  HD_INLINE double transfer(int i, int j, double xi_dot) const {
    return ChargeExchange::transferTo(params, step, static_cast<std::uint32_t>(id[i]),
                                      static_cast<std::uint32_t>(id[j]), xi_dot);
  }
  /// Stores i's gain, applied by the next kick pass (charges are read by others now).
  HD_INLINE void store(int i, double dqi) const {
    if (ON && dqi != 0.0) dq[i] = dqi;
  }
  /// i's entry of dq for the step's advance; null without charging.
  HD_INLINE double* of(int i) const { return ON ? dq + i : nullptr; }
};

/// The fast part of the Coulomb force, S(r) K q_i q_j / r^2 (ContactStep::fast), tabulated and
/// zero from r2sq = (fast.r2)^2 on.
struct FastCoulomb {
  double K, r2sq;
  const PairTable& table;
  /// The pair force over r: the force on i is this times r_i - r_j.
  HD_INLINE double overR(const Scalar4& ri, const Scalar4& rj, double r2) const {
    return K * ri.w * rj.w * table(r2 < r2sq ? r2 : r2sq);
  }
};

/// The step completed and the next one opened for a particle whose force f(t) is known
/// (ContactStep::advance_dt): closing kick, opening kick and drift (kickDriftParticle). The new
/// state goes to next_pos and next_vel, swapped in after the pass. ON = false: not this pass's job.
template <bool ON>
struct StepAdvance {
  Scalar4* next_pos;
  Vec3* next_vel;
  int *ix, *iy, *iz;  // image counts
  double dt;
  /// Advances particle i at position ri with drift velocity u; returns |u'|^2 of its new one.
  HD_INLINE double apply(const common::Box& box, int i, double f0, double f1, double f2,
                         const Vec3& u, const Scalar4& ri, double* dqi) const {
    return kickDriftParticle(box, 0.5 * dt, dt, true, Vec3{f0, f1, f2}, u, ri, dqi, ix[i], iy[i],
                             iz[i], next_vel[i], next_pos[i]);
  }
};

/// The compressed pair form's screening by the displacement bound (ContactStep::
/// displacement_bound): a pair at distance r cannot touch before the bound has grown by
/// (r - 1) / 2, since both partners would have to close half the gap, so it is not screened again
/// before then. The thresholds last from pass to pass (ContactWork::pair_next).
struct PairScreen {
  double* pair_next;  // the bound up to which each pair cannot be in contact
  double bound;       // the displacement bound of this pass
  /// Covers the rounding of the separations (ulps of L) at this pass and the next.
  static constexpr double NEXT_MARGIN = 1e-12;
  /// Whether pair p may be in contact and must be screened. A pair that is not due is not in
  /// contact, and was not at the last pass (a pair in contact is due at the next one).
  HD_INLINE bool due(int p) const { return !(pair_next[p] >= bound); }
  /// Pair p, screened at squared distance r2, is not due again before the bound has grown by half
  /// its gap.
  HD_INLINE void defer(int p, double r2) const {
    pair_next[p] = bound + 0.5 * (sqrt(r2) - 1.0) - NEXT_MARGIN;
  }
};

}  // namespace granagg::md::contact
