/// \file EngineLists.cpp
/// Engine::Impl's neighbour lists: the storage re-sorted in cell order at a build, the builds of
/// the contact list (alone, or filtered from the Coulomb list while that still covers it) and of
/// the Coulomb list, and the skins that follow the gas (md/neighbor/Skin.h: each list's skin is
/// chosen at its build from the largest drift per step, so that builds stay rare without rows
/// longer than needed).
#include <thrust/gather.h>

#include "md/engine/EngineImpl.h"
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

bool Engine::Impl::sortByCell() {
  const DVec<int>& order = nl.computeCellOrder(p, box);
  if (order.size() != p.size()) return false;  // all-pairs builds: nothing to sort
  permute(p.pos, order, scratch4);  // (dq is all zero here: applied by the kick pass before)
  for (auto* v : {&p.vel, &p.force}) permute(*v, order, scratch3);
  if (coulomb)  // the Coulomb forces, used until the next evaluation, follow their particles
    for (int a = 0; a < 3; ++a) permute(slow_coulomb->force(a), order, scratch_d);
  for (auto* v : {&p.ix, &p.iy, &p.iz, &p.id}) permute(*v, order, scratch_i);
  return true;
}

void Engine::Impl::rebuildList(bool sort) {
  PhaseTimer::Scope phase(&timer, nl_coul ? PhaseTimer::CoulombList : PhaseTimer::ContactList);
  chooseSkins(true, true);
  const bool sorted = sort && sortByCell();
  if (nl_coul) {
    nl_coul->build(p, box);
    drift_since_coul_build = 0.0;
    nl.buildFrom(*nl_coul, p, box);
  } else if (sorted) {
    nl.buildSorted(p, box);  // the storage is in nl's cell order now
  } else {
    nl.build(p, box);
  }
  drift_since_build = 0.0;
}

void Engine::Impl::rebuildContactList() {
  chooseSkins(true, false);
  if (!nl_coul) {
    rebuildList(true);
  } else if (nl.listRange() <= nl_coul->listRange() - 2.0 * drift_since_coul_build) {
    PhaseTimer::Scope phase(&timer, PhaseTimer::ContactList);
    nl.buildFrom(*nl_coul, p, box);
    drift_since_build = 0.0;
  } else {
    rebuildList(true);
  }
}

void Engine::Impl::chooseSkins(bool contact_list, bool coulomb_list) {
  if (u_max_last < 0.0) return;
  const double delta = dt * u_max_last;
  if (contact_list && contact_skin_follows)
    nl.setSkin(followingSkin(slow_coulomb->fastSwitch().r2, delta, CONTACT_LIST_BUILD_OVER_USE,
                             NEIGHBOR_SKIN_AUTO_MIN, cfg.neighbor.skinCap()));
  if (coulomb_list && nl_coul && coulomb_skin_follows)
    nl_coul->setSkin(followingSkin(slow_coulomb->setup().r_cut, slow.every * delta,
                                   COULOMB_LIST_BUILD_OVER_USE, COULOMB_SKIN_AUTO_MIN,
                                   coulomb_skin_cap));
}

}  // namespace granagg::md
