#include "meanfield/solvers/MonodisperseSolver.h"

#include <boost/numeric/odeint.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/Csv.h"

namespace granagg::meanfield {

namespace {

void checkInitialSize(double i0) {
  if (!(i0 > 0.0) || !std::isfinite(i0))
    throw std::invalid_argument("monodisperse initial_size must be positive and finite (got " +
                                common::formatReal(i0) + ").");
}

}  // namespace

double monodisperseBlowUpTime(const Kernel& kernel, double initial_size) {
  checkInitialSize(initial_size);
  const double lambda = kernel.homogeneity();
  if (lambda <= 1.0) return std::numeric_limits<double>::infinity();
  const double c = kernel(1.0, 1.0);  // K(i, i) = c i^lambda by homogeneity
  // i^{1-lambda} = i0^{1-lambda} - (lambda - 1) c t reaches zero (docs/model.md section 12;
  // separation of variables)
  return std::pow(initial_size, 1.0 - lambda) / ((lambda - 1.0) * c);
}

double monodisperseMeanSize(const Kernel& kernel, double t, double initial_size) {
  checkInitialSize(initial_size);
  if (!(t >= 0.0) || !std::isfinite(t))
    throw std::invalid_argument("monodisperse time must be finite and >= 0 (got " +
                                common::formatReal(t) + ").");
  const double lambda = kernel.homogeneity();
  const double c = kernel(1.0, 1.0);
  // di/dt = c i^lambda separated: i^{1-lambda} = i0^{1-lambda} + (1 - lambda) c t  (lambda != 1),
  // ln i = ln i0 + c t  (lambda = 1).  Written in logarithms to keep full precision for large i.
  if (lambda == 1.0) return initial_size * std::exp(c * t);
  const double t_star = monodisperseBlowUpTime(kernel, initial_size);
  if (!(t < t_star))
    throw std::invalid_argument("monodisperse time " + common::formatReal(t) +
                                " is at or beyond the blow-up time " + common::formatReal(t_star) +
                                " of kernel '" + kernel.name() + "'.");
  const double a = 1.0 - lambda;
  const double base = std::pow(initial_size, a) + a * c * t;
  return std::exp(std::log(base) / a);
}

SmolResult solveMonodisperse(const Kernel& kernel, const MonodisperseOptions& options) {
  using common::formatReal;
  namespace odeint = boost::numeric::odeint;
  const auto wall_start = std::chrono::steady_clock::now();

  const MonodisperseOptions& o = options;
  if (o.times.empty())
    throw std::invalid_argument(
        "monodisperse solver requires at least one output time (times is empty).");
  for (size_t k = 0; k < o.times.size(); ++k) {
    if (!(o.times[k] > 0.0) || !std::isfinite(o.times[k]))
      throw std::invalid_argument("monodisperse times must be positive and finite (got " +
                                  formatReal(o.times[k]) + ").");
    if (k > 0 && !(o.times[k] > o.times[k - 1]))
      throw std::invalid_argument("monodisperse times must increase strictly (got " +
                                  formatReal(o.times[k - 1]) + " then " + formatReal(o.times[k]) +
                                  ").");
  }
  checkInitialSize(o.initial_size);
  if (!(o.rtol > 0.0) || !std::isfinite(o.rtol))
    throw std::invalid_argument("monodisperse rtol must be positive and finite (got " +
                                formatReal(o.rtol) + ").");
  if (!(o.atol > 0.0) || !std::isfinite(o.atol))
    throw std::invalid_argument("monodisperse atol must be positive and finite (got " +
                                formatReal(o.atol) + ").");
  if (!(o.s_end > 0.0))
    throw std::invalid_argument("monodisperse s_end must be positive (got " + formatReal(o.s_end) +
                                ").");
  const double t_star = monodisperseBlowUpTime(kernel, o.initial_size);
  if (!(o.times.back() < t_star))
    throw std::invalid_argument("monodisperse times must stay before the blow-up time " +
                                formatReal(t_star) + " of kernel '" + kernel.name() + "' (got " +
                                formatReal(o.times.back()) + ").");

  // u = ln i against s = ln(1 + t): du/ds = (dt/ds) (di/dt) / i = (1 + t) K(i, i) / i.
  using State = std::vector<double>;
  long rhs_evaluations = 0;
  auto system = [&kernel, &rhs_evaluations](const State& u, State& duds, double s) {
    const double t = std::expm1(s);
    const double i = std::exp(u[0]);
    duds[0] = (1.0 + t) * kernel(i, i) / i;
    ++rhs_evaluations;
  };
  auto stepper = odeint::make_controlled(o.atol, o.rtol, odeint::runge_kutta_fehlberg78<State>());

  SmolResult result;
  result.method = "mono";
  State u{std::log(o.initial_size)};
  double s = 0.0;
  double ds = 1e-3;  // first trial step in s; the controller adapts it
  for (double tout : o.times) {
    const double s_out = std::log1p(tout);
    if (s_out > s) {
      result.stats.steps += static_cast<long>(
          odeint::integrate_adaptive(stepper, system, u, s, s_out, std::min(ds, s_out - s)));
      ds = std::max(ds, 0.1 * (s_out - s));
      s = s_out;
    }
    MomentSample m;
    m.t = tout;
    const double i = std::exp(u[0]);
    m.S = i;
    m.M0 = 1.0 / i;  // n = M1 / i with M1 = 1
    m.M1 = 1.0;
    m.M2 = i;  // sum k^2 n_k = i^2 n
    m.mass_loss = 0.0;
    m.valid = std::isfinite(i);
    m.max_size = i;
    result.samples.push_back(m);
    if (!m.valid) {
      result.stopped_early = "mean size is no longer finite at t = " + formatReal(tout);
      result.stop_cause = StopCause::NotFinite;
      break;
    }
    if (i >= o.s_end) break;
  }
  result.stats.rhs_evaluations = rhs_evaluations;
  result.stats.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace granagg::meanfield
