/// Charging-rate exponent (Charging.h).
#include "meanfield/kinetic/Charging.h"

#include <cmath>
#include <stdexcept>

#include "common/Csv.h"

namespace granagg::meanfield {

double chargingRateExponent(double kappa, double cooling_exponent) {
  if (!(kappa >= 0.0) || !std::isfinite(kappa))
    throw std::invalid_argument("charging exponent kappa must be non-negative and finite (got " +
                                common::formatReal(kappa) + ").");
  if (!(cooling_exponent > 0.0) || !std::isfinite(cooling_exponent))
    throw std::invalid_argument("cooling exponent a (T ~ t^-a) must be positive and finite (got " +
                                common::formatReal(cooling_exponent) + ").");
  return -cooling_exponent * (0.5 + kappa);
}

}  // namespace granagg::meanfield
