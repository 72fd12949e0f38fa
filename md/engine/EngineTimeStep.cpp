/// \file EngineTimeStep.cpp
/// The engine's time step: the fixed or "auto" step of a configuration, the adaptive step the gas
/// needs now, and changing the step between run() calls (Engine.h, "Adaptive time step").
#include "md/engine/Engine.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>

#include <thrust/iterator/counting_iterator.h>
#include <thrust/transform.h>

#include "md/engine/EngineImpl.h"
#include "md/engine/Launch.h"

namespace granagg::md {

using engine_detail::CombineVelocitySums;
using engine_detail::M_EFF;
using engine_detail::VelocitySums;
using engine_detail::VelocitySumsOf;

namespace {
/// The fastest impact the time step resolves: integrator.impact_speed_max, or "auto": exceeded by
/// a fraction 1e-6 of collisions in a Maxwellian gas at the initial temperature (collision-
/// weighted P(g) = g/(2T) exp(-g^2/(4T)), tail exp(-g^2/(4T))).
double impactSpeedMax(const MdConfig& c) {
  if (c.integrator.impact_speed_max > 0.0) return c.integrator.impact_speed_max;
  return std::sqrt(4.0 * c.system.temperature * std::log(1e6));
}

// integrator.dt = "adaptive" (Engine::adaptiveTimeStep): the margin on the fastest listed pair's
// impact speed (it may still gain speed before the next choice of the step; a speed margin m
// shortens the step by m^{1/5} only, 4.6 % here), and the largest step, in "auto" steps (a
// frozen gas, v -> 0, would otherwise ask for an infinite step)
constexpr double ADAPTIVE_PAIR_MARGIN = 1.25;
constexpr double ADAPTIVE_DT_GROWTH_MAX = 10.0;
}  // namespace

void Engine::Impl::changeTimeStep(double dt_new, std::int64_t next_change) {
  const double dt_old = dt;
  slow.interval_end = next_change;
  if (coulomb && slow.eval_step >= 0) {  // (< 0: the next force pass evaluates afresh)
    const std::int64_t j = step - slow.eval_step;
    double tau_prev = 0.0, w_old = 0.0;
    if (fresh_start) {  // (j = 0) the opening half alone, never applied to v: a fresh opening
      dt = dt_new;
      slowBoundsForStep();
      w_old = slowWeight(step);
      slow.every = chooseEvery();
      slow.every_prev = slow.every;
      addSlowForce(slowWeight(step) - w_old);
      moveTimeOrigin(dt_old);
      return;
    }
    double taken_back = 0.0;  // the closing half already in v, per unit F at this step
    if (j > 0) {
      kickSlow(-0.5 * static_cast<double>(slow.every - j) * dt_old);
      tau_prev = static_cast<double>(j) * dt_old;
      if (nl_coul && nl_coul->needsRebuild(p, drift_since_coul_build * drift_since_coul_build))
        rebuildList(true);
      evaluateSlowForce();
    } else {
      w_old = slowWeight(step);
      taken_back = 0.5 * dt_old * w_old;
      tau_prev = slow.every_prev * dt_old;
    }
    dt = dt_new;
    slowBoundsForStep();
    slow.eval_step = step;
    if (j > 0 || dt_new != dt_old) slow.every_prev = tau_prev / dt_new;
    slow.every = chooseEvery();
    const double w = slowWeight(step);
    // (one kick: nothing at all when neither the step nor the interval changed)
    kickSlow(0.5 * dt_new * w - taken_back);
    addSlowForce(w - w_old);
  }
  dt = dt_new;
  slowBoundsForStep();
  moveTimeOrigin(dt_old);
}

void Engine::Impl::moveTimeOrigin(double dt_old) {
  if (dt == dt_old) return;
  time_origin = time;
  step_origin = step;
}

double Engine::Impl::temperature() const {
  const std::size_t N = p.size();
  DVec<double> vx, vy, vz;
  unpackVec3(p.vel, vx, vy, vz);
  DVec<VelocitySums> per_slot(N);
  thrust::transform(thrust::counting_iterator<int>(0),
                    thrust::counting_iterator<int>(static_cast<int>(N)), per_slot.begin(),
                    VelocitySumsOf{raw(vx), raw(vy), raw(vz)});
  const VelocitySums vs = reduceById(per_slot, p.id, VelocitySums{}, CombineVelocitySums{});
  const double p2 = vs.p[0] * vs.p[0] + vs.p[1] * vs.p[1] + vs.p[2] * vs.p[2];
  return (vs.v2 - p2 / N) / (3.0 * N);
}

double Engine::chooseTimeStep(const MdConfig& c, std::string* reason) {
  if (c.integrator.dt > 0.0) {
    if (reason) *reason = "fixed by integrator.dt";
    return c.integrator.dt;
  }
  std::ostringstream why;
  std::string model_why;
  const double tc = std::visit(
      [&](const auto& m) {
        using Model = typename std::decay_t<decltype(m)>::Model;
        return Model::autoContactTime(m.params, impactSpeedMax(c), M_EFF, model_why);
      },
      makeContactModel(c.contact, M_EFF));
  why << model_why;
  const double dt = tc / c.integrator.steps_per_contact;
  why << " / " << c.integrator.steps_per_contact << " steps per contact";
  if (reason) *reason = "auto: " + why.str();
  return dt;
}

double Engine::impactSpeedMax(const MdConfig& config) { return md::impactSpeedMax(config); }

double Engine::adaptiveTimeStep(std::string* reason) const {
  const Impl& d = *m_impl;
  const double T = std::max(0.0, d.temperature());
  // the "auto" rule's tail speed at the current temperature (impactSpeedMax scales as sqrt(T))
  const double v_tail = md::impactSpeedMax(d.cfg) * std::sqrt(T / d.cfg.system.temperature);
  const double v_pair = std::sqrt(
      maxPairImpactSpeed2(d.p, d.nl, d.box, d.contact, d.coulomb ? d.cfg.coulomb.K : 0.0, M_EFF));
  const double v = std::max(v_tail, ADAPTIVE_PAIR_MARGIN * v_pair);
  std::string model_why;
  const double tc = std::visit(
      [&](const auto& m) {
        using Model = typename std::decay_t<decltype(m)>::Model;
        return Model::autoContactTime(m.params, v, M_EFF, model_why);
      },
      d.contact);
  const double dt_cap = ADAPTIVE_DT_GROWTH_MAX * d.dt_auto;
  const double dt = std::min(tc / d.cfg.integrator.steps_per_contact, dt_cap);
  if (reason) {
    std::ostringstream why;
    why << "adaptive: " << model_why << " / " << d.cfg.integrator.steps_per_contact
        << " steps per contact (the larger of the T_g tail speed " << v_tail << " and "
        << ADAPTIVE_PAIR_MARGIN << " x the fastest listed pair's impact speed " << v_pair << ")";
    if (dt == dt_cap) why << ", capped at " << ADAPTIVE_DT_GROWTH_MAX << " x the auto step";
    *reason = why.str();
  }
  return dt;
}

void Engine::setTimeStep(double dt, std::int64_t next_change) {
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("Engine::setTimeStep: dt must be positive and finite");
  Impl& d = *m_impl;
  // (the same step: only an evaluation at this step re-chooses its interval for the new end)
  if (dt != d.dt || (d.coulomb && d.slow.eval_step == d.step))
    d.changeTimeStep(dt, next_change);
  else
    d.slow.interval_end = next_change;
}

}  // namespace granagg::md
