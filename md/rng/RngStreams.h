#pragma once
/// \file RngStreams.h
/// Counter-based random numbers (Random123 Philox4x32-10; Salmon et al., SC'11): no stored state,
/// key = (seed low, seed high), counter = (stream id, a, b, c). Results do not depend on thread
/// order or backend, so CPU and GPU builds draw the same numbers (docs/model.md section 7). Every
/// stream id is listed here, like HOOMD's RNGIdentifiers.h.
#include <cstdint>

#include <Random123/philox.h>
#include <Random123/uniform.hpp>

#include "common/HostDevice.h"

namespace granagg::md {

enum RngStream : std::uint32_t {
  RNG_INIT_POSITION = 0x11,    ///< (particle, attempt): random insertion
  RNG_INIT_VELOCITY = 0x12,    ///< (particle): Maxwell velocities
  RNG_INIT_CHARGE = 0x13,      ///< (particle): which half of a bipolar initial state is positive
  RNG_CHARGE_EXCHANGE = 0x21,  ///< (step, min id, max id): collisional charging; the step's high
                               ///< 32 bits sit above the 8-bit stream id (ChargeExchange.h)
};

/// Four 32-bit random words for (seed, stream, a, b, c).
HD inline r123::Philox4x32::ctr_type philoxDraw(std::uint64_t seed, std::uint32_t stream,
                                                std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  r123::Philox4x32 rng;
  r123::Philox4x32::key_type key = {
      {static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)}};
  r123::Philox4x32::ctr_type ctr = {{stream, a, b, c}};
  return rng(ctr, key);
}

/// Uniform double in (0, 1] from a 32-bit word (Random123 u01: never returns 0, safe for log).
HD inline double uniform01(std::uint32_t w) { return r123::u01<double>(w); }

}  // namespace granagg::md
