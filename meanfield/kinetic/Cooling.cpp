/// Homogeneous cooling: Enskog frequency, Haff's law, velocity-dependent cooling (Cooling.h).
#include "meanfield/kinetic/Cooling.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>
#include <boost/numeric/odeint.hpp>

#include "common/Csv.h"

namespace granagg::meanfield {

using common::formatReal;

namespace {

constexpr double PI = 3.141592653589793238462643383279502884;

void checkTemperature(double T, const char* what) {
  if (!(T >= 0.0) || !std::isfinite(T))
    throw std::invalid_argument(std::string(what) +
                                " requires a non-negative, finite temperature T (got " +
                                formatReal(T) + ").");
}

void checkRestitution(double eps) {
  if (!(eps >= 0.0 && eps <= 1.0))
    throw std::invalid_argument(
        "Haff's law requires a restitution coefficient eps in [0, 1] (got " + formatReal(eps) +
        ").");
}

void checkTime(double t) {
  if (!(t >= 0.0) || !std::isfinite(t))
    throw std::invalid_argument("cooling time t must be non-negative and finite (got " +
                                formatReal(t) + ").");
}

/// Disables GSL's abort-on-error handler while a GSL call runs, so that failures come back as
/// status codes (thrown as std::runtime_error below), and restores the previous handler.
class GslHandlerOff {
 public:
  GslHandlerOff() : m_old(gsl_set_error_handler_off()) {}
  ~GslHandlerOff() { gsl_set_error_handler(m_old); }
  GslHandlerOff(const GslHandlerOff&) = delete;
  GslHandlerOff& operator=(const GslHandlerOff&) = delete;

 private:
  gsl_error_handler_t* m_old;
};

}  // namespace

void validateFillingFraction(double phi) {
  if (!(phi > 0.0 && phi < 0.74))
    throw std::invalid_argument("filling fraction phi must lie in (0, 0.74) (got " +
                                formatReal(phi) + ").");
}

double numberDensity(double phi) {
  validateFillingFraction(phi);
  return 6.0 * phi / PI;  // phi = n pi d^3 / 6 with d = 1
}

double carnahanStarlingG2(double phi) {
  validateFillingFraction(phi);
  return (1.0 - 0.5 * phi) / std::pow(1.0 - phi, 3);
}

double enskogCollisionFrequency(double phi, double T) {
  checkTemperature(T, "the Enskog collision frequency");
  return 4.0 * std::sqrt(PI) * numberDensity(phi) * carnahanStarlingG2(phi) *
         std::sqrt(T);  // m = d = 1
}

// Haff's law (Haff 1983; docs/model.md section 8). With a constant restitution L = 1 - eps^2, so
// the cooling equation below reads dT/dt = -(1 - eps^2) omega0 sqrt(T/T0) T / 3. Substituting
// T = T0 u^{-2}: -2 T0 u^{-3} u' = -(1 - eps^2) omega0 T0 u^{-3} / 3, i.e. u' = (1 - eps^2) omega0
// / 6 = 1/tau0 and T = T0 / (1 + t/tau0)^2.
double haffInverseTau0(double eps, double phi, double T0) {
  checkRestitution(eps);
  if (!(T0 > 0.0) || !std::isfinite(T0))
    throw std::invalid_argument("Haff's law requires a positive initial temperature T0 (got " +
                                formatReal(T0) + ").");
  return (1.0 - eps * eps) * enskogCollisionFrequency(phi, T0) / 6.0;
}

double haffTemperature(double t, double eps, double phi, double T0) {
  checkTime(t);
  const double x = 1.0 + t * haffInverseTau0(eps, phi, T0);
  return T0 / (x * x);
}

// Cooling equation with an impact-speed dependent restitution coefficient (derivation).
// A collision with normal relative speed g conserves momentum and takes the kinetic energy
// Delta(g) = (1/2) m_eff g^2 (1 - e(g)^2) out of the relative motion (m_eff = m/2). Per unit
// volume there are n omega / 2 collisions per unit time (omega per particle, two particles per
// collision), and the kinetic energy density is (3/2) n T, so
//     d/dt (3/2 n T) = -(n omega / 2) <Delta>_coll   =>   dT/dt = -(omega / 3) <Delta>_coll
//                                                        = -(omega / 12) <g^2 (1 - e(g)^2)>_coll,
// using m_eff = 1/2. In a Maxwellian gas the relative velocity of a pair is Gaussian with variance
// 2T/m per component; collisions sample its component g along the line of centres with the flux
// weight g, so P(g) = (g / (2T)) exp(-g^2 / (4T)) for g > 0 (normalised, <g^2> = 4T). With
// L(T) = <g^2 (1 - e^2)> / (4T):  dT/dt = -omega(T) T L(T) / 3.
// Check, constant e = eps: L = 1 - eps^2 and omega(T) = omega0 sqrt(T/T0) give
// dT/dt = -(1 - eps^2) omega0 T^{3/2} / (3 sqrt(T0)), Haff's ODE, whose solution is
// T0 / (1 + t/tau0)^2 with 1/tau0 = (1 - eps^2) omega0 / 6 (see haffInverseTau0): the
// normalisation of the average and the factor 1/12 are thereby fixed independently.
double energyLossFactor(const RestitutionFunction& e, double T, double rel_tol) {
  checkTemperature(T, "the energy loss factor");
  if (!(rel_tol > 0.0 && rel_tol < 1.0))
    throw std::invalid_argument("energy loss quadrature tolerance must lie in (0, 1) (got " +
                                formatReal(rel_tol) + ").");
  if (!e)
    throw std::invalid_argument(
        "energy loss factor requires a restitution function (got an empty one).");
  // Substituting g = 2 sqrt(T) y: L = int_0^inf 2 y^3 exp(-y^2) [1 - e(2 sqrt(T) y)^2] dy. The
  // weight has unit integral; the range is cut at y = 10, where the tail weight is
  // 101 exp(-100) ~ 4e-42.
  const double two_sqrt_T = 2.0 * std::sqrt(T);
  struct Ctx {
    const RestitutionFunction* e;
    double scale;
    std::exception_ptr error;
  } ctx{&e, two_sqrt_T, nullptr};
  gsl_function F;
  F.params = &ctx;
  F.function = [](double y, void* p) -> double {
    auto* c = static_cast<Ctx*>(p);
    try {
      const double ee = (*c->e)(c->scale * y);
      return 2.0 * y * y * y * std::exp(-y * y) * (1.0 - ee * ee);
    } catch (...) {
      if (!c->error) c->error = std::current_exception();
      return 0.0;
    }
  };
  constexpr std::size_t LIMIT = 200;
  std::unique_ptr<gsl_integration_workspace, void (*)(gsl_integration_workspace*)> ws(
      gsl_integration_workspace_alloc(LIMIT), gsl_integration_workspace_free);
  if (!ws) throw std::runtime_error("gsl_integration_workspace_alloc failed.");
  double result = 0.0, abserr = 0.0;
  int status;
  {
    GslHandlerOff off;
    status = gsl_integration_qags(&F, 0.0, 10.0, 0.0, rel_tol, LIMIT, ws.get(), &result, &abserr);
  }
  if (ctx.error) std::rethrow_exception(ctx.error);
  if (status != GSL_SUCCESS && !(abserr <= 100.0 * rel_tol * std::fabs(result)))
    throw std::runtime_error(std::string("velocity average of the energy loss failed at T = ") +
                             formatReal(T) + ": " + gsl_strerror(status) + ".");
  return result;
}

double coolingRate(const RestitutionFunction& e, double phi, double T) {
  if (T == 0.0) return 0.0;
  return -enskogCollisionFrequency(phi, T) * T * energyLossFactor(e, T) / 3.0;
}

std::vector<CoolingSample> solveCooling(const RestitutionFunction& e,
                                        const std::vector<double>& times, const CoolingOptions& o) {
  namespace odeint = boost::numeric::odeint;
  validateFillingFraction(o.phi);
  if (!(o.T0 > 0.0) || !std::isfinite(o.T0))
    throw std::invalid_argument("cooling requires a positive, finite initial temperature T0 (got " +
                                formatReal(o.T0) + ").");
  if (!(o.rtol > 0.0 && o.rtol < 1.0) || !(o.atol > 0.0 && o.atol < 1.0))
    throw std::invalid_argument("cooling tolerances rtol and atol must lie in (0, 1) (got rtol = " +
                                formatReal(o.rtol) + ", atol = " + formatReal(o.atol) + ").");
  if (!e)
    throw std::invalid_argument("cooling requires a restitution function (got an empty one).");
  for (std::size_t k = 0; k < times.size(); ++k) {
    checkTime(times[k]);
    if (k > 0 && times[k] < times[k - 1])
      throw std::invalid_argument("cooling output times must not decrease (got " +
                                  formatReal(times[k - 1]) + " then " + formatReal(times[k]) +
                                  ").");
  }
  std::vector<CoolingSample> out;
  if (times.empty()) return out;

  const double omega0 = enskogCollisionFrequency(o.phi, o.T0);
  auto sample = [&](double t, double T) {
    CoolingSample s;
    s.t = t;
    s.T = T;
    s.loss = energyLossFactor(e, T, o.quad_rtol);
    s.rate = -omega0 * std::sqrt(T / o.T0) * T * s.loss / 3.0;
    s.slope = t > 0.0 ? t * s.rate / T : 0.0;
    return s;
  };

  // Variables u = ln(T/T0) against s = ln(1 + t): du/ds = (1 + t) (dT/dt) / T
  //   = -(1 + t) omega0 sqrt(T/T0) L(T) / 3,
  // which stays of order one at all times for both T ~ t^{-2} and T ~ t^{-5/3} tails.
  using State = std::array<double, 1>;
  auto rhs = [&](const State& u, State& dudt, double s) {
    const double t = std::expm1(s);
    const double T = o.T0 * std::exp(u[0]);
    dudt[0] = -(1.0 + t) * omega0 * std::sqrt(T / o.T0) * energyLossFactor(e, T, o.quad_rtol) / 3.0;
  };
  std::vector<double> s_grid{0.0};
  for (double t : times)
    if (std::log1p(t) > s_grid.back()) s_grid.push_back(std::log1p(t));
  std::vector<double> u_at(s_grid.size(), 0.0);
  State u{0.0};
  if (s_grid.size() > 1) {
    std::size_t k = 0;
    auto stepper = odeint::make_dense_output(o.atol, o.rtol, odeint::runge_kutta_dopri5<State>());
    odeint::integrate_times(stepper, rhs, u, s_grid.begin(), s_grid.end(), 1e-3,
                            [&](const State& x, double) { u_at[k++] = x[0]; });
  }
  std::size_t j = 0;
  for (double t : times) {
    while (j + 1 < s_grid.size() && s_grid[j] < std::log1p(t)) ++j;
    out.push_back(sample(t, o.T0 * std::exp(u_at[j])));
  }
  return out;
}

std::vector<CoolingSample> solveViscoelasticCooling(const ContactParams& params,
                                                    const std::vector<double>& times,
                                                    const CoolingOptions& options) {
  // The velocity average reaches g = 20 sqrt(T0) (y = 10 in energyLossFactor); extend the table
  // beyond the default b_max = 20 if that impact speed needs it (strong damping).
  validateContactParams(params);
  const double b1 = params.D * std::pow(M_EFF, -0.4) * std::pow(params.E, -0.6);
  const double b_top = b1 * std::pow(20.0 * std::sqrt(std::max(options.T0, 0.0)), 0.2);
  const RestitutionTable table(params, 1e-6, std::max(20.0, 1.2 * b_top));
  return solveCooling([&table](double g) { return table(g); }, times, options);
}

// Small-damping closed form. To first order, 1 - e^2 = 2 (1 - e) = 2 C1 b1 g^{1/5}, and with
// <g^p>_P = (4T)^{p/2} Gamma(1 + p/2):
//   L(T) = 2 C1 b1 <g^{11/5}> / (4T) = 2 C1 b1 (4T)^{1/10} Gamma(21/10),
//   dT/dt = -omega0 sqrt(T/T0) T L / 3 = -(2/3) 4^{1/10} Gamma(21/10) C1 b1 omega0 T0^{-1/2}
//   T^{8/5}.
// Separating, T^{-3/5} - T0^{-3/5} = (3/5)(2/3) 4^{1/10} Gamma(21/10) C1 b1 omega0 T0^{-1/2} t, so
// T = T0 (1 + t/tau0')^{-5/3} with 1/tau0' = (2/5) 4^{1/10} Gamma(21/10) C1 b1 T0^{1/10} omega0
// = (16/5) q0 delta omega0, q0 = 2^{1/5} Gamma(21/10) / 8, delta = C1 b1 T0^{1/10}
// (since (16/5)(2^{1/5}/8) = (2/5) 4^{1/10}). This is the structure of Schwager & Poeschel (1998)
// and Brilliantov & Poeschel (2004) with their delta and q0; the constant is derived here for
// the Maxwellian average used by solveCooling, so the two agree to first order in delta.
double viscoelasticCoolingTau0(const ContactParams& params, double phi, double T0) {
  validateContactParams(params);
  if (!(T0 > 0.0) || !std::isfinite(T0))
    throw std::invalid_argument(
        "viscoelastic cooling requires a positive initial temperature T0 (got " + formatReal(T0) +
        ").");
  if (params.D == 0.0)
    throw std::invalid_argument(
        "viscoelastic cooling law requires a positive dissipative constant D (got 0: no cooling).");
  const double b1 = params.D * std::pow(M_EFF, -0.4) * std::pow(params.E, -0.6);
  const double delta = RESTITUTION_C1 * b1 * std::pow(T0, 0.1);
  const double q0 = std::pow(2.0, 0.2) * std::tgamma(2.1) / 8.0;
  return 1.0 / (16.0 / 5.0 * q0 * delta * enskogCollisionFrequency(phi, T0));
}

double viscoelasticCoolingTemperature(double t, const ContactParams& params, double phi,
                                      double T0) {
  checkTime(t);
  return T0 * std::pow(1.0 + t / viscoelasticCoolingTau0(params, phi, T0), -5.0 / 3.0);
}

}  // namespace granagg::meanfield
