/// \file EngineCoulomb.cpp
/// The engine's Coulomb part (Engine.h, "multiple time stepping"): setting up the solvers,
/// evaluating the slow force and choosing its interval, and the Coulomb energy for observables.
#include "md/engine/Engine.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <thrust/for_each.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/transform_reduce.h>

#include "md/engine/EngineImpl.h"

namespace granagg::md {

using engine_detail::toDevice;
using engine_detail::toHost;

namespace {
/// |u|^2 of a velocity (the fastest particle, for the slow interval that follows the gas)
struct Speed2 {
  HD double operator()(const Vec3& u) const { return u.x * u.x + u.y * u.y + u.z * u.z; }
};

// coulomb.every = "auto": time between evaluations of the slow Coulomb part (Engine::coulombEvery)
constexpr double SLOW_INTERVAL = 0.016;

struct AddScaled {  // a[i] += c (x, y, z)[i]
  Vec3* a;
  const double *x, *y, *z;
  double c;
  HD void operator()(int i) const {
    a[i].x += c * x[i];
    a[i].y += c * y[i];
    a[i].z += c * z[i];
  }
};
}  // namespace

void Engine::Impl::setupCoulomb(double sum_q2_design) {
  const CoulombConfig& cc = cfg.coulomb;
  const std::size_t N = p.size();
  const double L = box.L, skin = cfg.neighbor.skinCap();
  const CoulombDesign d =
      designCoulomb(cc, N, L, skin, slow.design_base, slow.design_cap, sum_q2_design);
  csetup = d.setup;
  fast_switch = d.fast_switch;
  pppm.reset();
  ewald.reset();
  nl_coul.reset();
  slow_table.clear();
  fast_table.clear();
  energy_table.clear();
  if (cc.method == "pppm") {
    pppm = std::make_unique<Pppm>(d.pppm, L, cc.K);
    pppm->setPhaseTimer(&timer);
    nl_coul = std::make_unique<NeighborList>(d.pppm.r_cut, d.coulomb_skin);
    coulomb_skin_cap = d.coulomb_skin;
    coulomb_skin_follows = d.coulomb_skin_follows;
    const auto e = energyPairTableValues(d.pppm.alpha, d.pppm.r_cut * d.pppm.r_cut);
    energy_table.assign(e.begin(), e.end());
    if (fast_switch.r2 > 0.0) {
      const auto t = slowPairTableValues(d.pppm.alpha, fast_switch, d.pppm.r_cut * d.pppm.r_cut);
      slow_table.assign(t.begin(), t.end());
      const auto f = fastPairTableValues(fast_switch);
      fast_table.assign(f.begin(), f.end());
    }
  } else {
    ewald = std::make_unique<EwaldReference>(d.ewald, L, cc.K);
  }
  nl = NeighborList(d.contact_list_cutoff, skin);
  nl.keepPairs(d.contact_list_keeps_pairs);
  contact_skin_follows = cfg.neighbor.skin == 0.0 && fast_switch.r2 > 0.0;
  for (auto* v : {&ext_fx, &ext_fy, &ext_fz}) v->assign(N, 0.0);
  slow.eval_step = -1;
}

CoulombRealParams Engine::Impl::realParams() const {
  CoulombRealParams prm{cfg.coulomb.K, csetup.alpha, csetup.r_cut, fast_switch};
  if (!slow_table.empty())
    prm.table = pairTable(raw(slow_table), csetup.r_cut * csetup.r_cut, SLOW_PAIR_TABLE_INTERVALS);
  if (!energy_table.empty())
    prm.energy_table =
        pairTable(raw(energy_table), csetup.r_cut * csetup.r_cut, ENERGY_PAIR_TABLE_INTERVALS);
  return prm;
}

CoulombResult Engine::Impl::ewaldOnHost() const {
  const auto pos = toHost(p.pos);
  std::vector<double> x(pos.size()), y(pos.size()), z(pos.size()), q(pos.size());
  for (std::size_t i = 0; i < pos.size(); ++i)
    x[i] = pos[i].x, y[i] = pos[i].y, z[i] = pos[i].z, q[i] = pos[i].w;
  return ewald->compute(x, y, z, q);
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
  const std::size_t N = p.size();
  ++slow_evaluations;
  if (pppm) {
    {
      PhaseTimer::Scope phase(&timer, PhaseTimer::CoulombReal);
      coulombRealForces(p, *nl_coul, box, realParams(), ext_fx, ext_fy, ext_fz);
    }
    coulomb_ext_energy = pppm->compute(reinterpret_cast<const double*>(raw(p.pos)), N, raw(ext_fx),
                                       raw(ext_fy), raw(ext_fz), raw(p.id));
    return;
  }
  // the plain-Ewald reference: all of its evaluation counts as the slow real space
  PhaseTimer::Scope phase(&timer, PhaseTimer::CoulombReal);
  const CoulombResult r = ewaldOnHost();
  toDevice(r.fx, ext_fx);
  toDevice(r.fy, ext_fy);
  toDevice(r.fz, ext_fz);
  coulomb_ext_energy = r.energy;
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

void Engine::Impl::addSlow(DVec<Vec3>& a, double c) {
  if (c == 0.0) return;
  thrust::for_each(thrust::counting_iterator<int>(0),
                   thrust::counting_iterator<int>(static_cast<int>(a.size())),
                   AddScaled{raw(a), raw(ext_fx), raw(ext_fy), raw(ext_fz), c});
}

void Engine::Impl::slowBoundsForStep() {
  if (coulomb) slow.boundsFor(dt);
}

double Engine::Impl::coulombEnergyNow() {
  if (!coulomb) return 0.0;
  if (pppm) {
    if (nl_coul->needsRebuild(p, drift_since_coul_build * drift_since_coul_build)) {
      chooseSkins(false, true);
      nl_coul->build(p, box);
      drift_since_coul_build = 0.0;
    }
    double ext = coulomb_ext_energy;
    if (slow.eval_step != step)  // the energy alone: no forces
      ext = pppm->compute(reinterpret_cast<const double*>(raw(p.pos)), p.size(), nullptr, nullptr,
                          nullptr, raw(p.id));
    return coulombRealEnergy(p, *nl_coul, box, realParams()) + ext;
  }
  if (slow.eval_step == step) return coulomb_ext_energy;
  return ewaldOnHost().energy;
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
  return m_impl->coulomb ? &m_impl->csetup : nullptr;
}
int Engine::slowInterval() const { return m_impl->coulomb ? m_impl->slow.every : 0; }
std::int64_t Engine::slowEvaluations() const { return m_impl->slow_evaluations; }

void Engine::useCoulombDesign(double sum_q2_design) {
  Impl& d = *m_impl;
  if (!d.coulomb || d.csetup.sum_q2_design == sum_q2_design) return;
  d.setupCoulomb(sum_q2_design);
  d.rebuildList(false);
}

}  // namespace granagg::md
