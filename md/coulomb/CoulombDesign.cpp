/// \file CoulombDesign.cpp
/// The Coulomb parameters of a configuration (CoulombDesign.h).
#include "md/coulomb/CoulombDesign.h"

#include <algorithm>
#include <stdexcept>

#include "common/Csv.h"
#include "md/neighbor/Skin.h"

namespace granagg::md {

CoulombDesign designCoulomb(const CoulombConfig& cc, std::size_t N, double L, double skin,
                            int every_base, int every_cap, double sum_q2_design) {
  CoulombDesign d;
  CoulombSetup& cs = d.setup;
  cs.method = cc.method;
  cs.sum_q2_design = sum_q2_design;
  if (cc.method != "pppm") {
    d.ewald = chooseEwaldParams(cc.accuracy, N, L, sum_q2_design, cc.r_cut);
    cs.alpha = d.ewald.alpha;
    cs.r_cut = d.ewald.r_cut;
    cs.k_max = d.ewald.k_max;
    cs.estimated_error = d.ewald.estimatedError();
    return d;
  }
  // "auto": a longer skin than the contact list's when the list is used every k-th step only
  // (fewer builds of a long list; measured optimum at N = 1e4, K = 5:
  // docs/benchmarks-coulomb.md)
  d.coulomb_skin = cc.skin > 0.0 ? cc.skin : (every_base > 1 ? COULOMB_SKIN_AUTO_MAX : skin);
  d.coulomb_skin_follows = cc.skin == 0.0 && every_base > 1;
  const double rc_max = 0.5 * L - d.coulomb_skin;  // the list must reach r_cut + skin within L/2
  if (cc.r_cut > rc_max)
    throw std::invalid_argument("coulomb.r_cut = " + common::formatReal(cc.r_cut) +
                                " exceeds L/2 - coulomb.skin = " + common::formatReal(rc_max) +
                                " for this box (L = " + common::formatReal(L) + ")");
  PppmParams& prm = d.pppm;
  if (cc.r_cut > 0.0) {
    prm = choosePppmParams(cc.accuracy, N, L, sum_q2_design, cc.r_cut, cc.order > 0 ? cc.order : 5);
  } else {
    if (!(rc_max >= 1.0))
      throw std::invalid_argument("box too small for PPPM with this coulomb.skin (L/2 - skin < 1)");
    prm = optimizePppmParams(cc.accuracy, N, L, sum_q2_design, 1.0, rc_max);
    if (cc.order > 0 && cc.order != prm.order)
      prm = choosePppmParams(cc.accuracy, N, L, sum_q2_design, prm.r_cut, cc.order);
  }
  if (cc.mesh > 0) {  // a mesh given explicitly overrides the chosen one (its error is reported)
    prm.mesh = cc.mesh;
    prm.estimated_error_kspace =
        pppmKspaceError(prm.alpha, prm.mesh, prm.order, N, L, sum_q2_design);
  }
  cs.alpha = prm.alpha;
  cs.r_cut = prm.r_cut;
  cs.mesh = prm.mesh;
  cs.order = prm.order;
  cs.estimated_error = prm.estimatedError();
  // multiple time stepping: the near real space, which changes as fast as pairs approach, is
  // computed at every step in the contact pass (its list then reaches r_fast), the rest is slow
  if (every_base > 1) {
    const double r2 = std::min(cc.r_fast > 0.0 ? cc.r_fast : R_FAST_AUTO, prm.r_cut);
    if (r2 < 2.0)
      throw std::invalid_argument("coulomb.r_cut = " + common::formatReal(prm.r_cut) +
                                  " leaves coulomb.r_fast = " + common::formatReal(r2) +
                                  " < 2 for the multiple time stepping (coulomb.every > 1): "
                                  "use a larger r_cut or coulomb.every = 1");
    d.fast_switch = RealSpaceSwitch{std::max(0.0, r2 - 1.0), r2};
    cs.r_fast = r2;
    cs.every = every_base;
    cs.every_max = every_cap;
  }
  d.contact_list_cutoff = std::max(1.0, d.fast_switch.r2);
  // with a fast Coulomb part every entry has work: per-row loops
  d.contact_list_keeps_pairs = d.fast_switch.r2 == 0.0;
  return d;
}

}  // namespace granagg::md
