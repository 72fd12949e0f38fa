#include "md/integrate/VelocityVerlet.h"

#include <thrust/for_each.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>

#include "md/engine/Launch.h"

namespace granagg::md {

namespace {
struct MaxReduction {
  using value_type = double;
  HD static double identity() { return 0.0; }
  HD double operator()(double a, double b) const { return a > b ? a : b; }
};

struct KickDrift {
  Scalar4* pos;
  Vec3* vel;
  const Vec3* force;
  int *ix, *iy, *iz;
  double* dq;
  double h, dt;
  bool close_pending;
  common::Box box;
  /// returns |u|^2 of the drift velocity
  HD double operator()(int i) const {
    return kickDriftParticle(box, h, dt, close_pending, force[i], vel[i], pos[i],
                             dq ? dq + i : nullptr, ix[i], iy[i], iz[i], vel[i], pos[i]);
  }
};

struct CloseKick {
  Vec3* vel;
  const Vec3* force;
  Scalar4* pos;
  double* dq;
  double h;
  HD void operator()(int i) const {
    const Vec3 f = force[i];
    Vec3 v = vel[i];
    v.x += h * f.x;
    v.y += h * f.y;
    v.z += h * f.z;
    vel[i] = v;
    if (dq && dq[i] != 0.0) {
      pos[i].w += dq[i];
      dq[i] = 0.0;
    }
  }
};
}  // namespace

double kickDrift(ParticleData& p, double half_dt, double dt, const common::Box& box,
                 bool close_pending, double* dq, DVec<double>& block_max) {
  const int n = static_cast<int>(p.size());
  const int block = blockSizeFor(n);
  block_max.resize(blockCount(n, block));
  forEachBlocked(n, block,
                 KickDrift{raw(p.pos), raw(p.vel), raw(p.force), raw(p.ix), raw(p.iy), raw(p.iz),
                           dq, half_dt, dt, close_pending, box},
                 MaxReduction{}, raw(block_max));
  return reduceBlocks(block_max, 0.0, MaxReduction{});
}

void closeKick(ParticleData& p, double half_dt, double* dq) {
  thrust::for_each(thrust::counting_iterator<int>(0),
                   thrust::counting_iterator<int>(static_cast<int>(p.size())),
                   CloseKick{raw(p.vel), raw(p.force), raw(p.pos), dq, half_dt});
}

}  // namespace granagg::md
