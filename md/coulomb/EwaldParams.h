#pragma once
/// \file EwaldParams.h
/// Parameter choice for the long-range Coulomb solvers (plain Ewald reference and PPPM) from
/// published RMS force error estimates, for a requested relative accuracy (docs/model.md
/// section 4, docs/coulomb.md).
///
/// Accuracy convention (as LAMMPS' kspace_style accuracy_relative): an accuracy `a` asks for an RMS
/// force error (RMS over particles of |F_computed - F_exact|) of at most a * K, where K q^2 / 1^2 =
/// K is the force between two unit charges at unit distance (one particle diameter). All error
/// estimates below are returned in these units, i.e. divided by K; they scale with sum_q2 =
/// sum_i q_i^2. The total error is split equally: real-space and reciprocal (or mesh) estimates are
/// each held at a / sqrt(2), so that their independent sum sqrt(e_r^2 + e_k^2) is at most a.
///
/// References:
/// - J. Kolafa and J. W. Perram, Mol. Simul. 9, 351 (1992): real-space and reciprocal-space RMS
///   force errors of Ewald sums (eqs. 18 and 32 there; also LAMMPS ewald.cpp `rms`).
/// - M. Deserno and C. Holm, J. Chem. Phys. 109, 7678 and 7694 (1998), "How to mesh up Ewald sums"
///   I and II: the P3M (PPPM) optimal influence function and its RMS force error; the closed
///   analytic approximation with the coefficient table `acons` is that of LAMMPS' pppm.cpp
///   (`estimate_ik_error`, after Deserno & Holm II and Hockney & Eastwood), for ik-differentiation.
#include <cstddef>

namespace granagg::md {

/// Plain Ewald parameters (EwaldReference).
struct EwaldParams {
  double alpha = 0.0;  ///< splitting parameter, in 1/d
  double r_cut = 0.0;  ///< real-space cutoff, in d (may exceed L/2: images are summed)
  int k_max = 0;       ///< reciprocal cutoff: k = 2 pi n / L for integer n, 0 < |n| <= k_max
  double estimated_error_real = 0.0;    ///< Kolafa-Perram real-space RMS force error / K
  double estimated_error_kspace = 0.0;  ///< Kolafa-Perram reciprocal RMS force error / K
  /// sqrt(e_r^2 + e_k^2): estimated relative RMS force error.
  double estimatedError() const;
};

/// Particle-particle particle-mesh (P3M / PPPM) parameters for a cubic box (Pppm).
/// How PPPM puts the charges on its mesh (md/coulomb/Pppm.h); both are deterministic.
enum class ChargeAssignment {
  Tiles,       ///< colour-ordered tiles, one thread each, plain adds (few, busy threads: CPU)
  FixedPoint,  ///< one thread per particle, 64-bit fixed-point atomic adds (many threads: GPU)
};

/// The backend's charge assignment: each is the faster one on its backend (docs/gpu.md).
#if defined(GRANAGG_CUDA)
constexpr ChargeAssignment DEFAULT_CHARGE_ASSIGNMENT = ChargeAssignment::FixedPoint;
#else
constexpr ChargeAssignment DEFAULT_CHARGE_ASSIGNMENT = ChargeAssignment::Tiles;
#endif

struct PppmParams {
  double alpha = 0.0;                 ///< splitting parameter, in 1/d
  double r_cut = 0.0;                 ///< real-space cutoff, in d (<= L/2, minimum image)
  int mesh = 0;                       ///< mesh points per box edge (product of 2, 3 and 5)
  int order = 5;                      ///< charge-assignment order P (2..7): P points per dimension
  double estimated_error_real = 0.0;  ///< Kolafa-Perram real-space RMS force error / K
  double estimated_error_kspace = 0.0;  ///< Deserno-Holm / LAMMPS ik mesh RMS force error / K
  ChargeAssignment assignment = DEFAULT_CHARGE_ASSIGNMENT;  ///< how charges reach the mesh
  /// sqrt(e_r^2 + e_k^2): estimated relative RMS force error.
  double estimatedError() const;
};

/// Kolafa-Perram real-space RMS force error / K:
///     2 sum_q2 exp(-alpha^2 r_cut^2) / sqrt(n r_cut L^3).
double ewaldRealSpaceError(double alpha, double r_cut, std::size_t n, double L, double sum_q2);

/// Kolafa-Perram reciprocal-space RMS force error / K for the spherical cutoff |n| <= k_max:
///     2 sum_q2 alpha / L sqrt(1 / (pi k_max n)) exp(-(pi k_max / (alpha L))^2).
double ewaldKspaceError(double alpha, int k_max, std::size_t n, double L, double sum_q2);

/// PPPM (ik-differentiation, optimal influence function) mesh RMS force error / K, with mesh
/// spacing h = L / mesh (Deserno & Holm 1998 II; LAMMPS pppm.cpp estimate_ik_error):
///     sum_q2 (h alpha)^P sqrt(alpha L sqrt(2 pi) sum_{m<P} a_{P,m} (h alpha)^{2m} / n) / L^2.
double pppmKspaceError(double alpha, int mesh, int order, std::size_t n, double L, double sum_q2);

/// The alpha for which the Kolafa-Perram real-space error equals `error_real` at cutoff r_cut:
/// alpha = sqrt(-ln(error_real sqrt(n r_cut L^3) / (2 sum_q2))) / r_cut. Where the argument of the
/// logarithm is >= 1 (few or small charges: any alpha meets the target) it returns LAMMPS'
/// fallback (1.35 - 0.15 ln(error_real)) / r_cut.
double realSpaceAlpha(double error_real, double r_cut, std::size_t n, double L, double sum_q2);

/// Smallest integer >= n_min whose only prime factors are 2, 3 and 5 (fast for FFTW and cuFFT).
int fftFriendlySize(int n_min);

/// Plain Ewald parameters for relative accuracy `accuracy` (> 0) for n charges with sum_i q_i^2 =
/// sum_q2 in a cube of edge L: r_cut (default 0 means L/2, the largest minimum-image cutoff; larger
/// values are allowed and sum explicit images), alpha from the real-space estimate at
/// accuracy / sqrt(2), then the smallest k_max whose reciprocal estimate is <= accuracy / sqrt(2).
/// Throws std::invalid_argument for accuracy <= 0, n == 0, L <= 0, sum_q2 <= 0 or r_cut < 0.
EwaldParams chooseEwaldParams(double accuracy, std::size_t n, double L, double sum_q2,
                              double r_cut = 0.0);

/// PPPM parameters for relative accuracy `accuracy` at a given real-space cutoff r_cut (0 < r_cut
/// <= L/2) and assignment order (2..7, default 5): alpha from the real-space estimate at
/// accuracy / sqrt(2), then the smallest FFT-friendly mesh whose estimate is <= accuracy / sqrt(2).
/// Throws std::invalid_argument for unphysical inputs (naming the parameter), or when the mesh
/// would exceed max_mesh points per edge.
PppmParams choosePppmParams(double accuracy, std::size_t n, double L, double sum_q2, double r_cut,
                            int order = 5, int max_mesh = 1024);

/// Cost model for one PPPM force evaluation, in nanoseconds per elementary operation. The
/// defaults were measured on one core of the 2-core development VM (Release, N = 1e5, mesh 108,
/// P = 5: assignment 5.7 ns and interpolation 3.8 ns per stencil point, 0.55 ns per mesh point and
/// log2 of one FFT, 400 ns per particle for the cell sort); the real-space pair cost is an estimate
/// to be replaced by the engine's measured one (docs/coulomb.md).
struct PppmCostModel {
  double pair = 15.0;       ///< one real-space pair in a full neighbour list (erfc, exp, division)
  double fft_point = 0.6;   ///< one mesh point times log2(mesh^3) of one 3-D FFT
  double stencil = 4.7;     ///< one particle-stencil point (assignment or interpolation)
  double particle = 400.0;  ///< per particle: sort by mesh cell, weights
  double mesh_point = 5.0;  ///< per mesh point: cell starts, influence-function products, energy
};

/// Modelled time (ns) of one PPPM evaluation with params p: real space with a full neighbour list
/// of n (4 pi / 3) r_cut^3 n / L^3 pairs, 4 FFTs (one forward, three inverse for ik), assignment
/// and interpolation over P^3 points per particle, the sort, and the per-mesh-point passes.
double pppmCost(const PppmParams& p, std::size_t n, double L, const PppmCostModel& model = {});

/// PPPM parameters minimising pppmCost over r_cut in [r_cut_min, r_cut_max] (steps of 0.25 d;
/// r_cut_max = 0 means L/2) and order 2..7, each meeting `accuracy` (choosePppmParams).
PppmParams optimizePppmParams(double accuracy, std::size_t n, double L, double sum_q2,
                              double r_cut_min, double r_cut_max = 0.0,
                              const PppmCostModel& model = {});

}  // namespace granagg::md
