#pragma once
/// \file MonodisperseSolver.h
/// Monodisperse approximation of the Smoluchowski equation (docs/model.md section 12; Singh & Mazza
/// 2018, the monodisperse kernel with its typo corrected in docs/model.md section 9): all clusters
/// have the same size i(t), their number density is n = M1 / i with M1 = 1 conserved, and
///
///     dn/dt = -K(i, i) n^2   <=>   di/dt = K(i, i)      (n = 1/i).
///
/// For a kernel with K(i, i) = c i^lambda (every homogeneous kernel: c = K(1, 1), lambda its
/// homogeneity; beta kernel: c = K0 (1 + 1)^2 (1 + 1)^{1/beta} = 4 K0 2^{1/beta},
/// lambda = 2/3 - 1/beta) the closed form from i(0) = i0 is, separating variables,
///
///     i(t) = (i0^{1-lambda} + (1 - lambda) c t)^{1/(1-lambda)}      (lambda != 1),
///     i(t) = i0 exp(c t)                                            (lambda = 1),
///
/// which blows up at t* = i0^{1-lambda} / ((lambda - 1) c) for lambda > 1. Its local slope is
/// d ln i / d ln t = z t / (t + t0), z = 1 / (1 - lambda), t0 = i0^{1-lambda} / ((1 - lambda) c):
/// z = 3 beta / (beta + 3) for the beta kernel (6/5 at beta = 2, 3/2 at beta = 3).
///
/// The numerical solution integrates u = ln i against s = ln(1 + t) with Boost.Odeint
/// (Runge-Kutta-Fehlberg 7(8), adaptive): du/ds = (1 + t) K(e^u, e^u) e^{-u}. In these variables
/// the right-hand side tends to the constant z at late times, so the step grows with t and a solve
/// to t = 1e12 costs a few hundred steps. It exists to cross-check the closed form (and any kernel
/// without one).
#include <limits>
#include <vector>

#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/SmolResult.h"

namespace granagg::meanfield {

struct MonodisperseOptions {
  /// Output times (time unit 1 / (K0 n_1(0)), strictly increasing, > 0). Required.
  std::vector<double> times;
  /// Cluster size i0 at t = 0 (monomer masses, > 0).
  double initial_size = 1.0;
  /// Odeint relative and absolute tolerances on u = ln i (dimensionless, > 0).
  double rtol = 1e-12;
  double atol = 1e-12;
  /// Stop at the first output time with i >= s_end.
  double s_end = std::numeric_limits<double>::infinity();
};

/// Integrates di/dt = K(i, i) with Boost.Odeint. Samples report S = M2 = i, M0 = n = 1/i, M1 = 1,
/// mass_loss = 0, max_size = i; method "mono". Throws std::invalid_argument for bad options (naming
/// the option) and for output times at or beyond the blow-up time t* of kernels with lambda > 1.
SmolResult solveMonodisperse(const Kernel& kernel, const MonodisperseOptions& options);

/// Closed-form i(t) above, with c = K(1, 1) and lambda = kernel.homogeneity(); t >= 0 (time unit
/// 1 / K0), initial_size > 0. Throws std::invalid_argument for t < 0, t >= t* or a bad initial
/// size.
double monodisperseMeanSize(const Kernel& kernel, double t, double initial_size = 1.0);

/// Blow-up time t* = i0^{1-lambda} / ((lambda - 1) c) of the monodisperse equation for lambda > 1;
/// +infinity for lambda <= 1.
double monodisperseBlowUpTime(const Kernel& kernel, double initial_size = 1.0);

}  // namespace granagg::meanfield
