#pragma once
/// \file ImpactSpeed.h
/// The impact speed that sets the adaptive time step (integrator.dt = "adaptive", docs/model.md
/// section 6, "Adaptive time step"). The fixed step resolves the contact of the fastest impact
/// expected at the initial temperature; the adaptive one re-applies that rule to the gas as it
/// is, taking the larger of two speeds:
///   - the Maxwellian tail of the current granular temperature: the speed exceeded by a fraction
///     1e-6 of collisions, v_T = sqrt(4 T_g ln 1e6) (Engine::impactSpeedMax at T_g);
///   - the fastest impact a pair of the contact list can still make, v_pair below, times a
///     margin (EngineTimeStep.cpp: ADAPTIVE_PAIR_MARGIN).
/// v_pair is an energy: the normal speed a pair would have at first touch if its normal energy
/// were all kinetic. For a pair in contact it counts the elastic energy, so that a persistent
/// contact (a sticking pair of the charged gas, a pair pressed in a cluster) is resolved like an
/// impact whose largest overlap is the present one: for Hertz, the small oscillation about a static
/// overlap xi_s has the period 2 pi (m / (1.5 E xi_s^{1/2}))^{1/2}, 1.56 times the duration of
/// the impact at v_pair(xi_s) (t_c = 2.94 xi_max / v), so a step that resolves that impact by n
/// steps resolves the oscillation by 1.56 n. For an attractive pair not yet in contact it adds
/// the Coulomb energy it gains until contact, K |q_i q_j| (1 - 1/r), so that a pair that is about
/// to fall together is resolved at the speed it will hit with.
#include "common/HostDevice.h"

namespace granagg::md {

/// v_pair^2 of a listed pair at centre distance r (diameter 1), approaching at the normal rate
/// `approach` (> 0 closing; its square counts either way: a pair in contact or bound by attraction
/// comes back), with Coulomb coupling kqq = K q_i q_j, for reduced mass m_eff.
template <class Potential>
HD double pairImpactSpeed2(double r, double approach, double kqq,
                           const typename Potential::Params& params, double m_eff) {
  double v2 = approach * approach;
  if (r < 1.0)
    v2 += 2.0 * Potential::elasticEnergy(1.0 - r, params) / m_eff;
  else if (kqq < 0.0)
    v2 += 2.0 * (-kqq) * (1.0 - 1.0 / r) / m_eff;
  return v2;
}

}  // namespace granagg::md
