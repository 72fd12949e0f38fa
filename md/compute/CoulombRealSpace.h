#pragma once
/// \file CoulombRealSpace.h
/// Launchers for the real-space part of the Ewald-split Coulomb force over a neighbour list that
/// reaches the real-space cutoff (device source; Thrust). Like the contact pass, each particle
/// gathers over its own full row (sorted by particle id): no atomics, and the sums do not depend
/// on the thread count or the storage order. The pair terms are md/coulomb/RealSpace.h.
///
/// The engine evaluates this part, with the mesh part, as the slow force of its multiple-time-step
/// integrator (Engine.h, `coulomb.every`), on a list of its own: the contact pass then walks only
/// the short contact list every step.
#include "common/Box.h"
#include "md/coulomb/RealSpace.h"
#include "md/engine/ParticleData.h"
#include "md/neighbor/NeighborList.h"

namespace granagg::md {

/// Real-space parameters: pair force K q_i q_j [erfc(alpha r)/r^2 + (2 alpha/sqrt pi) exp(-alpha^2
/// r^2)/r] along r_ij for r < r_cut.
struct CoulombRealParams {
  double K = 0.0, alpha = 0.0, r_cut = 0.0;
  /// coulombRealForces computes the slow part: the real-space force minus the fast part S(r) K q_i
  /// q_j / r^2
  RealSpaceSwitch fast{};
  /// The slow force over r tabulated on [0, r_cut^2] (slowPairTableValues), or null: computed
  PairTable table{};
  /// coulombRealEnergy: erfc(alpha r) / r tabulated on [0, r_cut^2] (energyPairTableValues),
  /// used from r^2 = ENERGY_TABLE_R2_MIN on, or null: libm's erfc for every pair
  PairTable energy_table{};
};

/// Real-space forces (their slow part, see CoulombRealParams::fast) of the current positions and
/// charges into fx, fy, fz (overwritten; resized to N). The list must reach r_cut (std::logic_error
/// otherwise).
void coulombRealForces(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                       const CoulombRealParams& prm, DVec<double>& fx, DVec<double>& fy,
                       DVec<double>& fz);

/// Real-space energy sum over pairs i < j of K q_i q_j erfc(alpha r)/r (exact erfc).
double coulombRealEnergy(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                         const CoulombRealParams& prm);

}  // namespace granagg::md
