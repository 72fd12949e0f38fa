#pragma once
/// \file BetaFit.h
/// Fitting the kernel exponent beta of the Smoluchowski equation to a measured mean size S(t)
/// (docs/model.md sections 1, 11 and 12; Singh & Mazza 2018, Figs. 5 and 6):
///
/// 1. the growth exponent z of S ~ t^z over a window, chosen by the user or automatically where the
///    local slope of S(t) is flat within its noise at late times, with a 95 % interval (Student t
///    on the residuals, or a bootstrap over independent runs);
/// 2. beta from z: the beta for which the full Smoluchowski solution (sectional solver, beta kernel
///    K = (i^{1/3} + j^{1/3})^2 (1/i + 1/j)^{1/beta}) grows with the same exponent over the same
///    range of S as the data window. Not 3 beta/(beta + 3): that is only the S -> infinity limit,
///    and the local slope of the mean field approaches it slowly (1.19 at S ~ 250 for beta = 2,
///    docs/model.md section 12), so the comparison is made at equal S (cli/ repeats it at S / S_c,
/// with
///    S_c from the curve fit, for data whose S unit differs from the mean field's monomer count);
/// 3. a full-curve fit of log S(t_i) against log[S_c S_MF(t_i / tau_c; beta)] (GSL nonlinear least
///    squares, trust region / Levenberg-Marquardt), parameters (beta, ln S_c, ln tau_c), with 95 %
///    intervals from the covariance scaled by chi^2/dof, or from a bootstrap over runs (>= 3 runs).
///
/// Units: t in the data's own unit (MD: sqrt(m d^2 / T0)); S in the data's own unit (MD: grid sites
/// or particles). S_MF(t; beta) is the mean-field S = M2/M1 (monomer masses) from the monodisperse
/// start n_1(0) = 1 with K0 = 1, its time in 1/(K0 n_1(0)); tau_c converts that time into the
/// data's time and S_c the mean-field size into the data's size.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace granagg::meanfield {

/// S(t) of one run or of an ensemble of runs sampled at the same times.
struct GrowthData {
  std::vector<double> t;  ///< times, strictly increasing, > 0
  std::vector<double> S;  ///< mean size (mean over runs when runs are given), > 0
  /// Per-run series, runs[r][i] = S of run r at t[i]; empty when only one series is known.
  std::vector<std::vector<double>> runs;
};

/// A GrowthData from one series (no runs).
GrowthData growthFromSeries(std::vector<double> t, std::vector<double> S);
/// A GrowthData from several runs on the same times: S is their arithmetic mean (as the ensemble
/// S_grid_mean of `granagg analyze`). One run gives S = that run and no runs.
GrowthData growthFromRuns(std::vector<double> t, std::vector<std::vector<double>> runs);
/// Throws std::invalid_argument naming the problem: length mismatch, non-positive or non-finite t,
/// times not increasing strictly, non-positive or non-finite S (of the mean or of a run).
void validateGrowthData(const GrowthData& data);

/// Options of the automatic window.
struct WindowOptions {
  int min_points = 5;  ///< fewest samples of S in a window
  double noise_factor =
      3.0;  ///< flat = the halves' exponents agree within noise_factor standard errors ...
  double min_tolerance = 0.01;  ///< ... or within this absolute tolerance in z, whichever is larger
};

/// A fit window [t0, t1] over the samples of S.
struct SlopeWindow {
  double t0 = 0.0, t1 = 0.0;
  int points = 0;  ///< samples of S with t0 <= t <= t1
  bool automatic = false;
  double sigma_lnS = 0.0;  ///< noise of ln S per sample (automatic window)
  double tolerance = 0.0;  ///< min_tolerance used (automatic window)
  std::string rule;        ///< one sentence: how the window was chosen
};

/// The automatic window: the longest stretch of samples ending at the last one over which the local
/// slope of S(t) is flat within its noise. Rule: the stretch [t_a, t_last] grows one sample at a
/// time to earlier times (starting from the last min_points samples) while it is flat: the
/// power-law exponents fitted to its earlier and later halves (split at the middle of ln t_a..ln
/// t_last) -- the local slope at two times a factor sqrt(t_last / t_a) apart -- differ by at most
/// max(noise_factor x the standard error of the difference, min_tolerance). The standard errors
/// use the noise of ln S: with >= 2 runs, the median over times of the relative standard error of
/// the mean over runs; with one series, 1.4826 x the median absolute deviation of ln S_i from the
/// line through its neighbours (normalised to one sample). Growth stops at the first stretch that
/// is not flat. Samples correlated in time (one MD run) make the noise look smaller and the window
/// shorter, never longer. Throws std::invalid_argument when the data hold fewer than min_points.
SlopeWindow automaticWindow(const GrowthData& data, const WindowOptions& options = {});
/// The window [t0, t1] given by the user (ends widened by a relative 1e-4, so that a frame a
/// rounding step past t1 stays inside); throws std::invalid_argument when t0 >= t1 or fewer than
/// min_points samples fall inside.
SlopeWindow explicitWindow(const GrowthData& data, double t0, double t1, int min_points = 5);

/// Options of the z fit and of every bootstrap.
struct BootstrapOptions {
  double confidence = 0.95;
  int replicates_z = 2000;        ///< bootstrap replicates of the z fit
  int replicates_curve = 200;     ///< bootstrap replicates of the full-curve fit
  int min_runs = 3;               ///< bootstrap over runs only with at least this many runs
  std::uint64_t seed = 20180901;  ///< fixed seed (GSL mt19937): intervals are reproducible
};

/// Power-law fit ln S = ln A + z ln t over a window.
struct ZFit {
  double z = 0.0, z_low = 0.0, z_high = 0.0;  ///< exponent and its interval
  double prefactor = 0.0;                     ///< A
  double t0 = 0.0, t1 = 0.0;                  ///< first and last sample in the window
  int points = 0;
  double S0 = 0.0, S1 = 0.0;  ///< fitted A t^z at t0 and t1 (the S range of the window)
  double confidence = 0.95;
  /// "student-t" (least squares on the mean S, n - 2 degrees of freedom) or "bootstrap-runs":
  /// z -/+ t_{R-1} sqrt(R / (R - 1)) sd, sd the standard deviation of z fitted to the means of R
  /// runs resampled with replacement (replicates times). The factor corrects the bootstrap's known
  /// underestimate with few runs (a plain percentile interval over 5 runs covers ~1.75 standard
  /// errors where Student's t needs 2.78).
  std::string interval_method;
  int replicates = 0;
  /// Why there is no z (empty when there is one): S the same at every sample of the window.
  std::string note;
};
/// Fits z over the window. The interval half-width is never below 1e-12 (the round-off of a
/// least-squares slope in double precision, so that an exact power law is inside its interval).
/// S the same at every sample of the window (ln S equal to 1e-12) has no growth exponent: a fit
/// would give z = 0 with a zero-width interval, a certainty the data do not carry; z, z_low and
/// z_high are NaN then, S0 = S1 = that S, and `note` says so.
ZFit fitGrowthExponent(const GrowthData& data, const SlopeWindow& window,
                       const BootstrapOptions& options = {});

/// Options of the mean-field curves S_MF(t; beta).
struct MeanFieldCurveOptions {
  /// Sectional grid ratio. Measured against ratio 1.02 at beta = 2: S is 0.7 % high at ratio 1.1,
  /// nearly constant for S > 30 (absorbed into S_c), the local slope within 2e-3 at S ~ 10-30 and
  /// 5e-4 at S ~ 300 -- far below MD's uncertainty in z -- at a third of the cost of ratio 1.05.
  double ratio = 1.1;
  double rtol = 1e-7;  ///< CVODE relative tolerance
  /// Spacing of the beta nodes (curves between nodes: Catmull-Rom in beta; its error in ln S, ~1e-4
  /// at 0.1, is far below the noise of MD data).
  double beta_step = 0.1;
  double initial_s_end = 1e4;  ///< first solve of a node stops at this S; extended x10 when needed
  double s_cap = 1e8;   ///< largest S solved; beyond it ln S continues with the last local slope
  int per_decade = 40;  ///< output times per decade of t
};

/// S_MF(t; beta) of the full Smoluchowski equation (sectional solver, beta kernel, monodisperse
/// start n_1(0) = 1, K0 = 1) for any beta > 0 and t > 0. Curves are solved at beta nodes
/// k * beta_step (each once, lazily, cached) and interpolated: cubic spline in ln t of ln S on a
/// node, Catmull-Rom (C1 cubic) in beta between nodes. Below the first output time (1e-6)
/// S = 1 + (S(t_1) - 1) t / t_1 (the exact early linear growth); above s_cap, ln S continues
/// linearly in ln t with the local slope at the end of the solve (the slope has then converged to
/// 3 beta / (beta + 3) within 1e-4, docs/model.md section 12).
class MeanFieldCurves {
 public:
  explicit MeanFieldCurves(const MeanFieldCurveOptions& options = {});
  ~MeanFieldCurves();
  MeanFieldCurves(const MeanFieldCurves&) = delete;
  MeanFieldCurves& operator=(const MeanFieldCurves&) = delete;

  /// ln S_MF(t; beta) for t > 0, beta > 2 beta_step.
  double logS(double t, double beta);
  /// The mean-field time at which S_MF(t; beta) = S, for S > 1 (bisection in ln t).
  double timeAtS(double S, double beta);
  /// Least-squares exponent of S_MF(t; beta) over the times where S_MF goes from S0 to S1
  /// (64 samples log-spaced in t, as MD frames are), i.e. the mean field's z at the data's S range.
  double exponentBetween(double S0, double S1, double beta);
  /// Number of sectional solves so far.
  int solves() const;
  const MeanFieldCurveOptions& options() const { return m_options; }

 private:
  struct Node;
  Node& node(int k, double t_needed);
  MeanFieldCurveOptions m_options;
  std::map<int, std::unique_ptr<Node>> m_nodes;
  int m_solves = 0;
};

/// Result of inverting z -> beta.
struct BetaFromZ {
  double beta = 0.0, beta_low = 0.0,
         beta_high = 0.0;     ///< NaN when z lies outside z(beta) on the range
  double S0 = 0.0, S1 = 0.0;  ///< S range at which the mean-field exponent was computed
  double z_at_beta_min = 0.0, z_at_beta_max = 0.0;  ///< mean-field z at the range ends
  std::string note;  ///< empty, or why a value is NaN or clamped to the range
};
/// beta such that curves.exponentBetween(S0, S1, beta) = z (Brent's method on [beta_min, beta_max];
/// z(beta) increases with beta). Interval ends from z_low and z_high; an end whose z lies beyond
/// the range is clamped to beta_min or beta_max (the interval extends at least that far; noted), a
/// central value beyond it is NaN. S0 is raised to 1.0001 if lower (S_MF >= 1; noted).
BetaFromZ betaFromZ(MeanFieldCurves& curves, double z, double z_low, double z_high, double S0,
                    double S1, double beta_min, double beta_max);

/// beta from z through the asymptotic law z = 3 beta / (beta + 3), i.e. beta = 3 z / (3 - z): the
/// growth exponent the full Smoluchowski equation with the beta kernel converges to at large S
/// (homogeneity lambda = 2/3 - 1/beta, z = 1/(1 - lambda); docs/model.md sections 9 and 12; the
/// sectional solver reaches it within 1e-4 by S ~ 1e6). It needs no S scale, so it applies to data
/// whose S unit (grid sites) differs from the mean field's (monomers), provided z was measured in
/// the scaling regime (a flat local slope). Every z in (0, 3) maps to one beta in (0, inf), and
/// the interval maps monotonically: z_high >= 3 gives beta_high = +inf (no upper bound), z_low <= 0
/// gives beta_low = 0. A central z outside (0, 3) gives NaN with a note (z >= 3 grows faster than
/// any kernel of the family, z <= 0 does not grow). S0, S1 and z_at_beta_* are NaN.
BetaFromZ betaAsymptotic(double z, double z_low, double z_high);

/// Options of the full-curve fit.
struct CurveFitOptions {
  double beta_min = 1.5, beta_max = 6.0;  ///< search range of beta
  BootstrapOptions bootstrap;
};

/// Full-curve fit ln S(t_i) ~ ln S_c + ln S_MF(t_i / tau_c; beta) over every sample.
struct CurveFit {
  double beta = 0.0, beta_low = 0.0, beta_high = 0.0;
  double S_c = 0.0, S_c_low = 0.0, S_c_high = 0.0;
  double tau_c = 0.0, tau_c_low = 0.0, tau_c_high = 0.0;
  double chi2_dof = 0.0;  ///< sum of squared residuals in ln S / (n - 3): the residual variance
  int points = 0;
  int iterations = 0;
  /// "covariance" (Student t, n - 3 dof) or "bootstrap-runs" (as ZFit: estimate -/+ t_{R-1}
  /// sqrt(R / (R - 1)) x the bootstrap standard deviation; for S_c and tau_c in ln, for beta in
  /// the logistic parameter of fitCurve).
  std::string interval_method;
  int replicates = 0;
  std::string note;  ///< empty, or e.g. that beta ended at a bound of its range
  /// true when beta ended at a bound of [beta_min, beta_max]: then beta is not determined by the
  /// data (the best curve lies beyond the range, or the data are not of the mean field's shape).
  bool at_bound = false;
  /// Fitted model S_c S_MF(t / tau_c; beta) at the data times.
  std::vector<double> S_fitted;
};
/// Fits (beta, ln S_c, ln tau_c): start from the best point of a coarse scan (beta in steps of 1,
/// ln tau_c in steps of 0.2, ln S_c profiled out), then gsl_multifit_nlinear (trust region,
/// Levenberg-Marquardt, finite-difference Jacobian). beta is fitted through a logistic map of the
/// real line onto (beta_min, beta_max), and its interval is formed there and mapped back: it stays
/// inside the range. At a bound (at_bound) beta has no interval (NaN). Throws
/// std::invalid_argument for a bad beta range or fewer than 5 samples; std::runtime_error when
/// GSL fails.
CurveFit fitCurve(MeanFieldCurves& curves, const GrowthData& data,
                  const CurveFitOptions& options = {});

/// Allowed beta range of the fits: beta_min >= BETA_LOWEST, beta_max <= BETA_HIGHEST.
constexpr double BETA_LOWEST = 1.0;
constexpr double BETA_HIGHEST = 20.0;
/// Throws std::invalid_argument naming the option when [beta_min, beta_max] is not a valid range.
void validateBetaRange(double beta_min, double beta_max);

}  // namespace granagg::meanfield
