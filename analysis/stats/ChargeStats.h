#pragma once
/// \file ChargeStats.h
/// Charge observables (docs/model.md sections 8 and 10): mean |q|(t), the charging rate d<|q|>/dt
/// against the kinetic-theory law t^{-5/6 - 5 kappa/3}, and the charge-speed scatter (q~, v~).
#include <utility>
#include <vector>

namespace granagg::analysis {

struct ChargeMoments {
  double mean_abs = 0.0;  ///< (1/N) sum |q_i|, in q_ref
  double rms = 0.0;       ///< <q^2>^{1/2}
  double net = 0.0;       ///< sum q_i (conserved by the exchange model)
  double max_abs = 0.0;   ///< max |q_i|
};

/// Moments of N charges; zeros for an empty list.
ChargeMoments chargeMoments(const std::vector<double>& q);

/// q~_i = q_i / <q^2>^{1/2} (signed; all zero when every charge is zero).
std::vector<double> scaledCharges(const std::vector<double>& q);

/// Pearson correlation of x and y (NaN when either is constant).
double pearson(const std::vector<double>& x, const std::vector<double>& y);

/// Charging rate between consecutive frames: r_k = (m_{k+1} - m_k) / (t_{k+1} - t_k) placed at
/// the geometric mean time sqrt(t_k t_{k+1}) (log-spaced frames; arithmetic mean when t_k = 0).
std::pair<std::vector<double>, std::vector<double>> chargingRate(
    const std::vector<double>& t, const std::vector<double>& mean_abs_q);

/// Exponent of d<|q|>/dt ~ t^x expected from T_g ~ t^{-5/3} and |dq| ~ v^{2 kappa}:
/// x = -5/6 - 5 kappa / 3 (docs/model.md section 8, the corrected law; -13/6 at kappa = 0.8).
inline double expectedChargingRateExponent(double kappa) { return -5.0 / 6.0 - 5.0 * kappa / 3.0; }

}  // namespace granagg::analysis
