#pragma once
/// \file RealSpace.h
/// Real-space (short-range) part of the Ewald splitting of the Coulomb interaction (design.md
/// section 2; Ewald 1921; Frenkel & Smit, Understanding Molecular Simulation, sec. 12.1).
///
/// The Coulomb pair energy K q_i q_j / r is split with the splitting parameter alpha (units 1/d)
/// into a short-range part K q_i q_j erfc(alpha r) / r, summed in real space up to a cutoff, and a
/// smooth long-range part K q_i q_j erf(alpha r) / r, summed in reciprocal space (EwaldReference)
/// or on a mesh (Pppm). These functions are the real-space pair terms: the same HD code is called
/// by the engine's neighbour-list launcher, by the Ewald reference and by the unit tests.
///
/// Units: reduced (d = 1); K = l_B / d is the coupling constant (force between two unit charges
/// at unit distance), charges in units of q_ref, energies in T0, forces in T0 / d.
#include <cmath>

#include "common/HostDevice.h"

namespace granagg::md {

/// 2 / sqrt(pi)
constexpr double TWO_OVER_SQRT_PI = 1.1283791670955126;

/// Real-space Ewald pair energy K q_i q_j erfc(alpha r) / r, for r > 0.
HD inline double ewaldRealEnergy(double qiqj, double r, double alpha, double K) {
  return K * qiqj * ::erfc(alpha * r) / r;
}

/// Magnitude factor of the real-space Ewald pair force: the force on i is
///     F_i = ewaldRealForceOverR(...) * (r_i - r_j),
/// i.e. K q_i q_j [erfc(alpha r) / r^2 + (2 alpha / sqrt(pi)) exp(-alpha^2 r^2) / r] / r, which is
/// -d/dr of ewaldRealEnergy divided by r (repulsive for like charges). Returning F/r avoids a
/// square root and a division per component in the pair loop.
HD inline double ewaldRealForceOverR(double qiqj, double r, double alpha, double K) {
  const double ar = alpha * r;
  const double inv_r = 1.0 / r;
  return K * qiqj * (::erfc(ar) * inv_r + TWO_OVER_SQRT_PI * alpha * ::exp(-ar * ar)) * inv_r * inv_r;
}

/// The same force factor for the MD hot loop, with erfc from Abramowitz & Stegun 7.1.26 (absolute
/// error below 1.5e-7 for x >= 0; the form LAMMPS' pair coul/long uses): erfc(x) ~ t P(t) exp(-x^2)
/// with t = 1 / (1 + p x), so one exp serves both terms and no libm erfc is called. The force error
/// is below 1.5e-7 K |q_i q_j| / r^2, far under the requested Ewald accuracies (>= 1e-6 relative to
/// K); the references (EwaldReference, the tests) keep the exact ewaldRealForceOverR.
HD inline double ewaldRealForceOverRFast(double qiqj, double r, double alpha, double K) {
  constexpr double P = 0.3275911, A1 = 0.254829592, A2 = -0.284496736, A3 = 1.421413741, A4 = -1.453152027,
                   A5 = 1.061405429;
  const double ar = alpha * r;
  const double e = ::exp(-ar * ar);
  const double t = 1.0 / (1.0 + P * ar);
  const double erfc_ar = t * (A1 + t * (A2 + t * (A3 + t * (A4 + t * A5)))) * e;
  const double inv_r = 1.0 / r;
  return K * qiqj * (erfc_ar * inv_r + TWO_OVER_SQRT_PI * alpha * e) * inv_r * inv_r;
}

}  // namespace granagg::md
