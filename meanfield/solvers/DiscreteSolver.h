#pragma once
/// \file DiscreteSolver.h
/// The discrete Smoluchowski equation for sizes 1..M (SmoluchowskiRhs.h), integrated with
/// SUNDIALS CVODE, with an active size range that grows with the mean size.
///
/// Growing range: the solver integrates sizes 1..M_active and enlarges M_active (to about
/// 2 * range_factor * S (40 S by default), an FFT-friendly length, at most max_size) whenever S >
/// M_active / range_factor. The scaling distribution decays exponentially in k/S, so with
/// M_active/S >= 20 the mass beyond the range is far below round-off; a truncated grid with M/S
/// below ~12 loses mass and its local slope collapses (docs/model.md section 12). Each resize
/// restarts CVODE from the current state (zero-padded), so the history of the multistep method is
/// lost: a few small steps.
///
/// Truncation is detected, never hidden: every output sample carries the relative mass loss
/// (M1(0) - M1(t)) / M1(0) and is marked invalid when it exceeds mass_loss_tolerance; by default
/// the solve stops at the first invalid sample (SmolResult::stopped_early says why).
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/SmolResult.h"

namespace granagg::meanfield {

struct DiscreteOptions {
  /// Output times (strictly increasing, > 0). Required.
  std::vector<double> times;
  /// Largest size class the active range may grow to (the truncation M of the equation).
  int max_size = 1 << 21;
  /// First active range; 0 picks max(128, 4 * length of the initial distribution).
  int initial_size = 0;
  /// Keep M_active >= range_factor * S while max_size allows (false: M_active = max_size
  /// throughout).
  bool grow = true;
  double range_factor = 20.0;
  /// CVODE relative tolerance and absolute tolerance (the latter relative to M1(0)).
  double rtol = 1e-8;
  double atol = 1e-14;
  /// "adams" (Adams-Moulton + fixed-point iteration), "bdf" (BDF + Newton with matrix-free GMRES)
  /// (preconditioned with the Jacobian diagonal, i.e. the loss rates) or "bdf-dense" (BDF + dense
  /// direct solver; M up to a few thousand).
  std::string integrator = "adams";
  /// Stop once S >= s_end (the last sample is the first output time past it).
  double s_end = std::numeric_limits<double>::infinity();
  double mass_loss_tolerance = 1e-8;
  /// Stop at the first sample whose mass loss exceeds the tolerance (otherwise continue, marking).
  bool stop_on_truncation = true;
  /// Store n_k for k <= snapshot_max_size at every output time (0: no snapshots).
  int snapshot_max_size = 0;
  /// Called after every output sample (progress reporting).
  std::function<void(const MomentSample&)> on_sample;
};

/// Solves from `initial` (n_k for k = 1..initial.size()), or from the monodisperse n_1 = 1 when
/// `initial` is null. Throws std::invalid_argument for bad options, std::runtime_error when CVODE
/// fails (with its flag name).
SmolResult solveDiscrete(const Kernel& kernel, const DiscreteOptions& options,
                         const std::vector<double>* initial = nullptr);

}  // namespace granagg::meanfield
