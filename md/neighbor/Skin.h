#pragma once
/// \file Skin.h
/// Verlet skins that follow the gas (`neighbor.skin` and `coulomb.skin` = "auto"; docs/config.md,
/// docs/benchmarks-coulomb.md). A skin trades the cost of each use of a list against the cost of
/// rebuilding it. A list of range r + s whose every use costs in proportion to the volume it
/// covers, P(s) = P0 (1 + s / r)^3, and whose rebuild costs B, lasts until the fastest particle
/// may have moved s / 2: s / (2 delta) uses at a displacement bound delta per use. Per use it costs
///
///     P0 (1 + s / r)^3 (1 + c / s),   c = 2 delta B / P0,
///
/// which is smallest where 3 s^2 + 2 c s - r c = 0, at s* = (sqrt(c^2 + 3 r c) - c) / 3. A hot gas
/// (large delta) wants a long skin, a cold one a short skin: in the paper's charged gas at t = 700
/// the fastest particle moves 6e-4 d per step, and the contact list's skin falls from 0.3 to 0.06.
///
/// The skin changes no result: rows are in particle-id order and entries beyond a pass's cutoff
/// add exactly zero, so forces, and hence trajectories, are the same to the bit for any skin
/// (tests/md/test_coulomb_md.cpp, "skins that follow a cold gas are short and change no bit").
#include <cmath>

namespace granagg::md {

/// The skin s* above for range r, displacement bound delta per use and cost ratio B / P0, clamped
/// to [s_min, s_max] (s_max also when delta is not finite or not positive).
inline double followingSkin(double r, double delta, double build_over_use, double s_min,
                            double s_max) {
  if (!(delta > 0.0) || !std::isfinite(delta)) return s_max;
  const double c = 2.0 * delta * build_over_use;
  const double s = (std::sqrt(c * c + 3.0 * r * c) - c) / 3.0;
  return s < s_min ? s_min : (s > s_max ? s_max : s);
}

/// Cost of a rebuild over the cost of one use, measured on the charged gas of the paper's preset
/// (K = 5, Q = 0.05, N = 1e4, t = 700, 2 threads, granagg 7d93806): the contact list, refiltered
/// from the Coulomb list (about 4.6 ms), against one contact pass with its fast Coulomb pairs
/// (about 1.1 ms); the Coulomb list, a cell search and a sort (about 87 ms), against one slow
/// real-space pass (about 14 ms). The optimum is flat: a factor 2 in a ratio moves s* by about 1.4.
constexpr double CONTACT_LIST_BUILD_OVER_USE = 4.0;
constexpr double COULOMB_LIST_BUILD_OVER_USE = 6.0;
/// Bounds of the following skins: the caps are the fixed skins used before (`neighbor.skin` 0.3,
/// the Coulomb list's 0.8 with multiple time stepping); the floors keep a list from being rebuilt
/// at nearly every use when the gas is almost at rest.
constexpr double NEIGHBOR_SKIN_AUTO_MAX = 0.3;
constexpr double NEIGHBOR_SKIN_AUTO_MIN = 0.05;
constexpr double COULOMB_SKIN_AUTO_MAX = 0.8;
constexpr double COULOMB_SKIN_AUTO_MIN = 0.2;

}  // namespace granagg::md
