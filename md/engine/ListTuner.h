#pragma once
/// \file ListTuner.h
/// The neighbour lists' tuner, as HOOMD-blue's SFCPackTuner and its neighbour-list autotuner are
/// objects of their own: it owns the choices that change no result, only the cost of the passes
/// and the builds.
/// - **Storage order.** At a build from cells the particles are re-stored in the list's cell
///   order (sortByCell), so that a particle's neighbours sit within a few hundred slots of it.
///   Rows are sorted by particle id, so forces, and hence trajectories, do not depend on it.
/// - **Skins that follow the gas** (md/neighbor/Skin.h): each list's skin is chosen at its build
///   from the largest drift per step of the last step (observe), the contact list's for one use
///   per step, the Coulomb list's for one use per slow interval. Before the first observation of
///   a process (also after a restart) the skins keep their caps, so a restart builds as the
///   uninterrupted run did at its start.
#include <initializer_list>

#include "common/Box.h"
#include "md/engine/ParticleData.h"
#include "md/neighbor/NeighborList.h"

namespace granagg::md {

/// How one list's skin is chosen (followingSkin's arguments, less the displacement).
struct SkinRule {
  bool follows = false;         ///< false: the list keeps the skin it was built with
  double reach = 0.0;           ///< the range the list serves (r in Skin.h)
  double build_over_use = 0.0;  ///< cost of a build over the cost of one use
  double min = 0.0, cap = 0.0;
};

class ListTuner {
 public:
  void setContactRule(const SkinRule& r) { m_contact = r; }
  void setCoulombRule(const SkinRule& r) { m_coulomb = r; }
  /// The largest drift speed max|u| of the step just taken.
  void observe(double u_max) { m_u_max = u_max; }

  /// Sets the skin of the contact list about to be rebuilt (a step of dt per use).
  void tuneContact(NeighborList& nl, double dt) const;
  /// Sets the skin of the Coulomb list about to be rebuilt (`every` steps of dt per use).
  void tuneCoulomb(NeighborList& nl, double dt, int every) const;

  /// Re-stores the particles of `p`, and the per-slot arrays `followers`, in `nl`'s cell order.
  /// The caller rebuilds the lists. Returns false if nothing was sorted (boxes too small for
  /// cells: all-pairs builds).
  bool sortByCell(NeighborList& nl, ParticleData& p, const common::Box& box,
                  std::initializer_list<DVec<double>*> followers);

 private:
  SkinRule m_contact, m_coulomb;
  double m_u_max = -1.0;  // < 0: no step observed in this process yet
  // permutation buffers, kept between sorts
  DVec<double> m_scratch_d;
  DVec<int> m_scratch_i;
  DVec<Scalar4> m_scratch4;
  DVec<Vec3> m_scratch3;
};

}  // namespace granagg::md
