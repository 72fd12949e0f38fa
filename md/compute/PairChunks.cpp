#include "md/compute/PairChunks.h"

// CPU build only: the CUDA build compiles this folder with nvcc and never calls these.
#if !defined(GRANAGG_CUDA)

namespace granagg::md {

// Clones for AVX-512F, AVX2 and the baseline, chosen once, at load time, by the features of the
// machine that runs (an ifunc). Features, not "arch=" models: an "arch=haswell" clone is chosen
// on Intel Haswell and later only, and an AMD machine got the baseline. -ffp-contract=off
// (md/CMakeLists.txt) keeps fused multiply-adds out of the clones.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define GRANAGG_PAIR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define GRANAGG_PAIR_CLONES
#endif

// The loops below spell out, per component, Box::minimumImageWrapped as two selects (blends in
// SIMD): dx - L where dx > L/2, dx + L where dx < -L/2; (dx - 0) + 0 == dx for every dx but -0,
// which becomes +0 (a zero component either way, and a zero term in the caller's sums). And
// PairTable::operator() with the coefficients indexed from the table's start (the vectoriser
// gathers data[b + m], not c[m] off a gathered pointer). They are written out rather than called:
// helpers without the clones' target attributes are not inlined into them, and a call per entry
// keeps the loop scalar.
#define GRANAGG_MIN_IMAGE(dx) (((dx) - ((dx) > h ? L : 0.0)) + ((dx) < -h ? L : 0.0))

GRANAGG_PAIR_CLONES
void slowRealChunk(const PairChunkInput& in, double qi, double K, const PairTable& slow, double rc2,
                   double* __restrict out_x, double* __restrict out_y, double* __restrict out_z) {
  const double* __restrict p = &in.pos[0].x;
  const int* __restrict partners = in.partners;
  const double L = in.L, h = 0.5 * L, xi = in.xi, yi = in.yi, zi = in.zi;
  const double* __restrict data = slow.data;
  const double inv_h = slow.inv_h;
  const int n = in.n;
  for (int k = 0; k < n; ++k) {
    const int j4 = 4 * partners[k];
    const double dx = xi - p[j4], dy = yi - p[j4 + 1], dz = zi - p[j4 + 2];
    const double rx = GRANAGG_MIN_IMAGE(dx), ry = GRANAGG_MIN_IMAGE(dy), rz = GRANAGG_MIN_IMAGE(dz);
    const double r2 = rx * rx + ry * ry + rz * rz;
    const double qq = qi * p[j4 + 3];
    const double x = (r2 < rc2 ? r2 : 0.0) * inv_h;
    const int kt = static_cast<int>(x);
    const double t = x - kt;
    const int b = 4 * kt;
    const double g = data[b] + t * (data[b + 1] + t * (data[b + 2] + t * data[b + 3]));
    const double fr = K * (r2 < rc2 ? qq : 0.0) * g;
    out_x[k] = fr * rx;
    out_y[k] = fr * ry;
    out_z[k] = fr * rz;
  }
}

#undef GRANAGG_MIN_IMAGE

}  // namespace granagg::md

#endif  // !GRANAGG_CUDA
