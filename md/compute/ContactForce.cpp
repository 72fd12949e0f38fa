#include "md/compute/ContactForce.h"

#include <cmath>

#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>

#include "md/potentials/HertzViscoelastic.h"
#include "md/potentials/SpringDashpot.h"

namespace granagg::md {

void ContactWork::resize(std::size_t n) {
  for (auto* v : {&fx, &fy, &fz, &energy, &overlap_upper, &max_overlap, &vpx, &vpy, &vpz}) v->assign(n, 0.0);
  for (auto* v : {&contacts, &new_contacts_upper, &bad}) v->assign(n, 0);
}

namespace {

/// Predicted full-step velocity of every particle, computed once per step (a neighbour's is then
/// one load per component instead of two loads and a multiply-add per pair; same values).
struct PredictVelocity {
  const double *vx, *vy, *vz, *fx, *fy, *fz;
  double *px, *py, *pz;
  double half_dt;
  HD void operator()(int i) const {
    px[i] = vx[i] + half_dt * fx[i];
    py[i] = vy[i] + half_dt * fy[i];
    pz[i] = vz[i] + half_dt * fz[i];
  }
};

template <class Potential>
struct ContactForceFunctor {
  const double *x, *y, *z, *xp, *yp, *zp, *vx, *vy, *vz;  // vx..: predicted velocities
  const int *rows, *counts;
  int cap;
  common::Box box;
  typename Potential::Params params;
  double max_overlap;
  double *ofx, *ofy, *ofz, *energy, *overlap_upper, *omax;
  int *contacts, *new_upper, *bad;

  HD void operator()(int i) const {
    const double xi_ = x[i], yi_ = y[i], zi_ = z[i];
    // predicted full-step velocity of i (see header)
    const double vix = vx[i], viy = vy[i], viz = vz[i];
    double f0 = 0.0, f1 = 0.0, f2 = 0.0, e = 0.0, ov = 0.0, mx = 0.0;
    int nc = 0, nnew = 0;
    const int* row = rows + static_cast<long>(i) * cap;
    const int n = counts[i];
    for (int k = 0; k < n; ++k) {
      const int j = row[k];
      const double rx = box.minimumImage(xi_ - x[j]), ry = box.minimumImage(yi_ - y[j]), rz = box.minimumImage(zi_ - z[j]);
      const double r2 = rx * rx + ry * ry + rz * rz;
      if (r2 >= 1.0) continue;
      const double r = sqrt(r2);
      const double inv_r = 1.0 / r;
      const double nx = rx * inv_r, ny = ry * inv_r, nz = rz * inv_r;  // unit vector from j to i
      const double xi = 1.0 - r;                                        // overlap
      const double gx = vix - vx[j], gy = viy - vy[j], gz = viz - vz[j];
      const double xi_dot = -(gx * nx + gy * ny + gz * nz);  // > 0 while approaching
      const double F = Potential::normalForce(xi, xi_dot, params);
      f0 += F * nx;
      f1 += F * ny;
      f2 += F * nz;
      e += 0.5 * Potential::elasticEnergy(xi, params);
      ++nc;
      mx = xi > mx ? xi : mx;
      if (j > i) {
        ov += xi;
        // a collision is the first step at which the pair overlaps after not overlapping
        const double px = box.minimumImage(xp[i] - xp[j]), py = box.minimumImage(yp[i] - yp[j]),
                     pz = box.minimumImage(zp[i] - zp[j]);
        if (px * px + py * py + pz * pz >= 1.0) ++nnew;
      }
    }
    ofx[i] = f0;
    ofy[i] = f1;
    ofz[i] = f2;
    energy[i] = e;
    overlap_upper[i] = ov;
    omax[i] = mx;
    contacts[i] = nc;
    new_upper[i] = nnew;
    // v - v == 0 exactly for finite v and is NaN for NaN or inf: a finiteness test that needs no
    // math library in device code
    const double probe = f0 + f1 + f2 + xi_ + yi_ + zi_;
    const bool finite = probe - probe == 0.0;
    bad[i] = !finite ? 1 : (mx > max_overlap ? 2 : 0);
  }
};

}  // namespace

template <class Potential>
void computeContactForces(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                          const typename Potential::Params& params, double half_dt, double max_overlap,
                          ContactWork& w) {
  const int N = static_cast<int>(p.size());
  if (w.fx.size() != p.size()) w.resize(p.size());
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N),
                   PredictVelocity{raw(p.vx), raw(p.vy), raw(p.vz), raw(p.fx), raw(p.fy), raw(p.fz), raw(w.vpx),
                                   raw(w.vpy), raw(w.vpz), half_dt});
  ContactForceFunctor<Potential> f{raw(p.x), raw(p.y), raw(p.z), raw(p.xp), raw(p.yp), raw(p.zp),
                                   raw(w.vpx), raw(w.vpy), raw(w.vpz),
                                   nl.rows(), nl.counts(), nl.capacity(), box, params, max_overlap,
                                   raw(w.fx), raw(w.fy), raw(w.fz), raw(w.energy), raw(w.overlap_upper),
                                   raw(w.max_overlap), raw(w.contacts), raw(w.new_contacts_upper), raw(w.bad)};
  thrust::for_each(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N), f);
}

// the contact models: adding one = one header + one line here
template void computeContactForces<HertzViscoelastic>(const ParticleData&, const NeighborList&, const common::Box&,
                                                      const HertzViscoelastic::Params&, double, double, ContactWork&);
template void computeContactForces<SpringDashpot>(const ParticleData&, const NeighborList&, const common::Box&,
                                                  const SpringDashpot::Params&, double, double, ContactWork&);

}  // namespace granagg::md
