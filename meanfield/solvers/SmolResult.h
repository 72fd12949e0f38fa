#pragma once
/// \file SmolResult.h
/// What every Smoluchowski solver returns: moments of the size distribution at output times.
///
/// Moments M_p = sum_k k^p n_k (sectional solvers: sum over pivots x_k^p N_k); the mean cluster
/// size is S = M2 / M1 (the mass-weighted mean, the quantity the paper compares with MD).
#include <cmath>
#include <string>
#include <vector>

namespace granagg::meanfield {

/// Moments at one output time.
struct MomentSample {
  double t = 0.0;
  double M0 = 0.0;  ///< number of clusters per unit volume
  double M1 = 0.0;  ///< mass per unit volume (conserved up to truncation)
  double M2 = 0.0;
  double S = 0.0;  ///< M2 / M1
  /// Relative mass lost so far, (M1(0) - M1(t)) / M1(0): truncation (discrete), escape past the
  /// last section (sectional), or integration error.
  double mass_loss = 0.0;
  /// False when mass_loss exceeds the solver's tolerance: S is then not a valid solution of the
  /// untruncated equation and must not be used (never reported as if valid).
  bool valid = true;
  /// Size range in use at this time (largest size class, or largest pivot).
  double max_size = 0.0;
};

/// The size distribution at one output time (sizes, and number densities per size / section).
struct Snapshot {
  double t = 0.0;
  std::vector<double> size;
  std::vector<double> n;
};

/// Cost and provenance of a solve.
struct SolveStats {
  long steps = 0;
  long rhs_evaluations = 0;
  long linear_iterations = 0;
  long nonlinear_failures = 0;  ///< convergence failures of the nonlinear solver
  long error_test_failures = 0;
  int resizes = 0;  ///< times the active size range was enlarged
  double wall_seconds = 0.0;
};

/// Why a solve stopped before the requested end. The solvers describe the cause in their own
/// terms; a caller turns it into advice that names its own options (SmolTables.cpp).
enum class StopCause {
  None,        ///< reached the last output time or s_end
  Truncation,  ///< mass left the size range, which had reached the largest size allowed
  SizeCeiling,  ///< mass left the size range at the largest size the solver represents at all
  MassGained,  ///< M1 grew beyond the tolerance: an integration error
  NotFinite,   ///< the mean size overflowed
};

struct SmolResult {
  std::string method;  ///< "discrete", "sectional" or "mono"
  std::vector<MomentSample> samples;
  std::vector<Snapshot> snapshots;
  SolveStats stats;
  /// Why the solve stopped before the requested end, empty if it reached it (names no option).
  std::string stopped_early;
  StopCause stop_cause = StopCause::None;
};

/// Log-spaced times from t_min to t_max, `count` points (count >= 2).
std::vector<double> logSpacedTimes(double t_min, double t_max, int count);

}  // namespace granagg::meanfield
