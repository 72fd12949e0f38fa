#include "md/compute/CoulombRealSpace.h"

#include <stdexcept>

#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/transform.h>
#include <thrust/transform_reduce.h>

#include "md/compute/PairChunks.h"
#include "md/coulomb/RealSpace.h"
#include "md/engine/Launch.h"

namespace granagg::md {

namespace {

template <bool TABLE>
struct RealForceFunctor {
  const Scalar4* pos;
  const int *rows, *counts;
  int cap;
  common::Box box;
  double K, alpha, rc2;
  RealSpaceSwitch sw;  // the slow part: minus the fast S(r) K q_i q_j / r^2
  PairTable table;     // TABLE: the same, tabulated
  double *fx, *fy, *fz;
  HD int operator()(int i) const {
    const Scalar4 ri = pos[i];
    double f0 = 0.0, f1 = 0.0, f2 = 0.0;
    if (ri.w != 0.0) {  // (an exchanging gas starts neutral)
      const int* row = rows + static_cast<long>(i) * cap;
      const int n = counts[i];
#if !defined(GRANAGG_CUDA)
      if (TABLE) {  // CPU: in chunks, the terms in SIMD where possible (md/compute/PairChunks.h)
        double tx[PAIR_CHUNK], ty[PAIR_CHUNK], tz[PAIR_CHUNK];
        for (int k0 = 0; k0 < n; k0 += PAIR_CHUNK) {
          const int m = n - k0 < PAIR_CHUNK ? n - k0 : PAIR_CHUNK;
          slowRealChunk(PairChunkInput{pos, row + k0, m, ri.x, ri.y, ri.z, box.L}, ri.w, K, table,
                        rc2, tx, ty, tz);
          for (int k = 0; k < m; ++k) {  // in row order, as the loop below
            f0 += tx[k];
            f1 += ty[k];
            f2 += tz[k];
          }
        }
        fx[i] = f0;
        fy[i] = f1;
        fz[i] = f2;
        return 0;
      }
#endif
      for (int k = 0; k < n; ++k) {
        const Scalar4 rj = pos[row[k]];
        const double rx = box.minimumImageWrapped(ri.x - rj.x),
                     ry = box.minimumImageWrapped(ri.y - rj.y),
                     rz = box.minimumImageWrapped(ri.z - rj.z);
        const double r2 = rx * rx + ry * ry + rz * rz;
        const double qq = ri.w * rj.w;
        if (TABLE) {  // branch-free: about half of the list's entries lie beyond r_cut,
                      // unpredictably
          const double fr = K * (r2 < rc2 ? qq : 0.0) * table(r2 < rc2 ? r2 : 0.0);
          f0 += fr * rx;
          f1 += fr * ry;
          f2 += fr * rz;
        } else if (r2 < rc2 && qq != 0.0) {
          double fr;
          if (TABLE) {
            fr = K * qq * table(r2);  // (r2 < rc2: inside the table)
          } else {
            const double r = sqrt(r2);
            fr = ewaldRealForceOverRFast(qq, r, alpha, K) - sw.fastFraction(r) * K * qq / (r2 * r);
          }
          f0 += fr * rx;
          f1 += fr * ry;
          f2 += fr * rz;
        }
      }
    }
    fx[i] = f0;
    fy[i] = f1;
    fz[i] = f2;
    return 0;
  }
};

/// The energy of the pairs (i, j) of i's row with id_j > id_i: each pair once (one erfc per pair,
/// not two), and by particle id, so that the per-particle terms, summed in id order, do not depend
/// on the storage order.
struct RealEnergyFunctor {
  const Scalar4* pos;
  const int *rows, *counts, *id;
  int cap;
  common::Box box;
  double K, alpha, rc2;
  PairTable table;  // erfc(alpha r) / r, or null
  HD double operator()(int i) const {
    const Scalar4 ri = pos[i];
    const int id_i = id[i];
    double e = 0.0;
    const int* row = rows + static_cast<long>(i) * cap;
    for (int k = 0; k < counts[i]; ++k) {
      const int j = row[k];
      if (id[j] <= id_i) continue;
      const Scalar4 rj = pos[j];
      const double rx = box.minimumImageWrapped(ri.x - rj.x),
                   ry = box.minimumImageWrapped(ri.y - rj.y),
                   rz = box.minimumImageWrapped(ri.z - rj.z);
      const double r2 = rx * rx + ry * ry + rz * rz;
      if (!(r2 < rc2)) continue;
      if (table.data && r2 >= ENERGY_TABLE_R2_MIN)
        e += K * ri.w * rj.w * table(r2);
      else
        e += ewaldRealEnergy(ri.w * rj.w, sqrt(r2), alpha, K);
    }
    return e;
  }
};

void checkRange(const NeighborList& nl, const CoulombRealParams& prm) {
  if (nl.listRange() < prm.r_cut)
    throw std::logic_error("neighbour list range below the Coulomb real-space cutoff");
}

}  // namespace

void coulombRealForces(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                       const CoulombRealParams& prm, DVec<double>& fx, DVec<double>& fy,
                       DVec<double>& fz) {
  checkRange(nl, prm);
  const int N = static_cast<int>(p.size());
  for (auto* v : {&fx, &fy, &fz}) v->resize(p.size());
  if (prm.table.data)
    forEachBlocked(N, blockSizeFor(N),
                   RealForceFunctor<true>{raw(p.pos), nl.rows(), nl.counts(), nl.capacity(), box,
                                          prm.K, prm.alpha, prm.r_cut * prm.r_cut, prm.fast,
                                          prm.table, raw(fx), raw(fy), raw(fz)},
                   NoReduction{}, static_cast<int*>(nullptr));
  else
    forEachBlocked(N, blockSizeFor(N),
                   RealForceFunctor<false>{raw(p.pos), nl.rows(), nl.counts(), nl.capacity(), box,
                                           prm.K, prm.alpha, prm.r_cut * prm.r_cut, prm.fast,
                                           prm.table, raw(fx), raw(fy), raw(fz)},
                   NoReduction{}, static_cast<int*>(nullptr));
}

double coulombRealEnergy(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                         const CoulombRealParams& prm) {
  checkRange(nl, prm);
  const int N = static_cast<int>(p.size());
  DVec<double> per_slot(p.size());
  thrust::transform(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N),
                    per_slot.begin(),
                    RealEnergyFunctor{raw(p.pos), nl.rows(), nl.counts(), raw(p.id), nl.capacity(),
                                      box, prm.K, prm.alpha, prm.r_cut * prm.r_cut,
                                      prm.energy_table});
  return reduceById(per_slot, p.id, 0.0, thrust::plus<double>());  // restart: same bits
}

}  // namespace granagg::md
