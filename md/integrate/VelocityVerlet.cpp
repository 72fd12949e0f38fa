#include "md/integrate/VelocityVerlet.h"

#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>

namespace granagg::md {

namespace {
struct Kick {
  double *vx, *vy, *vz;
  const double *fx, *fy, *fz;
  double h;
  HD void operator()(int i) const {
    vx[i] += h * fx[i];
    vy[i] += h * fy[i];
    vz[i] += h * fz[i];
  }
};

struct Drift {
  double *x, *y, *z, *xp, *yp, *zp;
  const double *vx, *vy, *vz;
  int *ix, *iy, *iz;
  double dt;
  common::Box box;
  HD void operator()(int i) const {
    xp[i] = x[i];
    yp[i] = y[i];
    zp[i] = z[i];
    double a = x[i] + dt * vx[i], b = y[i] + dt * vy[i], c = z[i] + dt * vz[i];
    ix[i] += box.wrap(a);
    iy[i] += box.wrap(b);
    iz[i] += box.wrap(c);
    x[i] = a;
    y[i] = b;
    z[i] = c;
  }
};
}  // namespace

void kick(ParticleData& p, double half_dt) {
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(static_cast<int>(p.size())),
                   Kick{raw(p.vx), raw(p.vy), raw(p.vz), raw(p.fx), raw(p.fy), raw(p.fz), half_dt});
}

void drift(ParticleData& p, double dt, const common::Box& box) {
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(static_cast<int>(p.size())),
                   Drift{raw(p.x), raw(p.y), raw(p.z), raw(p.xp), raw(p.yp), raw(p.zp), raw(p.vx), raw(p.vy), raw(p.vz),
                         raw(p.ix), raw(p.iy), raw(p.iz), dt, box});
}

}  // namespace granagg::md
