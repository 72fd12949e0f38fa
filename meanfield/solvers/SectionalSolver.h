#pragma once
/// \file SectionalSolver.h
/// Sectional Smoluchowski solver: the fixed-pivot method of Kumar & Ramkrishna, Chem. Eng. Sci. 51,
/// 1311 (1996), eq. (27), for mean sizes far beyond what a discrete grid holds (docs/model.md
/// section 12).
///
/// Grid: pivots x_i are the integers 1, 2, ..., m, with m the first integer for which the geometric
/// step exceeds one size unit, m (r - 1) >= 1; then x_{i+1} = r x_i up to the first pivot >=
/// max_size. Below m the method reduces to the discrete equation exactly (every sum of two integer
/// pivots
/// <= m is a pivot), so small sizes carry no discretisation error.
///
/// Equation (Kumar & Ramkrishna 1996, eq. 27), N_i = number of clusters (per unit volume) assigned
/// to pivot x_i:
///
///     dN_i/dt = sum_{j <= k, x_{i-1} <= x_j + x_k <= x_{i+1}} (1 - delta_jk / 2) eta_i(x_j + x_k)
///     K(x_j, x_k) N_j N_k
///               - N_i sum_k K(x_i, x_k) N_k,
///     eta_i(v) = (x_{i+1} - v) / (x_{i+1} - x_i)  for x_i <= v <= x_{i+1},
///                (v - x_{i-1}) / (x_i - x_{i-1})  for x_{i-1} <= v <= x_i:
///
/// an aggregate of size v between two pivots is split between them so that number and mass are
/// both conserved exactly. The kernel is evaluated at the real pivot sizes. Each pair (j, k) and
/// its target section and weight are tabulated once, so the right-hand side is an O(I^2) loop over
/// the pairs of sections that hold non-negligible mass. The fixed-pivot error in S scales as (r -
/// 1)^2 (docs/model.md section 12: 3e-4 at r = 1.02).
///
/// Growing grid: the solve starts on the grid up to min(initial_size, max_size) and appends
/// geometric pivots as the distribution spreads, so S is bounded by the section budget
/// (4096 sections: a last pivot of 5e87 at r = 1.05; at most ~1e100 at any r), not by a size
/// fixed in advance. Appending keeps every pivot and N_i, so no state is remapped; CVODE restarts
/// from the current state (a few small steps). The grid grows (a) at an output time when the
/// largest section holding mass, x_hi, has come within a factor GROW_TRIGGER = 100 of the last
/// pivot, to GROW_TARGET = 1e6 x_hi;
/// (b) when mass escaped during the last output interval all the same (sparse output times,
/// fast growth): the interval is integrated again from the previous output on the larger grid.
/// A solve that never comes near the initial grid's end takes exactly the steps of a fixed grid.
///
/// Truncation: aggregates larger than the last pivot leave the grid. Their mass is integrated as an
/// extra unknown, so that M1 + escaped mass is a linear invariant; every sample reports the
/// relative mass lost, (M1(0) - M1(t)) / M1(0), and is marked invalid when it exceeds
/// mass_loss_tolerance. With the growing grid this happens only at max_size or at the section
/// budget (SmolResult::stop_cause = Truncation), or at SECTIONAL_MAX_PIVOT (SizeCeiling).
///
/// Gelling kernels (multiplicative, K0 i j): the solution only exists before the gel time
/// t_gel = 1 / (K0 M2(0)) (Ziff 1980; 1/K0 for the monodisperse start); later output times are
/// rejected.
#include <limits>
#include <string>
#include <vector>

#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/SmolResult.h"

namespace granagg::meanfield {

struct SectionalOptions {
  /// Grid ratio r = x_{i+1} / x_i of the geometric part (> 1). The error in S scales as (r - 1)^2.
  double ratio = 1.05;
  /// Largest size the grid may grow to (monomer masses, >= 2; the last pivot is the first >= it).
  /// Infinity: as far as the section budget and SECTIONAL_MAX_PIVOT allow.
  double max_size = std::numeric_limits<double>::infinity();
  /// Last pivot of the first grid (>= 2); the grid starts at min(initial_size, max_size).
  double initial_size = 1e12;
  /// Append pivots as the distribution spreads (see the file comment); false: a fixed grid up to
  /// min(initial_size, max_size).
  bool grow = true;
  /// CVODE relative tolerance (dimensionless).
  double rtol = 1e-8;
  /// CVODE absolute tolerance on the mass x_i N_i of each section, relative to M1(0) (the tolerance
  /// on N_i is atol M1(0) / x_i, so that large and small sections are weighted by their mass).
  double atol = 1e-14;
  /// Output times (time unit 1 / (K0 n_1(0)), strictly increasing, > 0). Required.
  std::vector<double> times;
  /// Stop at the first output time at which S >= s_end.
  double s_end = std::numeric_limits<double>::infinity();
  /// Relative mass loss beyond which a sample is marked invalid.
  double mass_loss_tolerance = 1e-8;
  /// Stop at the first invalid sample (SmolResult::stopped_early says why); otherwise go on
  /// marking.
  bool stop_on_truncation = true;
  /// Store the pivots and N_i at every output time.
  bool snapshots = false;
  /// CVODE configuration (CvodeSolver.h): "bdf" (BDF, Newton with matrix-free GMRES; default),
  /// "adams" (Adams-Moulton with fixed-point iteration) or "bdf-dense". Both "bdf" and "adams"
  /// keep M1 + escaped mass to round-off (measured ~1e-15). Measured for the beta kernel from
  /// n_1 = 1 to S = 1e8 at r = 1.05, rtol 1e-8 (one core): bdf ~2200 steps / 0.5 s at every beta;
  /// adams is limited by stability, as the stiffness grows like S^{1/beta}: 10900 steps / 2.8 s at
  /// beta = 2, 2200 / 0.5 s at beta = 4 (it is faster than bdf only below S ~ 1e5); bdf-dense 14 s.
  std::string integrator = "bdf";
  /// Sections whose mass |N_i| x_i is below section_cutoff * M1(0) are left out of the right-hand
  /// side (their pairs contribute nothing; their own N_i is frozen). This skips the empty sections
  /// ahead of the distribution and the exponentially depleted ones behind it, so the cost follows
  /// the width of the distribution rather than the grid, and removes the stiffness of the depleted
  /// small sections. Far below atol, so it changes nothing measurable: a frozen section holds less
  /// than section_cutoff M1(0) / x_i clusters, ~1e-19 M1(0) in M0 over the whole grid by default
  /// (1e-11 of M0 at S = 1e8). 0 keeps every nonzero section.
  double section_cutoff = 1e-20;
};

/// The section budget: the pair table holds I (I + 1) / 2 entries (8 million at 4096).
constexpr int SECTIONAL_MAX_SECTIONS = 4096;
/// No pivot lies far beyond this size, so that x^2 N and K(x, x) N^2 stay finite in double.
constexpr double SECTIONAL_MAX_PIVOT = 1e100;

/// The pivot grid described above (exposed for tests and plots).
struct SectionalGrid {
  std::vector<double> pivots;  ///< x_i, monomer masses, strictly increasing, x_0 = 1
  int integer_pivots = 0;      ///< number of leading integer pivots 1..m
};
/// Builds the grid for ratio > 1 and max_size in [2, SECTIONAL_MAX_PIVOT]; throws
/// std::invalid_argument otherwise, or when it would exceed SECTIONAL_MAX_SECTIONS sections.
SectionalGrid makeSectionalGrid(double ratio, double max_size);

/// Solves the fixed-pivot equations from `initial` (n_k for sizes k = 1..initial.size(), mapped
/// onto the pivots with the number- and mass-conserving split above), or from the monodisperse
/// n_1 = 1 when `initial` is null. Moments are M_p = sum_i x_i^p N_i; Snapshot::n holds N_i (number
/// per section, not per unit size); MomentSample::max_size is the largest pivot with non-negligible
/// content. Throws std::invalid_argument for bad options (naming the option), std::runtime_error
/// when CVODE fails.
SmolResult solveSectional(const Kernel& kernel, const SectionalOptions& options,
                          const std::vector<double>* initial = nullptr);

}  // namespace granagg::meanfield
