#pragma once
/// \file RealSpace.h
/// Real-space (short-range) part of the Ewald splitting of the Coulomb interaction (docs/model.md
/// section 4; Ewald 1921; Frenkel & Smit, Understanding Molecular Simulation, sec. 12.1).
///
/// The Coulomb pair energy K q_i q_j / r is split with the splitting parameter alpha (units 1/d)
/// into a short-range part K q_i q_j erfc(alpha r) / r, summed in real space up to a cutoff, and a
/// smooth long-range part K q_i q_j erf(alpha r) / r, summed in reciprocal space (EwaldReference)
/// or on a mesh (Pppm). These functions are the real-space pair terms: the same HD code is called
/// by the engine's neighbour-list launcher, by the Ewald reference and by the unit tests.
///
/// Units: reduced (d = 1); K = l_B / d is the coupling constant (force between two unit charges
/// at unit distance), charges in units of q_ref, energies in T0, forces in T0 / d.
#include <algorithm>
#include <cmath>
#include <vector>

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
  return K * qiqj * (::erfc(ar) * inv_r + TWO_OVER_SQRT_PI * alpha * ::exp(-ar * ar)) * inv_r *
         inv_r;
}

/// The same force factor for the MD hot loop, with erfc from Abramowitz & Stegun 7.1.26 (absolute
/// error below 1.5e-7 for x >= 0; the form LAMMPS' pair coul/long uses): erfc(x) ~ t P(t) exp(-x^2)
/// with t = 1 / (1 + p x), so one exp serves both terms and no libm erfc is called. The force error
/// is below 1.5e-7 K |q_i q_j| / r^2, far under the requested Ewald accuracies (>= 1e-6 relative to
/// K); the references (EwaldReference, the tests) keep the exact ewaldRealForceOverR.
HD inline double ewaldRealForceOverRFast(double qiqj, double r, double alpha, double K) {
  constexpr double P = 0.3275911, A1 = 0.254829592, A2 = -0.284496736, A3 = 1.421413741,
                   A4 = -1.453152027, A5 = 1.061405429;
  const double ar = alpha * r;
  const double e = ::exp(-ar * ar);
  const double t = 1.0 / (1.0 + P * ar);
  const double erfc_ar = t * (A1 + t * (A2 + t * (A3 + t * (A4 + t * A5)))) * e;
  const double inv_r = 1.0 / r;
  return K * qiqj * (erfc_ar * inv_r + TWO_OVER_SQRT_PI * alpha * e) * inv_r * inv_r;
}

/// Splitting of the Coulomb force between the two levels of the multiple-time-step integrator
/// (Engine.h): the fast (every-step) part is the bare pair force S(r) K q_i q_j / r^2 and the slow
/// part the Ewald total minus it, which is smooth at short range (there the real-space term minus
/// the bare force is minus the pair's smooth erf part; the mesh carries the same, so they cancel),
/// with
/// S = 1 for r <= r1, S = 0 for r >= r2 and the quintic smoothstep in between, S(x) = 1 - x^3 (10 -
/// 15 x + 6 x^2) with x = (r - r1) / (r2 - r1): continuous with two continuous derivatives, so
/// neither level sees a kink (the RESPA split of Zhou, Harder, Xu & Berne, J. Chem. Phys. 115,
/// 2348 (2001)).
struct RealSpaceSwitch {
  double r1 = 0.0, r2 = 0.0;  ///< r2 = 0: no fast part (S = 0 everywhere)
  HD double fastFraction(double r) const {
    if (r >= r2) return 0.0;
    if (r <= r1) return 1.0;
    const double x = (r - r1) / (r2 - r1);
    return 1.0 - x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
  }
};

/// The slow pair force of a split with r1 >= 1 (every contact entirely fast), divided by K q_i q_j
/// and by r: g(r) = [erfc(alpha r)/r + (2 alpha/sqrt pi) exp(-alpha^2 r^2)] / r^2 - S(r) / r^3.
/// Where S = 1 this is minus the pair's smooth erf part, finite at r = 0 (-4 alpha^3 / (3 sqrt
/// pi)), so it is evaluated in that form there (no cancellation of two large terms).
inline double slowPairForceOverR(double r, double alpha, const RealSpaceSwitch& sw) {
  const double ar = alpha * r;
  if (r <= sw.r1) {
    if (ar <
        1e-3)  // series: erf(x)/x - 2/sqrt(pi) exp(-x^2) = (2/sqrt(pi)) (2 x^2/3 - 4 x^4/5 + ...)
      return -TWO_OVER_SQRT_PI * alpha * alpha * alpha * (2.0 / 3.0 - 0.8 * ar * ar);
    return -(std::erf(ar) / r - TWO_OVER_SQRT_PI * alpha * std::exp(-ar * ar)) / (r * r);
  }
  return (std::erfc(ar) / r + TWO_OVER_SQRT_PI * alpha * std::exp(-ar * ar)) / (r * r) -
         sw.fastFraction(r) / (r * r * r);
}

/// Piecewise-cubic interpolation in r^2 of a smooth function g (the slow or fast pair force over
/// r) on [0, r2_max] with n intervals of width h = r2_max / n. Interval k holds the monomial
/// coefficients of the cubic through g at r^2 = (k + t) h for t = 0, 1/3, 2/3, 1, so the table is
/// continuous and its error falls as h^4: a few hundred intervals (8-16 KiB, resident in the
/// first-level cache) are as accurate as 2^13 linear ones were (128 KiB, in the second level, whose
/// latency dominated the pair loops). Tabulating in r^2 needs no square root (LAMMPS's
/// `pair_modify table` does the same, linearly). Interval n repeats g(r2_max), so a lookup at
/// exactly r2_max is defined.
struct PairTable {
  const double* data = nullptr;  ///< 4 (n + 1) coefficients (device pointer)
  double inv_h = 0.0;            ///< n / r2_max
  HD double operator()(double r2) const {
    const double x = r2 * inv_h;
    const int k = static_cast<int>(x);
    const double t = x - k;
    const double* c = data + 4 * k;
    return c[0] + t * (c[1] + t * (c[2] + t * c[3]));
  }
};
/// Intervals of the engine's tables (PairTable; errors in tests/md/test_coulomb_md.cpp): the slow
/// force is smooth everywhere; the fast one is steep (1 / r^3) at deep overlaps.
constexpr int SLOW_PAIR_TABLE_INTERVALS = 256;
constexpr int FAST_PAIR_TABLE_INTERVALS = 512;
/// The observables' real-space energy (energyPairTableValues): erfc(alpha r) / r is steep at short
/// range, so its table has more intervals (32 KiB) and serves pairs from ENERGY_TABLE_R2_MIN on,
/// an overlap of 0.6 (the default run.max_overlap); closer pairs take libm's erfc.
constexpr int ENERGY_PAIR_TABLE_INTERVALS = 2048;
constexpr double ENERGY_TABLE_R2_MIN = 0.16;

/// The fast pair force of the split divided by K q_i q_j and by r: S(r) / r^3, held at its value at
/// r = 0.3 below that (no pair gets that close: an overlap of 0.7 aborts a run long before).
inline double fastPairForceOverR(double r, const RealSpaceSwitch& sw) {
  const double rr = r < 0.3 ? 0.3 : r;
  return sw.fastFraction(rr) / (rr * rr * rr);
}
/// Host coefficients of a PairTable of g (a function of r^2) with n intervals on [0, r2_max]: the
/// cubic through the samples v0..v3 at t = 0, 1/3, 2/3, 1, from their forward differences
/// (Newton's form in u = 3 t, expanded in t).
template <class G>
std::vector<double> pairTableValues(G g_of_r2, double r2_max, int n) {
  const double h = r2_max / n;
  std::vector<double> out(4 * static_cast<std::size_t>(n + 1));
  for (int k = 0; k < n; ++k) {
    const double v0 = g_of_r2(k * h), v1 = g_of_r2((k + 1.0 / 3.0) * h),
                 v2 = g_of_r2((k + 2.0 / 3.0) * h), v3 = g_of_r2((k + 1) * h);
    const double d1 = v1 - v0, d2 = v2 - 2.0 * v1 + v0, d3 = v3 - 3.0 * v2 + 3.0 * v1 - v0;
    out[4 * k] = v0;
    out[4 * k + 1] = 3.0 * (d1 - 0.5 * d2 + d3 / 3.0);
    out[4 * k + 2] = 4.5 * (d2 - d3);
    out[4 * k + 3] = 4.5 * d3;
  }
  out[4 * static_cast<std::size_t>(n)] = g_of_r2(r2_max);  // constant beyond (t = 0 at r2_max)
  return out;
}
/// A PairTable over host or device coefficients from pairTableValues(..., r2_max, n).
inline PairTable pairTable(const double* data, double r2_max, int n) {
  return PairTable{data, n / r2_max};
}
/// Table of fastPairForceOverR on [0, r2^2]; zero from r2^2 on (S(r2) = 0), so a lookup at
/// min(r^2, r2^2) is the force for any r.
inline std::vector<double> fastPairTableValues(const RealSpaceSwitch& sw,
                                               int n = FAST_PAIR_TABLE_INTERVALS) {
  return pairTableValues([&](double r2) { return fastPairForceOverR(std::sqrt(r2), sw); },
                         sw.r2 * sw.r2, n);
}
/// Table of the real-space pair energy over K q_i q_j, erfc(alpha r) / r, on [0, r2_max]. It is
/// held at its value at r^2 = ENERGY_TABLE_R2_MIN / 4 below that, well below where it is used,
/// so that the cubics it serves interpolate the smooth function.
inline std::vector<double> energyPairTableValues(double alpha, double r2_max,
                                                 int n = ENERGY_PAIR_TABLE_INTERVALS) {
  return pairTableValues(
      [&](double r2) {
        const double r = std::sqrt(std::max(r2, 0.25 * ENERGY_TABLE_R2_MIN));
        return std::erfc(alpha * r) / r;
      },
      r2_max, n);
}
/// Table of slowPairForceOverR on [0, r2_max].
inline std::vector<double> slowPairTableValues(double alpha, const RealSpaceSwitch& sw,
                                               double r2_max, int n = SLOW_PAIR_TABLE_INTERVALS) {
  return pairTableValues([&](double r2) { return slowPairForceOverR(std::sqrt(r2), alpha, sw); },
                         r2_max, n);
}

}  // namespace granagg::md
