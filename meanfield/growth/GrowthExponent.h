#pragma once
/// \file GrowthExponent.h
/// Growth exponent z of a mean size S(t) ~ t^z (docs/model.md sections 11 and 12):
/// - the local slope z(t) = log[S(t)/S(t/p)] / log p,
/// - a power-law fit log S = log A + z log t over a window, with a confidence interval,
/// - an asymptotic estimate from the local slope with a stated convergence criterion.
/// Used for mean-field solutions here and (through cli/) for MD data.
#include <string>
#include <vector>

namespace granagg::meanfield {

/// z(t_i) = log[S(t_i)/S(t_i/p)] / log p for every t_i with t_i / p >= t_0. S(t_i/p) is
/// interpolated linearly in (log t, log S), which is exact for a pure power law.
/// Times must increase strictly and S must be positive; throws std::invalid_argument otherwise.
struct LocalSlope {
  std::vector<double> t;
  std::vector<double> z;
};
LocalSlope localSlope(const std::vector<double>& t, const std::vector<double>& S, double p = 2.0);

/// Least-squares fit of log S = log A + z log t on the points with t_min <= t <= t_max.
struct PowerLawFit {
  double z = 0.0;         ///< exponent
  double z_stderr = 0.0;  ///< standard error of z from the residuals
  double z_low = 0.0;     ///< lower end of the `confidence` interval (Student t, n - 2 dof)
  double z_high = 0.0;
  double prefactor = 0.0;  ///< A
  double confidence = 0.95;
  int points = 0;
  double t_min = 0.0, t_max = 0.0;
  double chi2 = 0.0;  ///< sum of squared residuals in log S
};
/// Throws std::invalid_argument if fewer than 3 points fall in the window.
PowerLawFit fitPowerLaw(const std::vector<double>& t, const std::vector<double>& S, double t_min,
                        double t_max, double confidence = 0.95);

/// Asymptotic growth exponent. The local slope of Smoluchowski solutions approaches its limit as
/// z(t) ~ z_inf t / (t + t0) ~ z_inf (1 - t0/t) (docs/model.md section 12), so z_inf is estimated
/// by a straight-line fit of z(t) against 1/t over the last decade of times. Convergence criterion:
/// the extrapolation |z_inf - z(t_last)| and the change of z(t) over that last decade are both
/// below `tolerance`.
struct AsymptoticExponent {
  double z = 0.0;           ///< extrapolated z_inf
  double z_last = 0.0;      ///< local slope at the last time
  double correction = 0.0;  ///< z - z_last
  double change = 0.0;      ///< z(t_last) - z(t_last / 10), from the local slope
  double tolerance = 0.0;
  bool converged = false;
  int points = 0;
  /// One sentence stating the criterion and whether it is met.
  std::string describe() const;
};
AsymptoticExponent asymptoticExponent(const std::vector<double>& t, const std::vector<double>& S,
                                      double p = 2.0, double tolerance = 1e-3);

}  // namespace granagg::meanfield
