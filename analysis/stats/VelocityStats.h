#pragma once
/// \file VelocityStats.h
/// Granular temperature, Sonine coefficient a2 and the speed distribution f(v~) beside the
/// Maxwellian (docs/model.md section 10). All from peculiar velocities c = v - <v> (mass m = 1).
#include <cstddef>
#include <vector>

namespace granagg::analysis {

struct VelocityMoments {
  std::size_t n = 0;
  double T_g = 0.0;     ///< (1/3) <|c|^2>, in T0
  double a2 = 0.0;      ///< Sonine coefficient (3/5) <c^4>/<c^2>^2 - 1 (0 for a Maxwellian, 3-D)
  double a2_err = 0.0;  ///< standard error of a2 by the delta method from the sample
                        ///  covariance of (c^2, c^4) (Cov of the means = Cov / n)
};

/// Moments of the 3N velocities v (x0 y0 z0 x1 ...). Throws std::invalid_argument for n < 2.
VelocityMoments velocityMoments(const std::vector<double>& v);

/// Maxwellian density of v~ = |c| / <|c|^2>^{1/2} in 3-D: sqrt(54/pi) v~^2 exp(-3 v~^2 / 2).
double maxwellianScaledSpeedDensity(double v_tilde);
/// Its cumulative distribution: erf(a v~) - (2/sqrt(pi)) a v~ exp(-a^2 v~^2), a = sqrt(3/2).
double maxwellianScaledSpeedCdf(double v_tilde);

/// Histogram of v~ on [0, v_max) with `bins` equal bins; speeds above v_max count in `overflow`.
class SpeedHistogram {
 public:
  /// Throws std::invalid_argument for v_max <= 0 or bins < 1.
  SpeedHistogram(double v_max = 4.0, int bins = 80);
  /// Adds the scaled speeds of one frame's velocities (3N values); returns the scaled speeds.
  std::vector<double> add(const std::vector<double>& v);
  /// Probability density per bin: count / (total * width), total including overflow.
  std::vector<double> density() const;
  const std::vector<double>& counts() const { return m_counts; }
  double binLow(int k) const { return k * m_width; }
  double binWidth() const { return m_width; }
  int bins() const { return static_cast<int>(m_counts.size()); }
  double total() const { return m_total; }
  void reset();

 private:
  double m_vmax, m_width, m_total = 0.0;
  std::vector<double> m_counts;
};

/// Scaled speeds v~_i = |c_i| / <|c|^2>^{1/2} of 3N velocities.
std::vector<double> scaledSpeeds(const std::vector<double>& v);

}  // namespace granagg::analysis
