#include "md/compute/ContactForce.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include <thrust/for_each.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/transform.h>
#include <thrust/transform_reduce.h>

#include <thrust/reduce.h>

#include "md/compute/ContactParts.h"
#include "md/coulomb/RealSpace.h"
#include "md/engine/Launch.h"
#include "md/integrate/VelocityVerlet.h"
#include "md/potentials/ContactModels.h"
#include "md/potentials/ImpactSpeed.h"

namespace granagg::md {

void ContactWork::resize(std::size_t n) { f.resize(n); }

namespace {

/// The force pass over one list (ContactForce.h), composed of ContactParts.h's parts and the
/// contact law (Potential::normalForce). The functor owns the loop shapes -- the row pass
/// (operator()) and the pair form's two passes (pairs(), gather()) -- and the composition of one
/// contact (contact()); the parts do the rest. It holds the parts' fields in one flat record, in
/// the order the loops read them, and hands out each part as a view over its own fields
/// (ContactParts.h says why). The switches compile parts in or out:
/// - EXT: slow forces (SlowForce);
/// - FAST_COULOMB: the fast Coulomb force (FastCoulomb), with the row pass's two-loop shape;
/// - CHARGING: the charge exchange at new contacts (Charging; dq non-null);
/// - ADVANCE: the step completed in the same pass (StepAdvance; ContactStep::advance_dt).
template <class Potential, bool EXT, bool FAST_COULOMB, bool CHARGING, bool ADVANCE = false>
struct ContactForceFunctor {
  using value_type = StepAccum;
  const Scalar4* pos;  // Geometry
  const Vec3* vel;     // StepState
  const Vec3* f_old;   // StepState
  const int *rows, *counts;
  int cap;
  // the same list in compressed pair form (NeighborList::keepPairs), for pairs() and gather();
  // null: operator() only
  const int *pair_offsets, *pair_owners, *pair_partners, *entry_offsets, *entry_owners,
      *entry_pairs, *pair_entries;
  common::Box box;                    // Geometry
  typename Potential::Params params;  // the contact law's
  double h_pred, dt_prev;             // StepState
  Vec3* f_new;                        // f(t), written
  // Charging
  const int* id;
  ChargeExchange::Params charging;
  std::int64_t step;
  double* dq;
  // SlowForce
  const double *ext_fx, *ext_fy, *ext_fz;
  double ext_force_scale, ext_predict_scale;
  // FastCoulomb
  double K, fast_r2sq;
  PairTable fast_table;
  // StepAdvance
  Scalar4* next_pos;
  Vec3* next_vel;
  int *ix, *iy, *iz;
  double advance_dt;
  // pair form only: each pair's contact, written by pairs() and read by gather() (ContactWork)
  unsigned char* pair_hit;   // in contact
  unsigned char* entry_hit;  // in contact, per entry
  Vec3* pair_f;              // force on the owner (where in contact)
  double* pair_dq;           // charge the owner gains (CHARGING, where in contact)
  // PairScreen
  double* pair_next;
  double bound;

  // the parts, as views over the fields above
  HD_INLINE contact::Geometry geometry() const { return {pos, box}; }
  HD_INLINE contact::StepState stepState() const { return {vel, f_old, h_pred, dt_prev}; }
  HD_INLINE contact::SlowForce<EXT> slowForce() const {
    return {ext_fx, ext_fy, ext_fz, ext_force_scale, ext_predict_scale};
  }
  HD_INLINE contact::Charging<CHARGING> charge() const { return {id, charging, step, dq}; }
  HD_INLINE contact::FastCoulomb fastCoulomb() const { return {K, fast_r2sq, fast_table}; }
  HD_INLINE contact::StepAdvance<ADVANCE> stepAdvance() const {
    return {next_pos, next_vel, ix, iy, iz, advance_dt};
  }
  HD_INLINE contact::PairScreen pairScreen() const { return {pair_next, bound}; }

  /// Predicted full-step velocity of particle k (ContactForce.h), with the slow forces' impulse.
  HD void predicted(int k, double& a, double& b, double& c) const {
    stepState().predicted(k, a, b, c);
    slowForce().addToPrediction(k, a, b, c);
  }

  /// The contact of pair (i, j) at separation r = (rx, ry, rz), r2 = |r|^2 < 1: adds its force on i
  /// to (f0, f1, f2), its overlap to the maximum mx, a collision that started this step (counted
  /// for j > i) to nnew, and with charging the charge i gains to dqi.
  HD void contact(int i, int j, double rx, double ry, double rz, double r2, double& f0, double& f1,
                  double& f2, double& mx, int& nnew, double& dqi) const {
    const double r = sqrt(r2);
    const double inv_r = 1.0 / r;
    const double nx = rx * inv_r, ny = ry * inv_r, nz = rz * inv_r;  // unit vector from j to i
    const double xi = 1.0 - r;                                       // overlap
    double vi0, vi1, vi2, vj0, vj1, vj2;  // contacts are rare: predicted velocities on demand
    predicted(i, vi0, vi1, vi2);
    predicted(j, vj0, vj1, vj2);
    const double gx = vi0 - vj0, gy = vi1 - vj1, gz = vi2 - vj2;
    const double xi_dot = -(gx * nx + gy * ny + gz * nz);  // > 0 while approaching
    const double F = Potential::normalForce(xi, xi_dot, params);
    f0 += F * nx;
    f1 += F * ny;
    f2 += F * nz;
    mx = xi > mx ? xi : mx;
    // a collision is the first step at which the pair overlaps after not overlapping
    if (stepState().apartBefore(i, j, rx, ry, rz)) {
      if (j > i) ++nnew;  // each collision counted once
      if (CHARGING) dqi += charge().transfer(i, j, xi_dot);
    }
  }

  /// Separation r_i - r_j and its square (Geometry). This forwarding method and predicted() stay:
  /// g++'s inlining of the passes depends on them (docs/ARCHITECTURE.md, "The contact pass").
  HD double separation(const Scalar4& ri, const Scalar4& rj, double& rx, double& ry,
                       double& rz) const {
    return geometry().separation(ri, rj, rx, ry, rz);
  }

  /// Particle i over its row: returns the collisions of pairs (i, j > i) that started this step,
  /// i's largest overlap and a finiteness probe of i's force and position (StepAccum).
  HD StepAccum operator()(int i) const {
    const Scalar4 ri = pos[i];
    double f0 = 0.0, f1 = 0.0, f2 = 0.0, mx = 0.0, dqi = 0.0;
    int nnew = 0;
    const int* row = rows + static_cast<long>(i) * cap;
    const int n = counts[i];
    if (FAST_COULOMB) {
      // Every entry gets the fast Coulomb force, in a loop without branches; the few entries in
      // contact are noted and get their contact work in a second loop, in row order (a contact
      // branch inside the first loop was mispredicted at each contact and cost the loop its
      // overlap of independent entries). i's force is the Coulomb sum plus the contact sum.
      constexpr int BATCH = 16;
      int touching[BATCH];
      int nt = 0;
      double c0 = 0.0, c1 = 0.0, c2 = 0.0;
      for (int k = 0; k < n; ++k) {
        const Scalar4 rj = pos[row[k]];
        double rx, ry, rz;
        const double r2 = separation(ri, rj, rx, ry, rz);
        const double fr = fastCoulomb().overR(ri, rj, r2);
        c0 += fr * rx;
        c1 += fr * ry;
        c2 += fr * rz;
        touching[nt] = k;
        nt += r2 < 1.0;
        if (nt == BATCH) {  // (rare: a full batch)
          contacts(i, ri, row, touching, nt, f0, f1, f2, mx, nnew, dqi);
          nt = 0;
        }
      }
      contacts(i, ri, row, touching, nt, f0, f1, f2, mx, nnew, dqi);
      f0 += c0;
      f1 += c1;
      f2 += c2;
    } else {
      for (int k = 0; k < n; ++k) {
        const int j = row[k];
        double rx, ry, rz;
        const double r2 = separation(ri, pos[j], rx, ry, rz);
        if (r2 < 1.0) contact(i, j, rx, ry, rz, r2, f0, f1, f2, mx, nnew, dqi);
      }
    }
    charge().store(i, dqi);
    StepAccum res;
    res.collisions = nnew;
    res.max_overlap = mx;
    finish<true>(i, f0, f1, f2, res);
    return res;
  }

  /// The contact work of the entries touching[0..nt) of i's row (operator()).
  HD_INLINE void contacts(int i, const Scalar4& ri, const int* row, const int* touching, int nt,
                          double& f0, double& f1, double& f2, double& mx, int& nnew,
                          double& dqi) const {
    for (int t = 0; t < nt; ++t) {
      const int j = row[touching[t]];
      double rx, ry, rz;
      const double r2 = separation(ri, pos[j], rx, ry, rz);
      contact(i, j, rx, ry, rz, r2, f0, f1, f2, mx, nnew, dqi);
    }
  }

  /// Adds the slow force, stores i's force and adds its finiteness probe to res: PROBE_ALL, of the
  /// force and the position; otherwise of the force only where it has a slow part (the pair-form
  /// pass probes the contact forces where it computes them: a particle without contacts has a
  /// zero contact force, and finite forces keep velocities and positions finite).
  template <bool PROBE_ALL>
  HD_INLINE void finish(int i, double f0, double f1, double f2, StepAccum& res) const {
    slowForce().addToForce(i, f0, f1, f2);
    f_new[i] = Vec3{f0, f1, f2};
    const Scalar4 ri = pos[i];
    if (PROBE_ALL)
      res.probe += f0 + f1 + f2 + ri.x + ri.y + ri.z;  // NaN or inf if any term is
    else if (EXT)
      res.probe += f0 + f1 + f2;
    if (ADVANCE) {  // this step's closing kick, the next step's opening kick and drift (kickDrift)
      const double u2 = stepAdvance().apply(box, i, f0, f1, f2, vel[i], ri, charge().of(i));
      res.max_u2 = u2 > res.max_u2 ? u2 : res.max_u2;
    }
  }

  /// Compressed pair form, first pass: the pairs owned by particles [first, last) as one loop. The
  /// pairs are screened in chunks, branch-free, and those in contact get the contact work, once
  /// per pair: pair_hit, and for the hits the force on the owner (pair_f) and the charge it gains
  /// (pair_dq). In a dilute gas a row holds one or two entries and few are in contact: per-row
  /// loops spent their time in mispredicted loop exits and contact tests, whole chunks do not.
  /// With a displacement bound (ContactStep::displacement_bound) only the pairs that may have
  /// closed their gap since their last screening are screened (pair_next): a pair at distance r
  /// cannot touch before the bound has grown by (r - 1) / 2, so a pair near the edge of the list
  /// waits many steps and only pairs in or near contact are screened at every step.
  /// Returns the collisions (each pair once) and the largest overlap.
  HD StepAccum pairs(int first, int last) const {
    constexpr int CHUNK = 64;
    int due[CHUNK], hit[CHUNK];
    const int end = pair_offsets[last];
    int nnew = 0;
    double mx = 0.0, probe = 0.0;
    for (int c0 = pair_offsets[first]; c0 < end; c0 += CHUNK) {
      const int c1 = c0 + CHUNK < end ? c0 + CHUNK : end;
      int ndue = 0, nhit = 0;
      for (int p = c0; p < c1; ++p) {
        due[ndue] = p;
        ndue += pairScreen().due(p);
      }
      for (int k = 0; k < ndue; ++k) {
        const int p = due[k];
        double rx, ry, rz;
        const double r2 = separation(pos[pair_owners[p]], pos[pair_partners[p]], rx, ry, rz);
        const unsigned char in_contact = r2 < 1.0;
        // a contact begins or ends (rare): the flags of both entries; this pass alone writes
        // the partner's row
        if (in_contact != pair_hit[p]) {
          pair_hit[p] = in_contact;
          entry_hit[pair_entries[2 * p]] = in_contact;
          entry_hit[pair_entries[2 * p + 1]] = in_contact;
        }
        hit[nhit] = p;
        nhit += in_contact;
        pairScreen().defer(p, r2);
      }
      for (int h = 0; h < nhit; ++h) {
        const int p = hit[h], i = pair_owners[p], j = pair_partners[p];
        double rx, ry, rz;
        const double r2 = separation(pos[i], pos[j], rx, ry, rz);
        double f0 = 0.0, f1 = 0.0, f2 = 0.0, dqi = 0.0;
        // j > i: counts each collision once
        contact(i, j, rx, ry, rz, r2, f0, f1, f2, mx, nnew, dqi);
        probe += f0 + f1 + f2;  // (gather() probes only slow forces)
        pair_f[p] = Vec3{f0, f1, f2};
        if (CHARGING) pair_dq[p] = dqi;
      }
    }
    StepAccum res;
    res.collisions = nnew;
    res.max_overlap = mx;
    res.probe = probe;
    return res;
  }

  /// Compressed pair form, second pass: each particle of [first, last) sums the forces of its pairs
  /// in contact over its row, in row (id) order from zero -- the owner's force for pairs it owns,
  /// its negative for the others (Newton's third law; the contact arithmetic is antisymmetric in
  /// i and j to the last bit, so each particle gets exactly what a contact computed from its side
  /// gives, and the per-row pass operator() the same sums) -- then finishes (finish()). Entries
  /// are screened in chunks, as in pairs(). Gather only: each particle writes its own force.
  HD StepAccum gather(int first, int last) const {
    StepAccum res;
    for (int i = first; i < last; ++i) f_new[i] = Vec3{0.0, 0.0, 0.0};
    constexpr int CHUNK = 64;
    int hit[CHUNK];
    const int end = entry_offsets[last];
    for (int c0 = entry_offsets[first]; c0 < end; c0 += CHUNK) {
      const int c1 = c0 + CHUNK < end ? c0 + CHUNK : end;
      int nhit = 0;
      for (int e = c0; e < c1; ++e) {
        hit[nhit] = e;
        nhit += entry_hit[e];
      }
      for (int h = 0; h < nhit; ++h) {
        const int e = hit[h], i = entry_owners[e], q = entry_pairs[e];
        const Vec3 fp = pair_f[q < 0 ? ~q : q];
        Vec3 fi = f_new[i];
        if (q >= 0) {
          fi.x += fp.x;
          fi.y += fp.y;
          fi.z += fp.z;
        } else {  // the partner gets minus the owner's share (exact)
          fi.x += -fp.x;
          fi.y += -fp.y;
          fi.z += -fp.z;
        }
        f_new[i] = fi;
        if (CHARGING)
          dq[i] += q >= 0 ? pair_dq[q] : -pair_dq[~q];  // dq is zero here: the kick clears it
      }
    }
    for (int i = first; i < last; ++i) {
      const Vec3 fi = f_new[i];
      finish<false>(i, fi.x, fi.y, fi.z, res);
    }
    return res;
  }
};

/// The two passes of the compressed pair form as block bodies (md/engine/Launch.h).
template <class F>
struct PairsPass {
  using value_type = StepAccum;
  F f;
  HD StepAccum range(int first, int last) const { return f.pairs(first, last); }
};
template <class F>
struct GatherPass {
  using value_type = StepAccum;
  F f;
  HD StepAccum range(int first, int last) const { return f.gather(first, last); }
};

/// Block reduction of the force pass: sums and maxima only, so the pass has no per-particle branch
/// for its checks (a NaN or inf anywhere makes the probe sum NaN or inf).
struct CombineStepAccum {
  using value_type = StepAccum;
  HD static StepAccum identity() { return StepAccum{}; }
  HD StepAccum operator()(const StepAccum& a, const StepAccum& b) const {
    StepAccum r;
    r.collisions = a.collisions + b.collisions;
    r.probe = a.probe + b.probe;
    r.max_overlap = a.max_overlap > b.max_overlap ? a.max_overlap : b.max_overlap;
    r.max_u2 = a.max_u2 > b.max_u2 ? a.max_u2 : b.max_u2;
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
      const double rx = box.minimumImageWrapped(ri.x - rj.x),
                   ry = box.minimumImageWrapped(ri.y - rj.y),
                   rz = box.minimumImageWrapped(ri.z - rj.z);
      const double r2 = rx * rx + ry * ry + rz * rz;
      if (r2 >= 1.0) continue;
      const double xi = 1.0 - sqrt(r2);
      s.elastic_energy += 0.5 * Potential::elasticEnergy(xi, params);  // half per partner
      ++s.contacts;
      s.overlap_sum += 0.5 * xi;  // half per partner (not "j > i": slots, not ids)
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

/// Largest v_pair^2 (md/potentials/ImpactSpeed.h) of particle i's listed pairs.
template <class Potential>
struct PairImpactSpeed2Of {
  const Scalar4* pos;
  const Vec3* vel;
  const int *rows, *counts;
  int cap;
  common::Box box;
  typename Potential::Params params;
  double coulomb_K, m_eff;
  HD double operator()(int i) const {
    double best = 0.0;
    const int* row = rows + static_cast<long>(i) * cap;
    const Scalar4 ri = pos[i];
    const Vec3 vi = vel[i];
    for (int k = 0; k < counts[i]; ++k) {
      const int j = row[k];
      const Scalar4 rj = pos[j];
      const Vec3 vj = vel[j];
      const double rx = box.minimumImageWrapped(ri.x - rj.x),
                   ry = box.minimumImageWrapped(ri.y - rj.y),
                   rz = box.minimumImageWrapped(ri.z - rj.z);
      const double r = sqrt(rx * rx + ry * ry + rz * rz);
      if (!(r > 0.0)) continue;
      // closing rate -(v_i - v_j) . r_ij / r
      const double approach = -((vi.x - vj.x) * rx + (vi.y - vj.y) * ry + (vi.z - vj.z) * rz) / r;
      const double v2 =
          pairImpactSpeed2<Potential>(r, approach, coulomb_K * ri.w * rj.w, params, m_eff);
      best = v2 > best ? v2 : best;
    }
    return best;
  }
};

}  // namespace

template <class Potential, bool EXT, bool FAST_COULOMB, bool CHARGING, bool ADVANCE = false>
ContactStepResult forcePass(ParticleData& p, const NeighborList& nl, const common::Box& box,
                            const typename Potential::Params& params, const ContactStep& st,
                            ContactWork& w) {
  const int N = static_cast<int>(p.size());
  const double dt = st.dt, half_dt = 0.5 * dt;
  if (w.f.size() != p.size()) w.resize(p.size());
  if (ADVANCE) w.vel.resize(p.size());
  if (ADVANCE) w.pos.resize(p.size());
  const bool paired = !FAST_COULOMB && nl.hasPairs();
  if (paired) {
    w.pair_f.resize(nl.pairCount());
    if (CHARGING) w.pair_dq.resize(nl.pairCount());
    // a new list: no pair in contact yet, and every pair to be screened (threshold -inf). The
    // thresholds also hold only for bounds from the last pass's on, if that pass had one:
    // otherwise every pair is screened, and without a bound at every pass.
    const double bound = st.displacement_bound;
    const bool new_list = w.pairs_of != nl.generation();
    if (new_list) {
      w.pair_hit.assign(nl.pairCount(), 0);
      w.entry_hit.assign(2 * nl.pairCount(), 0);
      w.pairs_of = nl.generation();
    }
    if (new_list || !(bound >= 0.0) || w.next_bound < 0.0 || !(bound >= w.next_bound))
      w.pair_next.assign(nl.pairCount(), -std::numeric_limits<double>::infinity());
    w.next_bound = bound >= 0.0 ? bound : -1.0;
  }
  // filled by name (a positional list of 42 values let a swap of two pointers compile)
  ContactForceFunctor<Potential, EXT, FAST_COULOMB, CHARGING, ADVANCE> f{};
  f.pos = raw(p.pos);
  f.vel = raw(p.vel);
  f.f_old = raw(p.force);
  f.rows = nl.rows();
  f.counts = nl.counts();
  f.cap = nl.capacity();
  f.pair_offsets = paired ? nl.pairOffsets() : nullptr;
  f.pair_owners = paired ? nl.pairOwners() : nullptr;
  f.pair_partners = paired ? nl.pairPartners() : nullptr;
  f.entry_offsets = paired ? nl.entryOffsets() : nullptr;
  f.entry_owners = paired ? nl.entryOwners() : nullptr;
  f.entry_pairs = paired ? nl.entryPairs() : nullptr;
  f.pair_entries = paired ? nl.pairEntries() : nullptr;
  f.box = box;
  f.params = params;
  f.h_pred = half_dt;
  f.dt_prev = dt;
  f.f_new = raw(w.f);
  f.id = raw(p.id);
  f.charging = st.charging;
  f.step = st.step;
  f.dq = st.dq;
  f.ext_fx = st.ext_fx;
  f.ext_fy = st.ext_fy;
  f.ext_fz = st.ext_fz;
  f.ext_force_scale = st.ext_force_scale;
  f.ext_predict_scale = st.ext_predict_scale;
  f.K = st.coulomb_K;
  f.fast_r2sq = st.fast.r2 * st.fast.r2;
  f.fast_table = st.fast_table;
  f.next_pos = raw(w.pos);
  f.next_vel = raw(w.vel);
  f.ix = raw(p.ix);
  f.iy = raw(p.iy);
  f.iz = raw(p.iz);
  f.advance_dt = st.advance_dt;
  f.pair_hit = raw(w.pair_hit);
  f.entry_hit = raw(w.entry_hit);
  f.pair_f = raw(w.pair_f);
  f.pair_dq = raw(w.pair_dq);
  f.pair_next = raw(w.pair_next);
  f.bound = st.displacement_bound >= 0.0 ? st.displacement_bound : 0.0;
  // forces and, per block, collisions, probe sum and largest overlap; then one reduction over
  // blocks
  const int block = blockSizeFor(N);
  const int nblocks = blockCount(N, block);
  if (paired) {
    w.block_flags.resize(2 * nblocks);
    forEachBlockRange(N, block, PairsPass<decltype(f)>{f}, raw(w.block_flags));
    forEachBlockRange(N, block, GatherPass<decltype(f)>{f}, raw(w.block_flags) + nblocks);
  } else {
    w.block_flags.resize(nblocks);
    forEachBlocked(N, block, f, CombineStepAccum{}, raw(w.block_flags));
  }
  // p.force = f(t); the old forces stay in w until the next pass overwrites them
  p.force.swap(w.f);
  const StepAccum a = reduceBlocks(w.block_flags, StepAccum{}, CombineStepAccum{});
  ContactStepResult r;
  r.collisions = a.collisions;
  // v - v == 0 exactly for finite v and is NaN for NaN or inf (no math library needed)
  r.worst = !(a.probe - a.probe == 0.0) ? 1 : (a.max_overlap > st.max_overlap ? 2 : 0);
  r.max_u2 = a.max_u2;
  if (ADVANCE && r.worst == 0) {  // the next positions and drift velocities take over
    p.pos.swap(w.pos);
    p.vel.swap(w.vel);
  }
  return r;
}

/// The pass compiled for the step: with the fast Coulomb part the slow forces are always given.
template <class Potential, bool ADVANCE>
ContactStepResult forcePassFor(ParticleData& p, const NeighborList& nl, const common::Box& box,
                               const typename Potential::Params& params, const ContactStep& st,
                               ContactWork& w) {
  const bool fast = st.fast.r2 > 0.0;
  if (st.dq) {
    if (fast) return forcePass<Potential, true, true, true, ADVANCE>(p, nl, box, params, st, w);
    return st.ext_fx ? forcePass<Potential, true, false, true, ADVANCE>(p, nl, box, params, st, w)
                     : forcePass<Potential, false, false, true, ADVANCE>(p, nl, box, params, st, w);
  }
  if (fast) return forcePass<Potential, true, true, false, ADVANCE>(p, nl, box, params, st, w);
  return st.ext_fx ? forcePass<Potential, true, false, false, ADVANCE>(p, nl, box, params, st, w)
                   : forcePass<Potential, false, false, false, ADVANCE>(p, nl, box, params, st, w);
}

template <class Potential>
ContactStepResult computeContactForcesOf(ParticleData& p, const NeighborList& nl,
                                         const common::Box& box,
                                         const typename Potential::Params& params,
                                         const ContactStep& st, ContactWork& w) {
  const bool fast = st.fast.r2 > 0.0;
  if (fast && (nl.listRange() < st.fast.r2 || !st.fast_table.data))
    throw std::logic_error("neighbour list range below the fast Coulomb range");
  if (st.advance_dt > 0.0) {
    if (st.advance_dt != st.dt)
      throw std::logic_error("computeContactForces: advance_dt differs from dt (ContactStep)");
    return forcePassFor<Potential, true>(p, nl, box, params, st, w);
  }
  return forcePassFor<Potential, false>(p, nl, box, params, st, w);
}

template <class Potential>
ContactSummary contactSummaryOf(const ParticleData& p, const NeighborList& nl,
                                const common::Box& box, const typename Potential::Params& params) {
  const int N = static_cast<int>(p.size());
  SummaryFunctor<Potential> s{raw(p.pos), nl.rows(), nl.counts(), nl.capacity(), box, params};
  DVec<ContactSummary> per_slot(p.size());
  thrust::transform(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N),
                    per_slot.begin(), s);
  return reduceById(per_slot, p.id, ContactSummary{}, CombineSummary{});  // restart: same bits
}

template <class Potential>
void maxOverlapPerParticleOf(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                             const typename Potential::Params& params, DVec<double>& out) {
  const int N = static_cast<int>(p.size());
  out.resize(p.size());
  SummaryFunctor<Potential> s{raw(p.pos), nl.rows(), nl.counts(), nl.capacity(), box, params};
  thrust::transform(thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(N),
                    out.begin(), MaxOverlapOf<Potential>{s});
}

// The public entry points dispatch on the model (ContactModels.h); std::visit instantiates the
// passes for every model in the list.
ContactStepResult computeContactForces(ParticleData& p, const NeighborList& nl,
                                       const common::Box& box, const ContactModel& model,
                                       const ContactStep& st, ContactWork& w) {
  return std::visit(
      [&](const auto& c) {
        using Model = typename std::decay_t<decltype(c)>::Model;
        return computeContactForcesOf<Model>(p, nl, box, c.params, st, w);
      },
      model);
}

ContactSummary contactSummary(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                              const ContactModel& model) {
  return std::visit(
      [&](const auto& c) {
        using Model = typename std::decay_t<decltype(c)>::Model;
        return contactSummaryOf<Model>(p, nl, box, c.params);
      },
      model);
}

double maxPairImpactSpeed2(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                           const ContactModel& model, double coulomb_K, double m_eff) {
  const int N = static_cast<int>(p.size());
  return std::visit(
      [&](const auto& c) {
        using Model = typename std::decay_t<decltype(c)>::Model;
        const PairImpactSpeed2Of<Model> f{raw(p.pos),  raw(p.vel),    nl.rows(),
                                          nl.counts(), nl.capacity(), box,
                                          c.params,    coulomb_K,     m_eff};
        return thrust::transform_reduce(thrust::counting_iterator<int>(0),
                                        thrust::counting_iterator<int>(N), f, 0.0,
                                        thrust::maximum<double>());
      },
      model);
}

void maxOverlapPerParticle(const ParticleData& p, const NeighborList& nl, const common::Box& box,
                           const ContactModel& model, DVec<double>& out) {
  std::visit(
      [&](const auto& c) {
        using Model = typename std::decay_t<decltype(c)>::Model;
        maxOverlapPerParticleOf<Model>(p, nl, box, c.params, out);
      },
      model);
}

}  // namespace granagg::md
