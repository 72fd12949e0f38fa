#pragma once
/// \file Cooling.h
/// Homogeneous cooling of a granular gas (docs/model.md section 8; docs/kinetic.md): Enskog
/// collision frequency, Haff's law for constant restitution, cooling with a velocity-dependent
/// restitution coefficient e(g) and the small-damping viscoelastic law T ~ t^{-5/3}.
///
/// Units: nondimensional, particle diameter d = 1, mass m = 1, initial granular temperature
/// T0 = 1 (T = m <(v - <v>)^2> / 3); times in sqrt(m d^2 / T0), frequencies in its inverse.
///
/// Assumptions (stated once): spatially homogeneous gas, Maxwellian velocities at every time
/// (the Sonine correction a2 is neglected; Brilliantov & Poeschel, Kinetic Theory of Granular
/// Gases (OUP 2004), treat it), Enskog's pair correlation at contact from Carnahan & Starling.
/// A real gas at phi = 0.076 leaves the homogeneous state (clusters) long before the late-time
/// asymptotics below; they are mean-field references only.
#include <functional>
#include <vector>

#include "meanfield/kinetic/Restitution.h"

namespace granagg::meanfield {

/// Throws std::invalid_argument naming the value unless 0 < phi < 0.74 (close packing of equal
/// spheres is pi / sqrt(18) = 0.7405).
void validateFillingFraction(double phi);

/// Number density n = 6 phi / pi of unit-diameter spheres at filling fraction phi (units d^-3).
double numberDensity(double phi);

/// Carnahan-Starling pair correlation at contact g2 = (1 - phi/2) / (1 - phi)^3 (dimensionless;
/// Carnahan & Starling, J. Chem. Phys. 51, 635 (1969); docs/model.md section 8).
double carnahanStarlingG2(double phi);

/// Enskog collision frequency per particle omega = 4 sqrt(pi) n g2 d^2 sqrt(T/m) (units
/// sqrt(T0 / (m d^2)); Brilliantov & Poeschel (2004), tau_c^{-1}; docs/model.md section 8).
/// At phi = 0.076, T = 1: omega = 1.25490. Requires T >= 0 (std::invalid_argument).
double enskogCollisionFrequency(double phi, double T);

/// 1 / tau0 = (1 - eps^2) omega(T0) / 6 of Haff's law for constant restitution eps in [0, 1]
/// (units of inverse time; Haff, J. Fluid Mech. 134, 401 (1983); Brilliantov & Poeschel (2004),
/// docs/model.md section 8).
double haffInverseTau0(double eps, double phi, double T0 = 1.0);

/// Haff's law T(t) = T0 / (1 + t / tau0)^2 for constant restitution eps (temperature units T0,
/// t >= 0 in sqrt(m d^2/T0)). Solution of dT/dt = -(1 - eps^2) omega(T) T / 3.
double haffTemperature(double t, double eps, double phi, double T0 = 1.0);

/// Impact-speed dependent restitution coefficient e(g) for normal impact speeds g >= 0 (units
/// sqrt(T0/m)); must return values in [0, 1].
using RestitutionFunction = std::function<double(double)>;

/// Mean relative energy loss factor L(T) = <g^2 (1 - e(g)^2)>_P / <g^2>_P (dimensionless) over
/// the collision-weighted distribution of normal impact speeds of a Maxwellian gas at
/// temperature T, P(g) = (g / (2T)) exp(-g^2 / (4T)) (<g^2> = 4T). Constant e gives 1 - e^2.
/// GSL adaptive quadrature (QAGS) to relative accuracy `rel_tol`; GSL's global error handler is
/// switched off during the call (restored afterwards), so do not run it concurrently with other
/// code that changes that handler. Failures throw std::runtime_error.
double energyLossFactor(const RestitutionFunction& e, double T, double rel_tol = 1e-12);

/// Cooling rate dT/dt = -(omega(T) / 12) <g^2 (1 - e(g)^2)>_P = -omega(T) T L(T) / 3 (units
/// T0 per time). Derivation in Cooling.cpp.
double coolingRate(const RestitutionFunction& e, double phi, double T);

/// Options of the cooling ODE.
struct CoolingOptions {
  double phi = 0.076;        ///< filling fraction, 0 < phi < 0.74
  double T0 = 1.0;           ///< temperature at t = 0 (units T0; > 0)
  double rtol = 1e-10;       ///< relative tolerance of the Odeint Dormand-Prince stepper on ln T
  double atol = 1e-12;       ///< absolute tolerance on ln T
  double quad_rtol = 1e-12;  ///< relative tolerance of the velocity average L(T)
};

/// One output sample of a cooling solution.
struct CoolingSample {
  double t = 0.0;      ///< time, units sqrt(m d^2 / T0)
  double T = 0.0;      ///< granular temperature, units T0
  double rate = 0.0;   ///< dT/dt, units T0 per time
  double slope = 0.0;  ///< local exponent d ln T / d ln t = t (dT/dt) / T (0 at t = 0)
  double loss = 0.0;   ///< energy loss factor L(T) (dimensionless)
};

/// Integrates dT/dt = -(omega(T)/12) <g^2 (1 - e(g)^2)>_P (Boost.Odeint, dense-output
/// Dormand-Prince in the variables ln T against ln(1 + t), in which both Haff's t^{-2} and the
/// viscoelastic t^{-5/3} tails are straight lines) and returns T at the requested times (>= 0,
/// non-decreasing, finite; std::invalid_argument otherwise).
std::vector<CoolingSample> solveCooling(const RestitutionFunction& e,
                                        const std::vector<double>& times,
                                        const CoolingOptions& options = {});

/// Viscoelastic cooling: solveCooling with e(g) from a RestitutionTable of the contact params.
std::vector<CoolingSample> solveViscoelasticCooling(const ContactParams& params,
                                                    const std::vector<double>& times,
                                                    const CoolingOptions& options = {});

/// Characteristic time tau0' of the small-damping viscoelastic cooling law
///     T(t) = T0 (1 + t / tau0')^{-5/3},  1 / tau0' = (16/5) q0 delta omega(T0),
///     q0 = 2^{1/5} Gamma(21/10) / 8 = 0.1503,   delta = C1 b1 T0^{1/10},
/// with b1 = D m_eff^{-2/5} E^{-3/5} the coefficient of b = b1 g^{1/5} (Restitution.h); in
/// Brilliantov & Poeschel's notation b1 = A kappa^{2/5}. Form of Schwager & Poeschel, PRE 57, 650
/// (1998) and Brilliantov & Poeschel (2004) (first order in delta, Maxwellian); the
/// constant is derived in Cooling.cpp from the first-order restitution 1 - e^2 = 2 C1 b. Units
/// sqrt(m d^2/T0).
double viscoelasticCoolingTau0(const ContactParams& params, double phi, double T0 = 1.0);

/// Small-damping closed form T(t) = T0 (1 + t / tau0')^{-5/3} (units T0; t >= 0). Valid while
/// delta << 1; its large-t form T0 (t / tau0')^{-5/3} is the exact asymptote of the
/// viscoelastic cooling ODE for any damping (e -> 1 as T -> 0), approached with relative
/// corrections of order T^{1/10} ~ t^{-1/6}.
double viscoelasticCoolingTemperature(double t, const ContactParams& params, double phi,
                                      double T0 = 1.0);

}  // namespace granagg::meanfield
