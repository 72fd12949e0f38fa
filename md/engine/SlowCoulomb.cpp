#include "md/engine/SlowCoulomb.h"

#include <thrust/copy.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>

namespace granagg::md {

namespace {
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

SlowCoulomb::SlowCoulomb(const CoulombDesign& d, const CoulombConfig& config, double L,
                         std::size_t n, PhaseTimer* timer)
    : m_setup(d.setup), m_K(config.K), m_fast_switch(d.fast_switch) {
  if (config.method == "pppm") {
    m_pppm = std::make_unique<Pppm>(d.pppm, L, config.K);
    m_pppm->setPhaseTimer(timer);
    const auto e = energyPairTableValues(d.pppm.alpha, d.pppm.r_cut * d.pppm.r_cut);
    m_energy_table.assign(e.begin(), e.end());
    if (m_fast_switch.r2 > 0.0) {
      const auto t = slowPairTableValues(d.pppm.alpha, m_fast_switch, d.pppm.r_cut * d.pppm.r_cut);
      m_slow_table.assign(t.begin(), t.end());
      const auto f = fastPairTableValues(m_fast_switch);
      m_fast_table.assign(f.begin(), f.end());
    }
  } else {
    m_ewald = std::make_unique<EwaldReference>(d.ewald, L, config.K);
  }
  for (auto& f : m_f) f.assign(n, 0.0);
}

bool SlowCoulomb::fastTable(PairTable& table) const {
  if (m_fast_table.empty()) return false;
  table = pairTable(raw(m_fast_table), m_fast_switch.r2 * m_fast_switch.r2,
                    FAST_PAIR_TABLE_INTERVALS);
  return true;
}

CoulombRealParams SlowCoulomb::realParams() const {
  CoulombRealParams prm{m_K, m_setup.alpha, m_setup.r_cut, m_fast_switch};
  if (!m_slow_table.empty())
    prm.table =
        pairTable(raw(m_slow_table), m_setup.r_cut * m_setup.r_cut, SLOW_PAIR_TABLE_INTERVALS);
  if (!m_energy_table.empty())
    prm.energy_table =
        pairTable(raw(m_energy_table), m_setup.r_cut * m_setup.r_cut, ENERGY_PAIR_TABLE_INTERVALS);
  return prm;
}

CoulombResult SlowCoulomb::ewaldOnHost(const ParticleData& p) const {
  std::vector<Scalar4> pos(p.pos.size());
  thrust::copy(p.pos.begin(), p.pos.end(), pos.begin());
  std::vector<double> x(pos.size()), y(pos.size()), z(pos.size()), q(pos.size());
  for (std::size_t i = 0; i < pos.size(); ++i)
    x[i] = pos[i].x, y[i] = pos[i].y, z[i] = pos[i].z, q[i] = pos[i].w;
  return m_ewald->compute(x, y, z, q);
}

void SlowCoulomb::evaluate(const ParticleData& p, const NeighborList* list,
                           const common::Box& box, PhaseTimer* timer) {
  if (m_pppm) {
    {
      PhaseTimer::Scope phase(timer, PhaseTimer::CoulombReal);
      coulombRealForces(p, *list, box, realParams(), m_f[0], m_f[1], m_f[2]);
    }
    m_energy = m_pppm->compute(reinterpret_cast<const double*>(raw(p.pos)), p.size(),
                               raw(m_f[0]), raw(m_f[1]), raw(m_f[2]), raw(p.id));
    return;
  }
  // the plain-Ewald reference: all of its evaluation counts as the slow real space
  PhaseTimer::Scope phase(timer, PhaseTimer::CoulombReal);
  const CoulombResult r = ewaldOnHost(p);
  m_f[0].assign(r.fx.begin(), r.fx.end());
  m_f[1].assign(r.fy.begin(), r.fy.end());
  m_f[2].assign(r.fz.begin(), r.fz.end());
  m_energy = r.energy;
}

double SlowCoulomb::energyNow(const ParticleData& p, const NeighborList* list,
                              const common::Box& box, bool evaluated_here) const {
  if (m_pppm) {
    const double ext =
        evaluated_here ? m_energy
                       : m_pppm->compute(reinterpret_cast<const double*>(raw(p.pos)), p.size(),
                                         nullptr, nullptr, nullptr, raw(p.id));  // energy alone
    return coulombRealEnergy(p, *list, box, realParams()) + ext;
  }
  return evaluated_here ? m_energy : ewaldOnHost(p).energy;
}

void SlowCoulomb::restore(const std::vector<double>& fx, const std::vector<double>& fy,
                          const std::vector<double>& fz, double energy) {
  m_f[0].assign(fx.begin(), fx.end());
  m_f[1].assign(fy.begin(), fy.end());
  m_f[2].assign(fz.begin(), fz.end());
  m_energy = energy;
}

void SlowCoulomb::addScaled(DVec<Vec3>& a, double c) const {
  if (c == 0.0) return;
  thrust::for_each(thrust::counting_iterator<int>(0),
                   thrust::counting_iterator<int>(static_cast<int>(a.size())),
                   AddScaled{raw(a), raw(m_f[0]), raw(m_f[1]), raw(m_f[2]), c});
}

}  // namespace granagg::md
