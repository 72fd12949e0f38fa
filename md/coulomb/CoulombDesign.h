#pragma once
/// \file CoulombDesign.h
/// The choice of a Coulomb solver's parameters for a configuration (docs/coulomb.md): the method's
/// splitting parameter, cutoff and mesh for the configured accuracy, the Coulomb list's skin, and
/// the near/far split of the multiple time stepping. A pure function of the configuration, the
/// system (N, L) and the sum q^2 it is designed for; the engine builds its solvers from the
/// result and stores the record (CoulombSetup) in checkpoints, so that a restart reuses it.
#include <cstddef>
#include <string>

#include "md/config/MdConfig.h"
#include "md/coulomb/EwaldParams.h"
#include "md/coulomb/RealSpace.h"

namespace granagg::md {

/// What the engine reports and a checkpoint records of its Coulomb set-up.
struct CoulombSetup {
  std::string method;            ///< "pppm" or "ewald"
  double alpha = 0.0;            ///< Ewald splitting parameter (1/d)
  double r_cut = 0.0;            ///< real-space cutoff (d)
  int mesh = 0, order = 0;       ///< PPPM mesh points per side, assignment order
  int k_max = 0;                 ///< plain Ewald reciprocal cutoff
  double estimated_error = 0.0;  ///< estimated relative RMS force error at sum_q2_design
  double sum_q2_design = 0.0;    ///< sum q^2 the parameters were chosen for
  double r_fast =
      0.0;  ///< multiple time stepping: real space within this is fast (switched over 1 d); 0: none
  int every = 1;  ///< multiple time stepping: steps between evaluations of the slow part
  /// > every: the interval follows the gas up to this many steps (coulomb.every_max);
  /// = every: fixed
  int every_max = 1;
};

/// `coulomb.r_fast = "auto"`: the pair force within 2 d is fast. At 2 d the ensemble of the
/// paper's K = 5 gas is indistinguishable from the tight reference and the cold gas runs
/// 1.5x faster; energy drift 4x that of 3.5 d, 0.1 % of the cold gas's dissipation
/// (docs/coulomb.md, docs/benchmarks-coulomb.md).
constexpr double R_FAST_AUTO = 2.0;

/// The parameters of the Coulomb solvers for one configuration.
struct CoulombDesign {
  CoulombSetup setup;
  PppmParams pppm;                       ///< method "pppm"
  EwaldParams ewald;                     ///< method "ewald"
  double coulomb_skin = 0.0;             ///< skin of the Coulomb (r_cut) list, pppm only; with
                                         ///< coulomb_skin_follows its largest value
  bool coulomb_skin_follows = false;     ///< "auto" with every > 1: the skin follows the gas
  RealSpaceSwitch fast_switch;           ///< the near/far split; r2 = 0: none
  double contact_list_cutoff = 1.0;      ///< the contact list's reach: max(1, r_fast)
  bool contact_list_keeps_pairs = true;  ///< false when every entry has fast Coulomb work
};

/// Chooses the parameters for `config` at N particles in a box of edge L, designed for
/// sum_q2_design. `contact_skin` is the contact list's skin; `every` and `every_max` the
/// multiple time stepping's base interval and cap (every = 1: none). Throws
/// std::invalid_argument naming the key when the box or the cutoffs do not allow the request.
CoulombDesign designCoulomb(const CoulombConfig& config, std::size_t N, double L,
                            double contact_skin, int every, int every_max, double sum_q2_design);

}  // namespace granagg::md
