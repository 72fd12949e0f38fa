#include "md/compute/ContactForce.h"

#include <cmath>

#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/transform.h>
#include <thrust/transform_reduce.h>

#include <thrust/reduce.h>

#include "md/engine/Launch.h"
#include "md/potentials/HertzViscoelastic.h"
#include "md/potentials/SpringDashpot.h"

namespace granagg::md {

void ContactWork::resize(std::size_t n) {
  vp.resize(n);
  bad.assign(n, 0);
}

namespace {

template <class Potential>
struct ContactForceFunctor {
  const Scalar4 *pos, *pos_prev, *vp;  // vp: predicted velocities
  const int *rows, *counts;
  int cap;
  common::Box box;
  typename Potential::Params params;
  double max_overlap, close_h;
  double *fx, *fy, *fz, *vx, *vy, *vz;
  int* bad;

  /// returns the collisions of pairs (i, j > i) that started this step and the check flag of i
  HD ContactStepResult operator()(int i) const {
    const Scalar4 ri = pos[i];
    const double xi_ = ri.x, yi_ = ri.y, zi_ = ri.z;
    const Scalar4 vi = vp[i];
    double f0 = 0.0, f1 = 0.0, f2 = 0.0, mx = 0.0;
    int nnew = 0;
    const int* row = rows + static_cast<long>(i) * cap;
    const int n = counts[i];
    for (int k = 0; k < n; ++k) {
      const int j = row[k];
      // positions are wrapped into [0, L): one conditional shift is the minimum image
      const Scalar4 rj = pos[j];
      const double rx = box.minimumImageWrapped(xi_ - rj.x), ry = box.minimumImageWrapped(yi_ - rj.y),
                   rz = box.minimumImageWrapped(zi_ - rj.z);
      const double r2 = rx * rx + ry * ry + rz * rz;
      if (r2 >= 1.0) continue;
      const double r = sqrt(r2);
      const double inv_r = 1.0 / r;
      const double nx = rx * inv_r, ny = ry * inv_r, nz = rz * inv_r;  // unit vector from j to i
      const double xi = 1.0 - r;                                        // overlap
      const Scalar4 vj = vp[j];
      const double gx = vi.x - vj.x, gy = vi.y - vj.y, gz = vi.z - vj.z;
      const double xi_dot = -(gx * nx + gy * ny + gz * nz);  // > 0 while approaching
      const double F = Potential::normalForce(xi, xi_dot, params);
      f0 += F * nx;
      f1 += F * ny;
      f2 += F * nz;
      mx = xi > mx ? xi : mx;
      if (j > i) {
        // a collision is the first step at which the pair overlaps after not overlapping
        const Scalar4 pi = pos_prev[i], pj = pos_prev[j];
        const double px = box.minimumImageWrapped(pi.x - pj.x), py = box.minimumImageWrapped(pi.y - pj.y),
                     pz = box.minimumImageWrapped(pi.z - pj.z);
        if (px * px + py * py + pz * pz >= 1.0) ++nnew;
      }
    }
    fx[i] = f0;
    fy[i] = f1;
    fz[i] = f2;
    if (close_h != 0.0) {  // closing kick of velocity Verlet: v(t+dt) = v(t+dt/2) + (dt/2) f(t+dt)
      vx[i] += close_h * f0;
      vy[i] += close_h * f1;
      vz[i] += close_h * f2;
    }
    // v - v == 0 exactly for finite v and is NaN for NaN or inf: a finiteness test that needs no
    // math library in device code
    const double probe = f0 + f1 + f2 + xi_ + yi_ + zi_;
    const bool finite = probe - probe == 0.0;
    ContactStepResult res;
    res.collisions = nnew;
    res.worst = !finite ? 1 : (mx > max_overlap ? 2 : 0);
    bad[i] = res.worst;
    return res;
  }
};

struct CombineStepFlags {
  using value_type = ContactStepResult;
  HD static ContactStepResult identity() { return ContactStepResult{}; }
  HD ContactStepResult operator()(const ContactStepResult& a, const ContactStepResult& b) const {
    ContactStepResult r;
    r.collisions = a.collisions + b.collisions;
    r.worst = a.worst > b.worst ? a.worst : b.worst;
    return r;
  }
};

/// Contact statistics of particle i (the same pair test as the force pass).
template <class Potential>
struct SummaryFunctor {
  const Scalar4* pos;
  const int *rows, *counts;
  int cap;
  common::Box box;
  typename Potential::Params params;
  HD ContactSummary operator()(int i) const {
    ContactSummary s;
    const int* row = rows + static_cast<long>(i) * cap;
    for (int k = 0; k < counts[i]; ++k) {
      const int j = row[k];
      const Scalar4 ri = pos[i], rj = pos[j];
      const double rx = box.minimumImageWrapped(ri.x - rj.x), ry = box.minimumImageWrapped(ri.y - rj.y),
                   rz = box.minimumImageWrapped(ri.z - rj.z);
      const double r2 = rx * rx + ry * ry + rz * rz;
      if (r2 >= 1.0) continue;
      const double xi = 1.0 - sqrt(r2);
      s.elastic_energy += 0.5 * Potential::elasticEnergy(xi, params);  // half per partner
      ++s.contacts;
      if (j > i) s.overlap_sum += xi;
      s.max_overlap = xi > s.max_overlap ? xi : s.max_overlap;
    }
    return s;
  }
};
struct CombineSummary {
  HD ContactSummary operator()(const ContactSummary& a, const ContactSummary& b) const {
    ContactSummary r;
    r.elastic_energy = a.elastic_energy + b.elastic_energy;
    r.overlap_sum = a.overlap_sum + b.overlap_sum;
    r.max_overlap = a.max_overlap > b.max_overlap ? a.max_overlap : b.max_overlap;
    r.contacts = a.contacts + b.contacts;
    return r;
  }
};
template <class Potential>
struct MaxOverlapOf {
  SummaryFunctor<Potential> s;
  HD double operator()(int i) const { return s(i).max_overlap; }
};

}  // namespace

template <class Potential>
ContactStepResult computeContactForces(ParticleData& p, const NeighborList& nl, const common::Box& box,
                                       const typename Potential::Params& params, double max_overlap,
                                       double close_half_dt, ContactWork& w) {
  const int N = static_cast<int>(p.size());
  if (w.bad.size() != p.size()) w.resize(p.size());
  ContactForceFunctor<Potential> f{raw(p.pos), raw(p.pos_prev), raw(w.vp),
                                   nl.rows(), nl.counts(), nl.capacity(), box, params, max_overlap, close_half_dt,
                                   raw(p.fx), raw(p.fy), raw(p.fz), raw(p.vx), raw(p.vy), raw(p.vz),
                                   raw(w.bad)};
  // forces and, per block, collisions (sum) and the worst flag (max); then one reduction over blocks
  const int block = blockSizeFor(N);
  w.block_flags.resize(blockCount(N, block));
  forEachBlocked(N, block, f, CombineStepFlags{}, raw(w.block_flags));
  return thrust::reduce(w.block_flags.begin(), w.block_flags.end(), ContactStepResult{}, CombineStepFlags{});
}

template <class Potential>
ContactSummary contactSummary(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                              const typename Potential::Params& params) {
  const int N = static_cast<int>(p.size());
  SummaryFunctor<Potential> s{raw(p.pos), nl.rows(), nl.counts(), nl.capacity(), box, params};
  return thrust::transform_reduce(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N), s, ContactSummary{},
                                  CombineSummary{});
}

template <class Potential>
void maxOverlapPerParticle(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                           const typename Potential::Params& params, DVec<double>& out) {
  const int N = static_cast<int>(p.size());
  out.resize(p.size());
  SummaryFunctor<Potential> s{raw(p.pos), nl.rows(), nl.counts(), nl.capacity(), box, params};
  thrust::transform(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N), out.begin(),
                    MaxOverlapOf<Potential>{s});
}

// the contact models: adding one = one header + one line per function here
#define GRANAGG_CONTACT_MODEL(P)                                                                                  \
  template ContactStepResult computeContactForces<P>(ParticleData&, const NeighborList&, const common::Box&,      \
                                                     const P::Params&, double, double, ContactWork&);            \
  template ContactSummary contactSummary<P>(const ParticleData&, const NeighborList&, const common::Box&,          \
                                            const P::Params&);                                                    \
  template void maxOverlapPerParticle<P>(const ParticleData&, const NeighborList&, const common::Box&,             \
                                         const P::Params&, DVec<double>&);
GRANAGG_CONTACT_MODEL(HertzViscoelastic)
GRANAGG_CONTACT_MODEL(SpringDashpot)
#undef GRANAGG_CONTACT_MODEL

}  // namespace granagg::md
