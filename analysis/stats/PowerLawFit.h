#pragma once
/// \file PowerLawFit.h
/// Growth exponents: y = A t^z fitted by least squares of ln y on ln t over a window, with a
/// Student-t confidence interval (one run) or a bootstrap over independent runs (ensembles), and
/// the local slope z(t) = ln[S(t) / S(t/p)] / ln p (docs/model.md section 11).
#include <cstdint>
#include <vector>

namespace granagg::analysis {

/// Relative slack of the fit windows' ends: a sample within t_min (1 - 1e-4) .. t_max (1 + 1e-4)
/// is inside (frames sit on whole time steps, a little past their nominal times).
constexpr double WINDOW_SLACK = 1e-4;

struct PowerLawFitResult {
  bool valid = false;
  double exponent = 0.0;   ///< z
  double amplitude = 0.0;  ///< A
  double stderr_z = 0.0;   ///< standard error of z from the residuals (n - 2 degrees of freedom)
  double low = 0.0;        ///< lower end of the confidence interval of z
  double high = 0.0;       ///< upper end
  std::size_t points = 0;  ///< points used (t in [t_min, t_max], t > 0, y > 0, finite)
  /// y is the same at every point used: it does not grow, and a fit would give z = 0 with a
  /// zero-width interval, a certainty the data do not carry. No exponent then (valid false).
  bool constant = false;
};

/// Ordinary least squares of ln y on ln t over t_min <= t <= t_max; the interval is
/// z +- t_{n-2, (1+confidence)/2} * stderr (GSL's Student-t quantile). Needs 3 points whose y
/// differ (a constant y: `constant`, no exponent).
/// Throws std::invalid_argument when t and y differ in length or confidence is not in (0, 1).
PowerLawFitResult fitPowerLaw(const std::vector<double>& t, const std::vector<double>& y,
                              double t_min, double t_max, double confidence = 0.95);

/// Bootstrap over runs: `runs[r][k]` is run r's y at time t[k]. Each replicate draws the runs with
/// replacement (std::mt19937_64 seeded with `seed`, so results are reproducible), averages y over
/// them and fits the power law. `exponent` is the fit to the mean over all runs; the interval is
/// common/Statistics.h's bootstrap rule (exponent -/+ t_{R-1} sqrt(R/(R-1)) sd of the replicate
/// exponents, the rule fit-beta uses); stderr_z is that sd. Needs 2 runs.
PowerLawFitResult bootstrapPowerLaw(const std::vector<double>& t,
                                    const std::vector<std::vector<double>>& runs, double t_min,
                                    double t_max, int replicates = 2000, std::uint64_t seed = 20091,
                                    double confidence = 0.95);

/// Local slope z(t_k) = ln[y(t_k) / y(t_k/p)] / ln p, y(t_k/p) interpolated linearly in
/// (ln t, ln y) between the bracketing samples (exact for a power law). NaN where t_k/p lies
/// before the first positive time or a y involved is not positive. t must increase. p > 1.
std::vector<double> localSlope(const std::vector<double>& t, const std::vector<double>& y,
                               double p);

}  // namespace granagg::analysis
