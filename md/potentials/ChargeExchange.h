#pragma once
/// \file ChargeExchange.h
/// Collisional charging (docs/model.md section 7): at the first step of a
/// contact between particles a and b, a charge
///
///     |dq| = Q [Psi1 m_eff xi'^2]^(kappa + Psi2),   m_eff = 1/2,
///     Psi1 ~ U[psi1_min, psi1_max],  Psi2 ~ U[-psi2_half_width, +psi2_half_width]
///
/// moves from one partner to the other, either way with probability 1/2. xi' is the normal
/// approach speed at that step.
///
/// Random numbers: Philox keyed by the run's seed with the counter (stream, step, min id, max id),
/// so both partners of a pair draw the same numbers without talking to each other: each thread
/// updates only its own particle's charge (no atomics), the pair's total is unchanged, and CPU and
/// GPU builds give the same charges (RngStreams.h).
#include <cmath>
#include <cstdint>

#include "common/HostDevice.h"
#include "md/rng/RngStreams.h"

namespace granagg::md {

struct ChargeExchange {
  struct Params {
    std::uint64_t seed = 1;
    double Q = 1.0;
    double kappa = 0.83;
    double psi1_min = 0.1, psi1_max = 3.1623;
    double psi2_half_width = 0.05 * 0.83;  ///< psi2_fraction * kappa
    double m_eff = 0.5;
  };

  /// The charge gained by the partner with the smaller particle id at a collision of the pair
  /// (id_lo < id_hi) at `step` with approach speed xi_dot (> 0); the other partner gains minus it.
  /// Grazing or receding pairs (xi_dot <= 0) exchange nothing.
  HD static double transferToLower(const Params& p, std::int64_t step, std::uint32_t id_lo,
                                   std::uint32_t id_hi, double xi_dot) {
    if (!(xi_dot > 0.0)) return 0.0;
    // the step's high bits go into the stream word (above the 8-bit stream id): unique counters
    // for 2^56 steps
    const std::uint64_t s = static_cast<std::uint64_t>(step);
    const auto r =
        philoxDraw(p.seed, RNG_CHARGE_EXCHANGE | static_cast<std::uint32_t>((s >> 32) << 8),
                   static_cast<std::uint32_t>(s), id_lo, id_hi);
    const double psi1 = p.psi1_min + (p.psi1_max - p.psi1_min) * uniform01(r[0]);
    const double psi2 = p.psi2_half_width * (2.0 * uniform01(r[1]) - 1.0);
    const double magnitude = p.Q * pow(psi1 * p.m_eff * xi_dot * xi_dot, p.kappa + psi2);
    return (r[2] & 1u) ? magnitude : -magnitude;
  }

  /// The charge particle `self` gains at its collision with `other` (ids), as above.
  HD static double transferTo(const Params& p, std::int64_t step, std::uint32_t self,
                              std::uint32_t other, double xi_dot) {
    return self < other ? transferToLower(p, step, self, other, xi_dot)
                        : -transferToLower(p, step, other, self, xi_dot);
  }
};

}  // namespace granagg::md
