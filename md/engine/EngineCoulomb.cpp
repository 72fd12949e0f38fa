/// \file EngineCoulomb.cpp
/// The engine's Coulomb part (Engine.h, "multiple time stepping"): the lists and the schedule
/// around the solvers (md/engine/SlowCoulomb.h): setting them up for a design, evaluating the
/// slow force and choosing its interval, and the Coulomb energy for observables.
#include "md/engine/Engine.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include <thrust/functional.h>
#include <thrust/transform_reduce.h>

#include "md/engine/EngineImpl.h"
#include "md/neighbor/Skin.h"

namespace granagg::md {

namespace {
/// |u|^2 of a velocity (the fastest particle, for the slow interval that follows the gas)
struct Speed2 {
  HD double operator()(const Vec3& u) const { return u.x * u.x + u.y * u.y + u.z * u.z; }
};

// coulomb.every = "auto": time between evaluations of the slow Coulomb part (Engine::coulombEvery)
constexpr double SLOW_INTERVAL = 0.016;

}  // namespace

void Engine::Impl::setupCoulomb(double sum_q2_design) {
  const CoulombConfig& cc = cfg.coulomb;
  const std::size_t N = p.size();
  const double L = box.L, skin = cfg.neighbor.skinCap();
  const CoulombDesign d =
      designCoulomb(cc, N, L, skin, slow.design_base, slow.design_cap, sum_q2_design);
  slow_coulomb = std::make_unique<SlowCoulomb>(d, cc, L, N, &timer);
  nl_coul.reset();
  if (slow_coulomb->usesMesh()) {
    nl_coul = std::make_unique<NeighborList>(d.pppm.r_cut, d.coulomb_skin);
    tuner.setCoulombRule({d.coulomb_skin_follows, slow_coulomb->setup().r_cut,
                          COULOMB_LIST_BUILD_OVER_USE, COULOMB_SKIN_AUTO_MIN, d.coulomb_skin});
  }
  nl = NeighborList(d.contact_list_cutoff, skin);
  nl.keepPairs(d.contact_list_keeps_pairs);
  // the contact list's skin follows where it is "auto" and the list holds fast Coulomb pairs
  const double r2 = slow_coulomb->fastSwitch().r2;
  tuner.setContactRule({cfg.neighbor.skin == 0.0 && r2 > 0.0, r2, CONTACT_LIST_BUILD_OVER_USE,
                        NEIGHBOR_SKIN_AUTO_MIN, skin});
  slow.eval_step = -1;
}

void Engine::Impl::evaluateCoulomb() {
  // the interval that ends here (a fresh start has none: its impulse opens an interval only)
  slow.every_prev = slow.eval_step < 0 ? -1.0 : static_cast<double>(step - slow.eval_step);
  slow.eval_step = step;
  slow.every = chooseEvery();
  if (slow.every_prev < 0) slow.every_prev = slow.every;
  evaluateSlowForce();
}

void Engine::Impl::evaluateSlowForce() {
  ++slow_evaluations;
  slow_coulomb->evaluate(p, nl_coul.get(), box, &timer);
}

int Engine::Impl::chooseEvery() const {
  if (!slow.follows()) return slow.clamp(slow.every_base, step);
  const double u2 = thrust::transform_reduce(p.vel.begin(), p.vel.end(), Speed2{}, 0.0,
                                             thrust::maximum<double>());
  const double v_rel = 2.0 * std::sqrt(u2);
  return slow.clamp(
      v_rel > 0.0 ? std::floor(slow.every_base * impactSpeedMax(cfg) / v_rel) : slow.every_cap,
      step);
}

void Engine::Impl::addSlow(DVec<Vec3>& a, double c) { slow_coulomb->addScaled(a, c); }

void Engine::Impl::slowBoundsForStep() {
  if (coulomb) slow.boundsFor(dt);
}

double Engine::Impl::coulombEnergyNow() {
  if (!coulomb) return 0.0;
  if (nl_coul && nl_coul->needsRebuild(p, drift_since_coul_build * drift_since_coul_build)) {
    tuner.tuneCoulomb(*nl_coul, dt, slow.every);
    nl_coul->build(p, box);
    drift_since_coul_build = 0.0;
  }
  return slow_coulomb->energyNow(p, nl_coul.get(), box, slow.eval_step == step);
}

int Engine::coulombEvery(const MdConfig& c, double dt) {
  // multiple time stepping with PPPM only: the plain-Ewald reference has no fast/slow split
  if (c.coulomb.method != "pppm") return 1;
  if (c.coulomb.every > 0) return c.coulomb.every;
  // auto: the slow part every SLOW_INTERVAL time units, the interval whose accuracy the tests
  // check (8 steps of 0.002: energy drift < 1e-4 at K = 5 with +-1 charges)
  return std::max(1, static_cast<int>(std::floor(SLOW_INTERVAL / dt + 1e-9)));
}

const CoulombSetup* Engine::coulombSetup() const {
  return m_impl->coulomb ? &m_impl->slow_coulomb->setup() : nullptr;
}
int Engine::slowInterval() const { return m_impl->coulomb ? m_impl->slow.every : 0; }
std::int64_t Engine::slowEvaluations() const { return m_impl->slow_evaluations; }

void Engine::useCoulombDesign(double sum_q2_design) {
  Impl& d = *m_impl;
  if (!d.coulomb || d.slow_coulomb->setup().sum_q2_design == sum_q2_design) return;
  d.setupCoulomb(sum_q2_design);
  d.rebuildList(false);
}

}  // namespace granagg::md
