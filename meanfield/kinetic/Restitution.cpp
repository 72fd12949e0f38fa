/// Viscoelastic restitution coefficient by integration of the scaled two-body contact
/// (Restitution.h; docs/model.md section 3).
#include "meanfield/kinetic/Restitution.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gsl/gsl_spline.h>
#include <boost/math/tools/toms748_solve.hpp>
#include <boost/numeric/odeint.hpp>

#include "common/Csv.h"

namespace granagg::meanfield {

using common::formatReal;

void validateContactParams(const ContactParams& p) {
  if (!(p.E > 0.0) || !std::isfinite(p.E))
    throw std::invalid_argument(
        "viscoelastic contact requires the elastic constant E to be positive and finite (got " +
        formatReal(p.E) + ").");
  if (!(p.D >= 0.0) || !std::isfinite(p.D))
    throw std::invalid_argument(
        "viscoelastic contact requires the dissipative constant D to be non-negative and finite "
        "(got " +
        formatReal(p.D) + ").");
}

namespace {

void validateOptions(const RestitutionOptions& o) {
  if (!(o.tolerance >= 1e-15 && o.tolerance <= 1e-3))
    throw std::invalid_argument("restitution tolerance must lie in [1e-15, 1e-3] (got " +
                                formatReal(o.tolerance) + ").");
  if (!(o.max_scaled_time > 0.0) || !std::isfinite(o.max_scaled_time))
    throw std::invalid_argument("restitution max_scaled_time must be positive and finite (got " +
                                formatReal(o.max_scaled_time) + ").");
}

using State = std::array<double, 2>;  // (x, x') in the scaled units of Restitution.h

/// Unclamped scaled force law x'' = -x^{1/2} (x + b x') for x > 0, free flight for x <= 0. The
/// clamped variant needs no separate right-hand side: before the force first vanishes the two
/// are identical, and the clamped contact is finished analytically from that point (see below),
/// so the integrator never sees the kink of max(F, 0).
struct ScaledContact {
  double b;
  void operator()(const State& y, State& dy, double /*s*/) const {
    const double x = y[0];
    const double r = x > 0.0 ? std::sqrt(x) : 0.0;
    dy[0] = y[1];
    dy[1] = -r * (x + b * y[1]);
  }
};

/// Root of one scalar function of the dense output on [a, c] (with values fa, fc of opposite
/// sign) by Boost.Math's TOMS 748 to full double precision.
template <class F>
double bracketRoot(F f, double a, double c, double fa, double fc) {
  if (fa == 0.0) return a;
  if (fc == 0.0) return c;
  std::uintmax_t iterations = 200;
  const auto r = boost::math::tools::toms748_solve(
      f, a, c, fa, fc, boost::math::tools::eps_tolerance<double>(52), iterations);
  return 0.5 * (r.first + r.second);
}

}  // namespace

CollisionResult collideScaled(double b, bool clamped, const RestitutionOptions& options) {
  namespace odeint = boost::numeric::odeint;
  if (!(b >= 0.0) || !std::isfinite(b))
    throw std::invalid_argument(
        "restitution scaling parameter b must be non-negative and finite (got " + formatReal(b) +
        ").");
  validateOptions(options);

  // Start off the singular point x = 0 (where x^{1/2} is not Lipschitz) on the short-time series
  // of the solution, obtained by inserting x = s + ... into x'' = -x^{1/2}(x + b x') and
  // integrating term by term:
  //   x''= -b s^{1/2} - s^{3/2} + (4/5) b^2 s^2 + O(b s^3, b^3 s^{7/2}),
  //   x' = 1 - (2/3) b s^{3/2} - (2/5) s^{5/2} + (4/15) b^2 s^3,
  //   x  = s - (4/15) b s^{5/2} - (4/35) s^{7/2} + (1/15) b^2 s^4.
  // At s0 = 1e-4 / max(1, b) the neglected terms change x' by less than 1e-16 for b <= 20 (and
  // by O(b^3 s0^{9/2}) beyond), far below the integration tolerance; the test suite checks that
  // e is unchanged when the tolerance is tightened.
  const double s0 = 1e-4 / std::max(1.0, b);
  const double s12 = std::sqrt(s0), s32 = s0 * s12, s52 = s32 * s0, s72 = s52 * s0;
  State y{
      s0 - (4.0 / 15.0) * b * s52 - (4.0 / 35.0) * s72 + (1.0 / 15.0) * b * b * s0 * s0 * s0 * s0,
      1.0 - (2.0 / 3.0) * b * s32 - 0.4 * s52 + (4.0 / 15.0) * b * b * s0 * s0 * s0};

  const ScaledContact rhs{b};
  auto stepper = odeint::make_dense_output(options.tolerance, options.tolerance,
                                           odeint::runge_kutta_dopri5<State>());
  stepper.initialize(y, s0, s0);

  // Event functions on the dense output: x' (maximum compression), x (overlap closes) and
  // g = x + b x' (the force F ~ x^{1/2} g changes sign during the recovery).
  auto component = [&stepper](double s, int which, double bb) {
    State z;
    stepper.calc_state(s, z);
    return which == 0 ? z[0] : (which == 1 ? z[1] : z[0] + bb * z[1]);
  };

  CollisionResult r;
  r.scaling_parameter = b;
  bool receding = false;  // past the maximum compression
  while (true) {
    const auto step = stepper.do_step(rhs);
    ++r.steps;
    const double sa = step.first, sc = step.second;
    const State& ya = stepper.previous_state();
    const State& yc = stepper.current_state();
    if (!std::isfinite(yc[0]) || !std::isfinite(yc[1]))
      throw std::runtime_error(
          "restitution integration produced a non-finite state at b = " + formatReal(b) + ".");

    if (!receding && yc[1] <= 0.0) {
      // Maximum compression inside this step: x' crosses zero.
      const double sm =
          bracketRoot([&](double s) { return component(s, 1, b); }, sa, sc, ya[1], yc[1]);
      r.max_overlap = component(sm, 0, b);
      receding = true;
    } else if (receding && yc[1] > 0.0) {
      // Only the unclamped attractive tail can turn the separation round.
      throw std::runtime_error(
          "unclamped contact is captured by its attractive force at b = " + formatReal(b) +
          ": the overlap never closes (use the clamped force).");
    }

    if (receding && clamped) {
      const double ga = ya[0] + b * ya[1], gc = yc[0] + b * yc[1];
      if (gc <= 0.0) {
        // The force vanishes at s* and would turn attractive: the clamped contact releases and
        // the overlap closes at the constant speed x'(s*) (no force acts while x > 0 and g < 0,
        // since g keeps decreasing in free flight), so e = -x'(s*).
        const double ss = bracketRoot([&](double s) { return component(s, 2, b); }, sa, sc, ga, gc);
        State z;
        stepper.calc_state(ss, z);
        r.restitution = -z[1];
        r.release_time = ss;
        r.contact_time = ss + std::max(z[0], 0.0) / (-z[1]);
        return r;
      }
    }
    if (receding && !clamped && yc[0] <= 0.0) {
      const double se =
          bracketRoot([&](double s) { return component(s, 0, b); }, sa, sc, ya[0], yc[0]);
      r.restitution = -component(se, 1, b);
      r.release_time = se;
      r.contact_time = se;
      return r;
    }
    if (sc > options.max_scaled_time)
      throw std::runtime_error("viscoelastic contact at b = " + formatReal(b) +
                               " has not ended after " + formatReal(options.max_scaled_time) +
                               " scaled time units.");
  }
}

double seriesRestitutionScaled(double b) {
  return 1.0 - RESTITUTION_C1 * b + RESTITUTION_C2 * b * b;
}

// First-order coefficient, rederived: along the elastic trajectory (1/2) m_eff xi'^2 +
// (2/5) E xi^{5/2} = (1/2) m_eff v^2 the dissipated energy is
//   Delta = 2 D int_0^{X} xi^{1/2} xi' dxi = 2 D v X^{3/2} int_0^1 u^{1/2} (1 - u^{5/2})^{1/2} du
//         = 2 D v X^{3/2} (2/5) B(3/5, 3/2),   X^{5/2} = (5/4) m_eff v^2 / E,
// and 1 - e ~ Delta / (m_eff v^2) = (4/5) (5/4)^{3/5} B(3/5, 3/2) D m_eff^{-2/5} E^{-3/5} v^{1/5}
// = C1 b with C1 = Gamma(3/5) sqrt(pi) / (2^{1/5} 5^{2/5} Gamma(21/10)) = 1.153445: the
// published constant, which fixes the mapping b = A kappa^{2/5} v^{1/5} of Restitution.h.

Restitution::Restitution(const ContactParams& params, const RestitutionOptions& options)
    : m_params(params), m_options(options) {
  validateContactParams(m_params);
  validateOptions(m_options);
}

void Restitution::checkSpeed(double v) const {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::invalid_argument("restitution requires a positive, finite impact speed v (got " +
                                formatReal(v) + ").");
}

double Restitution::scalingParameter(double v) const {
  checkSpeed(v);
  return m_params.D * std::pow(M_EFF, -0.4) * std::pow(m_params.E, -0.6) * std::pow(v, 0.2);
}

double Restitution::timeScale(double v) const {
  checkSpeed(v);
  return std::pow(M_EFF, 0.4) * std::pow(m_params.E, -0.4) * std::pow(v, -0.2);
}

double Restitution::overlapScale(double v) const {
  checkSpeed(v);
  return std::pow(M_EFF * v * v / m_params.E, 0.4);
}

CollisionResult Restitution::collide(double v) const {
  CollisionResult r = collideScaled(scalingParameter(v), m_params.clamped, m_options);
  const double tau = timeScale(v);
  r.contact_time *= tau;
  r.release_time *= tau;
  r.max_overlap *= overlapScale(v);
  return r;
}

double Restitution::seriesRestitution(double v) const {
  return seriesRestitutionScaled(scalingParameter(v));
}

double Restitution::elasticContactTime(double v) const {
  checkSpeed(v);
  return HERTZ_CONTACT_TIME_FACTOR * std::pow(M_EFF * M_EFF / (m_params.E * m_params.E * v), 0.2);
}

// ---- RestitutionTable ----

struct RestitutionTable::Spline {
  gsl_spline* spline = nullptr;
  Spline(const std::vector<double>& x, const std::vector<double>& y) {
    spline = gsl_spline_alloc(gsl_interp_cspline, x.size());
    if (!spline) throw std::runtime_error("gsl_spline_alloc failed for the restitution table.");
    gsl_spline_init(spline, x.data(), y.data(), x.size());
  }
  ~Spline() { gsl_spline_free(spline); }
  Spline(const Spline&) = delete;
  Spline& operator=(const Spline&) = delete;
};

RestitutionTable::RestitutionTable(const ContactParams& params, double b_min, double b_max,
                                   int points, const RestitutionOptions& options)
    : m_params(params), m_options(options), m_b_min(b_min), m_b_max(b_max) {
  validateContactParams(m_params);
  validateOptions(m_options);
  if (!(b_min > 0.0) || !(b_max > b_min) || !std::isfinite(b_max))
    throw std::invalid_argument("restitution table requires 0 < b_min < b_max < inf (got b_min = " +
                                formatReal(b_min) + ", b_max = " + formatReal(b_max) + ").");
  if (points < 8)
    throw std::invalid_argument("restitution table requires at least 8 points (got " +
                                std::to_string(points) + ").");
  m_b1 = m_params.D * std::pow(M_EFF, -0.4) * std::pow(m_params.E, -0.6);

  // Knots uniform in ln b for ln[(1 - e)/b], which is smooth and nearly linear at both ends:
  // -> ln C1 - (C2/C1) b as b -> 0 and ~ -ln b for large b (e -> 0). Nearly linear ends suit the
  // natural end conditions (zero second derivative) of the cubic spline; the knots also extend
  // MARGIN spacings beyond [b_min, b_max], so that what is left of the end error (it decays by
  // 2 - sqrt(3) per knot) does not reach the range that is used.
  const int inner = points;
  const double h = (std::log(b_max) - std::log(b_min)) / (inner - 1);
  constexpr int MARGIN = 8;
  points = inner + 2 * MARGIN;
  std::vector<double> lnb(points), f(points);
  const double l0 = std::log(b_min) - MARGIN * h;
  for (int i = 0; i < points; ++i) {
    lnb[i] = l0 + h * i;
    const double b = std::exp(lnb[i]);
    f[i] = std::log((1.0 - collideScaled(b, m_params.clamped, m_options).restitution) / b);
  }
  m_spline = std::make_shared<const Spline>(lnb, f);
}

double RestitutionTable::restitutionScaled(double b) const {
  if (b <= 0.0) return 1.0;
  if (b < m_b_min) return seriesRestitutionScaled(b);
  if (b > m_b_max) return collideScaled(b, m_params.clamped, m_options).restitution;
  return 1.0 - b * std::exp(gsl_spline_eval(m_spline->spline, std::log(b), nullptr));
}

double RestitutionTable::operator()(double v) const {
  return restitutionScaled(m_b1 * std::pow(v, 0.2));
}

double RestitutionTable::restitution(double v) const {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::invalid_argument("restitution requires a positive, finite impact speed v (got " +
                                formatReal(v) + ").");
  return (*this)(v);
}

}  // namespace granagg::meanfield
