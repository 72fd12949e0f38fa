/// \file ListTuner.cpp
/// The storage order and the following skins of the neighbour lists (ListTuner.h).
#include "md/engine/ListTuner.h"

#include <thrust/gather.h>

#include "md/neighbor/Skin.h"

namespace granagg::md {

namespace {
/// d = d[order] (storage permutation).
template <class T>
void permute(DVec<T>& d, const DVec<int>& order, DVec<T>& scratch) {
  scratch.resize(d.size());
  thrust::gather(order.begin(), order.end(), d.begin(), scratch.begin());
  d.swap(scratch);
}
}  // namespace

void ListTuner::tuneContact(NeighborList& nl, double dt) const {
  if (m_u_max < 0.0 || !m_contact.follows) return;
  nl.setSkin(followingSkin(m_contact.reach, dt * m_u_max, m_contact.build_over_use, m_contact.min,
                           m_contact.cap));
}

void ListTuner::tuneCoulomb(NeighborList& nl, double dt, int every) const {
  if (m_u_max < 0.0 || !m_coulomb.follows) return;
  nl.setSkin(followingSkin(m_coulomb.reach, every * (dt * m_u_max), m_coulomb.build_over_use,
                           m_coulomb.min, m_coulomb.cap));
}

bool ListTuner::sortByCell(NeighborList& nl, ParticleData& p, const common::Box& box,
                           std::initializer_list<DVec<double>*> followers) {
  const DVec<int>& order = nl.computeCellOrder(p, box);
  if (order.size() != p.size()) return false;  // all-pairs builds: nothing to sort
  permute(p.pos, order, m_scratch4);  // (dq is all zero here: applied by the kick pass before)
  for (auto* v : {&p.vel, &p.force}) permute(*v, order, m_scratch3);
  for (auto* v : followers) permute(*v, order, m_scratch_d);
  for (auto* v : {&p.ix, &p.iy, &p.iz, &p.id}) permute(*v, order, m_scratch_i);
  return true;
}

}  // namespace granagg::md
