/// \file EngineLists.cpp
/// Engine::Impl's neighbour lists: the storage re-sorted in cell order at a build, the builds of
/// the contact list (alone, or filtered from the Coulomb list while that still covers it) and of
/// the Coulomb list. The storage order and the skins are the tuner's (ListTuner.h).
#include "md/engine/EngineImpl.h"

namespace granagg::md {

void Engine::Impl::rebuildList(bool sort) {
  PhaseTimer::Scope phase(&timer, nl_coul ? PhaseTimer::CoulombList : PhaseTimer::ContactList);
  tuner.tuneContact(nl, dt);
  if (nl_coul) tuner.tuneCoulomb(*nl_coul, dt, slow.every);
  // the Coulomb forces, used until the next evaluation, follow their particles
  const bool sorted =
      sort && (coulomb ? tuner.sortByCell(nl, p, box,
                                          {&slow_coulomb->force(0), &slow_coulomb->force(1),
                                           &slow_coulomb->force(2)})
                       : tuner.sortByCell(nl, p, box, {}));
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
  tuner.tuneContact(nl, dt);
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

}  // namespace granagg::md
