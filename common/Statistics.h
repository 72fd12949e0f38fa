#pragma once
/// \file Statistics.h
/// The statistics every module's fits share (one implementation, one interval rule):
/// ordinary least squares of a line, Student-t intervals, and the bootstrap interval over
/// independent runs. GSL underneath (gsl_fit_linear, gsl_cdf_tdist_Pinv, gsl_stats_sd).
///
/// **The interval rule.** One series: estimate -/+ t_{n-2, (1+c)/2} se, with se from the scatter
/// of the points about the line. R >= 2 independent runs: the estimate is the fit to the mean over
/// the runs, its interval estimate -/+ t_{R-1, (1+c)/2} sqrt(R / (R - 1)) sd_boot, where sd_boot is
/// the standard deviation of the estimate over bootstrap resamples of the runs (Efron & Tibshirani,
/// An Introduction to the Bootstrap, 1993, ch. 5 and 12). The factor and Student's quantile
/// correct the bootstrap's underestimate with few runs: a percentile interval over 5 runs covers
/// about 1.75 standard errors where 2.78 are needed.
#include <cstddef>
#include <vector>

namespace granagg::common::stats {

/// y = intercept + slope x by ordinary least squares.
struct LineFit {
  double slope = 0.0, intercept = 0.0;
  /// standard error of the slope from the scatter of the points about the line (n - 2 degrees of
  /// freedom); NaN for n < 3
  double slope_se = 0.0;
  double sumsq = 0.0;  ///< sum of squared residuals
  std::size_t n = 0;
};
/// Needs x and y of equal length n >= 2 (std::invalid_argument otherwise).
LineFit fitLine(const std::vector<double>& x, const std::vector<double>& y);

/// Half width of the two-sided `confidence` interval (0 < c < 1) of an estimate with standard
/// error `se` and `dof` degrees of freedom: t_{dof, (1+c)/2} se. NaN for dof < 1.
double studentHalfWidth(double se, double dof, double confidence);

struct Interval {
  double low = 0.0, high = 0.0;
};
/// The interval over R = `runs` independent runs from `replicates` (the estimate recomputed on
/// bootstrap resamples of the runs), centred on `estimate` (the rule above). Needs runs >= 2 and
/// 2 or more replicates (std::invalid_argument otherwise).
Interval bootstrapInterval(const std::vector<double>& replicates, double estimate, std::size_t runs,
                           double confidence);

/// Local slope z(t_k) = ln[y(t_k) / y(t_k / p)] / ln p of a growing quantity (docs/model.md
/// section 11), y(t_k / p) interpolated linearly in (ln t, ln y) between the bracketing samples
/// (exact for a power law). NaN where t_k / p lies before the first sample or a t or y involved is
/// not positive. t must increase; p > 1 (std::invalid_argument otherwise).
std::vector<double> localSlope(const std::vector<double>& t, const std::vector<double>& y,
                               double p);

/// Median (NaN for an empty sample).
double median(std::vector<double> v);

}  // namespace granagg::common::stats
