#include "md/integrate/VelocityVerlet.h"

#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>

namespace granagg::md {

namespace {
struct Predict {
  const double *vx, *vy, *vz, *fx, *fy, *fz;
  double *px, *py, *pz;
  double h;
  HD void operator()(int i) const {
    px[i] = vx[i] + h * fx[i];
    py[i] = vy[i] + h * fy[i];
    pz[i] = vz[i] + h * fz[i];
  }
};

struct KickDrift {
  double *x, *y, *z, *xp, *yp, *zp, *vx, *vy, *vz, *px, *py, *pz;
  const double *fx, *fy, *fz;
  int *ix, *iy, *iz;
  double h, dt;
  common::Box box;
  HD void operator()(int i) const {
    const double f0 = fx[i], f1 = fy[i], f2 = fz[i];
    const double u0 = vx[i] + h * f0, u1 = vy[i] + h * f1, u2 = vz[i] + h * f2;  // v(t + dt/2)
    vx[i] = u0;
    vy[i] = u1;
    vz[i] = u2;
    px[i] = u0 + h * f0;  // predicted v(t + dt) for the dissipative force (ContactForce.h)
    py[i] = u1 + h * f1;
    pz[i] = u2 + h * f2;
    const double x0 = x[i], y0 = y[i], z0 = z[i];
    xp[i] = x0;
    yp[i] = y0;
    zp[i] = z0;
    double a = x0 + dt * u0, b = y0 + dt * u1, c = z0 + dt * u2;
    ix[i] += box.wrap(a);
    iy[i] += box.wrap(b);
    iz[i] += box.wrap(c);
    x[i] = a;
    y[i] = b;
    z[i] = c;
  }
};
}  // namespace

void predictVelocities(const ParticleData& p, double half_dt, DVec<double>& vpx, DVec<double>& vpy, DVec<double>& vpz) {
  for (auto* v : {&vpx, &vpy, &vpz}) v->resize(p.size());
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(static_cast<int>(p.size())),
                   Predict{raw(p.vx), raw(p.vy), raw(p.vz), raw(p.fx), raw(p.fy), raw(p.fz), raw(vpx), raw(vpy), raw(vpz),
                           half_dt});
}

void kickDrift(ParticleData& p, double half_dt, double dt, const common::Box& box, DVec<double>& vpx,
               DVec<double>& vpy, DVec<double>& vpz) {
  for (auto* v : {&vpx, &vpy, &vpz}) v->resize(p.size());
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(static_cast<int>(p.size())),
                   KickDrift{raw(p.x), raw(p.y), raw(p.z), raw(p.xp), raw(p.yp), raw(p.zp), raw(p.vx), raw(p.vy),
                             raw(p.vz), raw(vpx), raw(vpy), raw(vpz), raw(p.fx), raw(p.fy), raw(p.fz), raw(p.ix),
                             raw(p.iy), raw(p.iz), half_dt, dt, box});
}

}  // namespace granagg::md
