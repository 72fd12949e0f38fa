#pragma once
/// \file PairChunks.h
/// The per-entry arithmetic of the slow real-space pair loop (CoulombRealSpace.cpp, its longest
/// rows: about 250 entries per particle in the cold charged gas), for a chunk of one particle's
/// row at a time, in a form the compiler vectorises: each entry's force terms are written to
/// buffers, and the caller sums them in row order. The sum's order, and every operation of each
/// term, are the scalar loop's, so results are the same to the bit on every instruction set
/// (docs/benchmarks-coulomb.md, "The slow real space in SIMD"). The contact pass's fast pairs
/// (about 30 entries per particle) are not treated so: their ordered sum and their contacts, not
/// the terms, bound that loop (docs/benchmarks-coulomb.md, "Contact pass in the cold clustered
/// gas").
///
/// CPU build only (the CUDA build runs the pair loops per thread on the device). PairChunks.cpp
/// is compiled for several x86-64 levels and picks one at run time (GCC's target_clones); it is
/// compiled with -ffp-contract=off, so that no clone fuses a multiply and an add into one rounding
/// that the baseline's separate roundings do not, and -fno-trapping-math, which lets the compiler
/// turn the minimum image's selects into blends (it changes no value).
#include "md/coulomb/RealSpace.h"
#include "md/engine/ParticleData.h"

namespace granagg::md {

/// Entries in one chunk (the callers' buffers).
constexpr int PAIR_CHUNK = 64;

/// One particle's view of a chunk of its row: r_i, the box, and the first n <= PAIR_CHUNK
/// partner slots.
struct PairChunkInput {
  const Scalar4* pos;  ///< all positions (x, y, z) and charges (w)
  const int* partners;
  int n;
  double xi, yi, zi;
  double L;  ///< box edge; positions lie in [0, L)
};

/// Slow real-space pairs (RealForceFunctor<true>): fr = K (r^2 < rc2 ? q_i q_j : 0)
/// slow(r^2 < rc2 ? r^2 : 0), out_x[k] = fr r_x ...
void slowRealChunk(const PairChunkInput& in, double qi, double K, const PairTable& slow, double rc2,
                   double* out_x, double* out_y, double* out_z);

}  // namespace granagg::md
