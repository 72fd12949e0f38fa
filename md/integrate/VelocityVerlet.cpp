#include "md/integrate/VelocityVerlet.h"

#include <thrust/for_each.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>

#include "md/engine/Launch.h"

namespace granagg::md {

namespace {
struct Predict {
  const double *vx, *vy, *vz, *fx, *fy, *fz;
  Scalar4* vp;
  double h;
  HD void operator()(int i) const { vp[i] = Scalar4{vx[i] + h * fx[i], vy[i] + h * fy[i], vz[i] + h * fz[i], 0.0}; }
};

struct MaxReduction {
  using value_type = double;
  HD static double identity() { return 0.0; }
  HD double operator()(double a, double b) const { return a > b ? a : b; }
};

struct KickDrift {
  Scalar4 *pos, *pos_prev, *vp;
  double *vx, *vy, *vz;
  const double *fx, *fy, *fz;
  int *ix, *iy, *iz;
  const Scalar4* reference;
  double h, dt;
  common::Box box;
  /// returns the squared displacement from the reference positions
  HD double operator()(int i) const {
    const double f0 = fx[i], f1 = fy[i], f2 = fz[i];
    const double u0 = vx[i] + h * f0, u1 = vy[i] + h * f1, u2 = vz[i] + h * f2;  // v(t + dt/2)
    vx[i] = u0;
    vy[i] = u1;
    vz[i] = u2;
    vp[i] = Scalar4{u0 + h * f0, u1 + h * f1, u2 + h * f2, 0.0};  // predicted v(t + dt) (ContactForce.h)
    const Scalar4 r = pos[i];
    pos_prev[i] = r;
    double a = r.x + dt * u0, b = r.y + dt * u1, c = r.z + dt * u2;
    ix[i] += box.wrap(a);
    iy[i] += box.wrap(b);
    iz[i] += box.wrap(c);
    pos[i] = Scalar4{a, b, c, r.w};
    if (!reference) return 0.0;
    const Scalar4 r0 = reference[i];
    const double dx = box.minimumImageWrapped(a - r0.x), dy = box.minimumImageWrapped(b - r0.y),
                 dz = box.minimumImageWrapped(c - r0.z);
    return dx * dx + dy * dy + dz * dz;
  }
};
}  // namespace

void predictVelocities(const ParticleData& p, double half_dt, DVec<Scalar4>& vp) {
  vp.resize(p.size());
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(static_cast<int>(p.size())),
                   Predict{raw(p.vx), raw(p.vy), raw(p.vz), raw(p.fx), raw(p.fy), raw(p.fz), raw(vp), half_dt});
}

double kickDrift(ParticleData& p, double half_dt, double dt, const common::Box& box, DVec<Scalar4>& vp,
                 const Scalar4* reference, DVec<double>& block_max) {
  const int n = static_cast<int>(p.size());
  vp.resize(p.size());
  const int block = blockSizeFor(n);
  block_max.resize(blockCount(n, block));
  forEachBlocked(n, block,
                 KickDrift{raw(p.pos), raw(p.pos_prev), raw(vp), raw(p.vx), raw(p.vy), raw(p.vz), raw(p.fx), raw(p.fy),
                           raw(p.fz), raw(p.ix), raw(p.iy), raw(p.iz), reference, half_dt, dt, box},
                 MaxReduction{}, raw(block_max));
  return thrust::reduce(block_max.begin(), block_max.end(), 0.0, thrust::maximum<double>());
}

}  // namespace granagg::md
