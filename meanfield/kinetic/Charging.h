#pragma once
/// \file Charging.h
/// Time exponent of the collisional charging rate (docs/model.md sections 8 and 9).
namespace granagg::meanfield {

/// Exponent of the mean-charge growth rate d<|q|>/dt ~ t^{x} in a cooling gas.
///
/// The charge moved per collision scales as |dq| ~ (m_eff g^2)^{kappa} ~ T^{kappa} (docs/model.md
/// section 7, with <Psi2> = 0), and the collision frequency as omega ~ T^{1/2} (Enskog), so
/// d<|q|>/dt ~ T^{1/2} T^{kappa}. With T ~ t^{-a}:
///
///     x = -a (1/2 + kappa);   a = 5/3 (viscoelastic cooling): x = -5/6 - 5 kappa / 3,
///
/// i.e. -13/6 at kappa = 0.8 (the t^{-13/6} of Singh & Mazza, PRE 2018, whose printed
/// t^{-5/6} t^{-5/(3 kappa)} is a typo) and -2.2167 at the default kappa = 0.83; a = 2 is
/// Haff's law. Dimensionless. Throws std::invalid_argument unless kappa is finite and >= 0 and
/// a is finite and > 0.
double chargingRateExponent(double kappa, double cooling_exponent = 5.0 / 3.0);

}  // namespace granagg::meanfield
