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
    const Vec3 f = force[i], v = vel[i];
    const double f0 = f.x, f1 = f.y, f2 = f.z;
    double u0 = v.x, u1 = v.y, u2 = v.z;
    if (close_pending) {  // v(t) = u(t - dt/2) + (dt/2) f(t)
      u0 += h * f0;
      u1 += h * f1;
      u2 += h * f2;
    }
    u0 += h * f0;  // u(t + dt/2) = v(t) + (dt/2) f(t)
    u1 += h * f1;
    u2 += h * f2;
    vel[i] = Vec3{u0, u1, u2};
    const Scalar4 r = pos[i];
    double q = r.w;
    if (dq && dq[i] != 0.0) {  // charge exchanged at the last force pass
      q += dq[i];
      dq[i] = 0.0;
    }
    double a = r.x + dt * u0, b = r.y + dt * u1, c = r.z + dt * u2;
    // image counts are touched only when a particle crosses a face (rare)
    const int sa = box.wrap(a), sb = box.wrap(b), sc = box.wrap(c);
    if (sa) ix[i] += sa;
    if (sb) iy[i] += sb;
    if (sc) iz[i] += sc;
    pos[i] = Scalar4{a, b, c, q};
    return u0 * u0 + u1 * u1 + u2 * u2;
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

double kickDrift(ParticleData& p, double half_dt, double dt, const common::Box& box, bool close_pending, double* dq,
                 DVec<double>& block_max) {
  const int n = static_cast<int>(p.size());
  const int block = blockSizeFor(n);
  block_max.resize(blockCount(n, block));
  forEachBlocked(n, block,
                 KickDrift{raw(p.pos), raw(p.vel), raw(p.force), raw(p.ix),
                           raw(p.iy), raw(p.iz), dq, half_dt, dt, close_pending, box},
                 MaxReduction{}, raw(block_max));
  return reduceBlocks(block_max, 0.0, MaxReduction{});
}

void closeKick(ParticleData& p, double half_dt, double* dq) {
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(static_cast<int>(p.size())),
                   CloseKick{raw(p.vel), raw(p.force), raw(p.pos), dq, half_dt});
}

}  // namespace granagg::md
