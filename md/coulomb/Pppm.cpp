#include "md/coulomb/Pppm.h"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <thrust/copy.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/sort.h>
#include <thrust/transform.h>

#include "common/HostDevice.h"
#include "md/engine/ParticleData.h"  // DVec, raw
#include "md/engine/PhaseTimer.h"
#include "md/fft/Fft3d.h"

namespace granagg::md {

namespace {

constexpr double PI = 3.14159265358979323846;
constexpr int MAX_ORDER = 7;
/// Aliases |m_d| <= ALIAS_RANGE in the numerator of the optimal influence function (Hockney &
/// Eastwood; Deserno & Holm 1998 use 2: the terms fall off as sinc^{2P}).
constexpr int ALIAS_RANGE = 2;
/// Block length of the deterministic sums (fixed, so partial sums never depend on thread count).
constexpr long SUM_BLOCK = 1024;

/// sin(x) / x, 1 at x = 0.
HD inline double sinc(double x) { return fabs(x) < 1e-12 ? 1.0 : sin(x) / x; }

/// Wave number (in units 2 pi / L) of FFT index idx on a mesh of M points: idx for idx <= M/2,
/// idx - M above (the first Brillouin zone).
HD inline int waveIndex(int idx, int M) { return idx <= M / 2 ? idx : idx - M; }

/// Mesh coordinate u = x / h wrapped into [0, M). A non-finite x maps to 0: the result is then
/// meaningless but every mesh index stays in range (the engine detects NaN positions itself).
HD inline double meshCoordinate(double x, double inv_h, int M) {
  double u = x * inv_h;
  u -= M * floor(u / M);
  if (u >= M) u -= M;  // rounding: u = M - tiny can land on M
  return (u >= 0.0 && u < M) ? u : 0.0;
}

/// Charge-assignment weights of order P (Hockney & Eastwood's W^(P), the cardinal B-spline M_P
/// centred on the mesh point) for a particle at mesh coordinate u: the P mesh points
/// j_max - p (p = 0..P-1) with j_max = floor(u + P/2) receive a[p] = M_P(w + p), where
/// w = u + P/2 - j_max in [0, 1). Cox-de Boor recursion M_n(t) = [t M_{n-1}(t) + (n - t)
/// M_{n-1}(t-1)] / (n - 1), starting from M_2(w) = w, M_2(w + 1) = 1 - w; the weights sum to 1.
/// Returns j_max (not wrapped).
HD inline int assignmentWeights(double u, int P, double* a) {
  const double s = u + 0.5 * P;
  const double jf = floor(s);
  const double w = s - jf;
  for (int p = 0; p < P; ++p) a[p] = 0.0;
  a[0] = w;
  a[1] = 1.0 - w;
  for (int n = 3; n <= P; ++n)
    for (int p = n - 1; p >= 0; --p)
      a[p] = ((w + p) * a[p] + (n - w - p) * (p > 0 ? a[p - 1] : 0.0)) / (n - 1);
  return static_cast<int>(jf);
}

constexpr int N_ALIAS = 2 * ALIAS_RANGE + 1;

/// Hockney-Eastwood optimal influence function for ik-differentiation (Deserno & Holm 1998 I,
/// eq. 31 with D(k) = i k and the Ewald reference force R(k) = -i k (4 pi / k^2)
/// exp(-k^2/4alpha^2)):
///     G_opt(k) = (4 pi / k^2) sum_m (k.k_m / k_m^2) exp(-k_m^2 / 4 alpha^2) U^2(k_m) / [sum_m
///     U^2(k_m)]^2,
/// k_m = k + 2 pi m / h, U(k) = prod_d sinc(k_d h / 2)^P. The numerator's alias sum runs over
/// |m_d| <= ALIAS_RANGE; the denominator factorises into 1-D sums, precomputed (den1d) to
/// convergence. The exponential and U^2 factorise too: 1-D tables per FFT index i and alias m
/// (q: k_m component, e: exp(-q^2/4alpha^2), u: sinc(q h/2)^{2P}) keep the 3-D loop to products.
/// Indexed like the r2c output: (ix, iy, iz), iz <= M/2.
///
/// Also, per k point with its multiplicity in the half spectrum, the self-energy term: the exact
/// reciprocal-space self interaction of a unit charge, sum_m phi(k_m) with phi(k) = (4 pi / k^2)
/// exp(-k^2 / 4 alpha^2), minus its position average on the mesh, G(k) sum_m U^2(k_m) (the mean of
/// |Q(k)|^2 for one unit charge is sum_m U^2(k_m), Hockney & Eastwood). Summed and times K / 2V it
/// is the mean P3M self-energy error per unit q^2 (Ballenegger, Cerda & Holm, J. Chem. Theory
/// Comput. 8, 936 (2012)), which compute() removes from the mesh energy.
struct InfluenceFunction {
  int M;
  const double *den1d, *tq, *te, *tu;
  double *G, *self_term;
  HD void operator()(long idx) const {
    const int Mz = M / 2 + 1;
    const int iz = static_cast<int>(idx % Mz);
    const int iy = static_cast<int>((idx / Mz) % M);
    const int ix = static_cast<int>(idx / (long(Mz) * M));
    const double* qx = tq + ix * N_ALIAS;
    const double* qy = tq + iy * N_ALIAS;
    const double* qz = tq + iz * N_ALIAS;
    const double kx = qx[ALIAS_RANGE], ky = qy[ALIAS_RANGE], kz = qz[ALIAS_RANGE];  // m = 0
    const double k2 = kx * kx + ky * ky + kz * kz;
    double sum = 0.0, exact = 0.0;
    for (int a = 0; a < N_ALIAS; ++a)
      for (int b = 0; b < N_ALIAS; ++b) {
        const double exy = te[ix * N_ALIAS + a] * te[iy * N_ALIAS + b];
        const double uexy = exy * tu[ix * N_ALIAS + a] * tu[iy * N_ALIAS + b];
        const double dxy = kx * qx[a] + ky * qy[b], q2xy = qx[a] * qx[a] + qy[b] * qy[b];
        for (int c = 0; c < N_ALIAS; ++c) {
          const double q2 = q2xy + qz[c] * qz[c];
          if (q2 == 0.0) continue;  // k = 0 itself
          const double inv_q2 = 1.0 / q2;
          const double e = exy * te[iz * N_ALIAS + c];
          sum += (dxy + kz * qz[c]) * inv_q2 * uexy * te[iz * N_ALIAS + c] * tu[iz * N_ALIAS + c];
          exact += 4.0 * PI * inv_q2 * e;
        }
      }
    const double den = den1d[ix] * den1d[iy] * den1d[iz];
    // k = 0 excluded (tinfoil; the background term handles a net charge)
    const double g = k2 == 0.0 ? 0.0 : 4.0 * PI / k2 * sum / (den * den);
    G[idx] = g;
    const double mult = (iz == 0 || (M % 2 == 0 && iz == M / 2)) ? 1.0 : 2.0;
    self_term[idx] = mult * (exact - g * den);
  }
};

/// Mesh cell key of slot i: cell index of the stencil's top point j_max (wrapped), times n, plus
/// the particle id, so that sorting by key orders by cell, then by id (keys are unique).
struct CellKey {
  const double *x, *y, *z;
  long stride;  // doubles between consecutive particles (1: separate arrays; 4: Scalar4 records)
  const int* id;
  double inv_h;
  int M, P;
  long long n;
  long long* key;
  int* order;
  HD void operator()(int i) const {
    double a[MAX_ORDER];
    const long o = i * stride;
    const int jx = assignmentWeights(meshCoordinate(x[o], inv_h, M), P, a) % M;
    const int jy = assignmentWeights(meshCoordinate(y[o], inv_h, M), P, a) % M;
    const int jz = assignmentWeights(meshCoordinate(z[o], inv_h, M), P, a) % M;
    const long long cell = (static_cast<long long>(jx) * M + jy) * M + jz;
    key[i] = cell * n + (id ? id[i] : i);
    order[i] = i;
  }
};

/// For sorted particle k: weights (P per dimension), stencil top j_max per dimension, charge and
/// cell.
struct SortedSetup {
  const double *x, *y, *z, *q;
  long stride;
  const long long* key;
  const int* order;
  double inv_h;
  int M, P;
  long long n;
  double *wx, *wy, *wz, *qs;
  int *jx, *jy, *jz;
  long long* cell;
  HD void operator()(int k) const {
    const long o = order[k] * stride;
    jx[k] = assignmentWeights(meshCoordinate(x[o], inv_h, M), P, wx + static_cast<long>(k) * P) % M;
    jy[k] = assignmentWeights(meshCoordinate(y[o], inv_h, M), P, wy + static_cast<long>(k) * P) % M;
    jz[k] = assignmentWeights(meshCoordinate(z[o], inv_h, M), P, wz + static_cast<long>(k) * P) % M;
    qs[k] = q[o];
    cell[k] = key[k] / n;
  }
};

/// Charge assignment without atomics, in a fixed order (deterministic whatever the thread count):
/// the mesh is cut into T tiles per dimension (T even, each tile at least P cells wide), and the
/// tiles are processed in 8 passes by parity colour (tx % 2, ty % 2, tz % 2). A particle in cell
/// j_max writes to j_max - P + 1 .. j_max, so tiles of one colour, separated by a tile of width
/// >= P (also across the periodic boundary, since T is even), never write to the same mesh point:
/// one thread per tile scatters the particles of its cells, in sorted order, with plain adds.
/// Work O(N P^3 + M^3), against O(M^3 P^2) range look-ups for a per-mesh-point gather. Meshes
/// narrower than 2P use one tile (T = 1), processed serially.
struct ScatterTile {
  const double *wx, *wy, *wz, *qs;
  const int *jx, *jy, *jz;
  const int* start;  // particles of cell c: sorted slots start[c] .. start[c+1]-1
  int M, P, T;
  int colour_x, colour_y, colour_z;  // parity of the tiles of this pass (0 when T = 1)
  double* mesh;
  HD void operator()(int tile) const {
    const int half = T == 1 ? 1 : T / 2;  // tiles of one colour per dimension
    const int tz = 2 * (tile % half) + colour_z, ty = 2 * ((tile / half) % half) + colour_y,
              tx = 2 * (tile / (half * half)) + colour_x;
    const int x0 = static_cast<int>(long(tx) * M / T), x1 = static_cast<int>(long(tx + 1) * M / T);
    const int y0 = static_cast<int>(long(ty) * M / T), y1 = static_cast<int>(long(ty + 1) * M / T);
    const int z0 = static_cast<int>(long(tz) * M / T), z1 = static_cast<int>(long(tz + 1) * M / T);
    for (int cx = x0; cx < x1; ++cx)
      for (int cy = y0; cy < y1; ++cy) {
        const long row = (static_cast<long>(cx) * M + cy) * M;
        // cells z0..z1-1 of this row are one contiguous range of sorted particles
        for (int k = start[row + z0]; k < start[row + z1]; ++k) {
          const long kp = static_cast<long>(k) * P;
          const double qk = qs[k];
          // mesh points j_max - p, wrapped by comparison (integer division is slow). A stencil
          // that does not wrap in z (j_max >= P - 1: most particles) runs over one contiguous
          // block without the test; every mesh point still gets the same adds in the same order.
          const bool z_inside = jz[k] >= P - 1;
          for (int px = 0, gx = jx[k]; px < P; ++px, gx = gx == 0 ? M - 1 : gx - 1)
            for (int py = 0, gy = jy[k]; py < P; ++py, gy = gy == 0 ? M - 1 : gy - 1) {
              const double qw = qk * wx[kp + px] * wy[kp + py];
              const long mrow = (static_cast<long>(gx) * M + gy) * M;
              if (z_inside) {
                double* m = mesh + mrow + jz[k];
                const double* w = wz + kp;
                for (int pz = 0; pz < P; ++pz) m[-pz] += qw * w[pz];
              } else {
                for (int pz = 0, gz = jz[k]; pz < P; ++pz, gz = gz == 0 ? M - 1 : gz - 1)
                  mesh[mrow + gz] += qw * wz[kp + pz];
              }
            }
        }
      }
  }
};

/// Adds v to *p atomically (64-bit integers: any order gives the same sum).
HD inline void atomicAddInteger(unsigned long long* p, unsigned long long v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(p, v);
#else
  __atomic_fetch_add(p, v, __ATOMIC_RELAXED);
#endif
}

/// x rounded to the nearest integer, ties to even, on both backends.
HD inline long long roundToInteger(double x) {
#if defined(__CUDA_ARCH__)
  return __double2ll_rn(x);
#else
  return std::llrint(x);  // the default rounding mode: to nearest, ties to even
#endif
}

/// ChargeAssignment::FixedPoint: one thread per particle adds its P^3 stencil terms to the mesh
/// with 64-bit integer atomics on the charge in fixed point (units of 1 / scale). Integer addition
/// is associative, so the mesh is the same whatever order the threads run in: deterministic
/// without ScatterTile's colour passes, whose one thread per tile serialises the dense tiles of a
/// clustered gas on a GPU (docs/gpu.md). `scale` keeps every partial sum within 2^61
/// (Pppm::run); each term's rounding, at most 0.5 / scale, lies far below the accuracy that the
/// PPPM and backend tests resolve.
struct ScatterFixedPoint {
  const double *wx, *wy, *wz, *qs;
  const int *jx, *jy, *jz;
  int M, P;
  double scale;
  unsigned long long* mesh;  // two's complement: wrapping unsigned adds are signed adds
  HD void operator()(int k) const {
    const long kp = static_cast<long>(k) * P;
    const double qk = qs[k] * scale;
    for (int px = 0, gx = jx[k]; px < P; ++px, gx = gx == 0 ? M - 1 : gx - 1)
      for (int py = 0, gy = jy[k]; py < P; ++py, gy = gy == 0 ? M - 1 : gy - 1) {
        const double qw = qk * wx[kp + px] * wy[kp + py];
        const long mrow = (static_cast<long>(gx) * M + gy) * M;
        for (int pz = 0, gz = jz[k]; pz < P; ++pz, gz = gz == 0 ? M - 1 : gz - 1)
          atomicAddInteger(mesh + mrow + gz,
                           static_cast<unsigned long long>(roundToInteger(qw * wz[kp + pz])));
      }
  }
};

/// Fixed-point mesh charge back to a double.
struct FromFixedPoint {
  double inv_scale;
  HD double operator()(unsigned long long v) const {
    return static_cast<double>(static_cast<long long>(v)) * inv_scale;
  }
};

/// First sorted slot of every cell: start[c] = k for the cells c in (cell[k-1], cell[k]] (and
/// start[M^3] = n). Every entry is written exactly once, by the particle that opens it.
struct CellStart {
  const long long* cell;
  long n, ncell;
  int* start;
  HD void operator()(long k) const {
    const long lo = k == 0 ? 0 : static_cast<long>(cell[k - 1]) + 1;
    const long hi = k == n ? ncell : static_cast<long>(cell[k]);
    for (long c = lo; c <= hi; ++c) start[c] = static_cast<int>(k);
  }
};

/// |Q(k)|^2 G(k) with the multiplicity of the half spectrum (planes iz = 0 and, for even M,
/// iz = M/2 stand for themselves; every other iz also for its mirror -k).
struct EnergyTerm {
  const double *G, *c;
  int M;
  double* out;
  HD void operator()(long idx) const {
    const int Mz = M / 2 + 1;
    const int iz = static_cast<int>(idx % Mz);
    const double mult = (iz == 0 || (M % 2 == 0 && iz == M / 2)) ? 1.0 : 2.0;
    const double re = c[2 * idx], im = c[2 * idx + 1];
    out[idx] = mult * G[idx] * (re * re + im * im);
  }
};

/// Field spectrum of component d: E_d(k) = -i k_d G(k) Q(k) / V. k_d = 0 on the Nyquist plane of an
/// even mesh, where the sign of k_d is ambiguous (keeps the spectrum Hermitian, the field real).
struct FieldSpectrum {
  const double *G, *c;
  int M, dim;
  double unit_over_V;  // (2 pi / L) / V
  double* out;
  HD void operator()(long idx) const {
    const int Mz = M / 2 + 1;
    int i;
    if (dim == 2)
      i = static_cast<int>(idx % Mz);
    else if (dim == 1)
      i = static_cast<int>((idx / Mz) % M);
    else
      i = static_cast<int>(idx / (long(Mz) * M));
    const int w = (M % 2 == 0 && i == M / 2) ? 0 : waveIndex(i, M);
    const double f = unit_over_V * w * G[idx];
    const double re = c[2 * idx], im = c[2 * idx + 1];
    out[2 * idx] = f * im;  // -i f (re + i im) = f im - i f re
    out[2 * idx + 1] = -f * re;
  }
};

/// Mesh force on sorted particle k, added to its slot: F = K q sum_stencil W E (per-particle
/// gather).
struct Interpolate {
  const double *wx, *wy, *wz, *qs, *ex, *ey, *ez;
  const int *jx, *jy, *jz, *order;
  int M, P;
  double K;
  double *fx, *fy, *fz;
  HD void operator()(int k) const {
    const long kp = static_cast<long>(k) * P;
    double f0 = 0.0, f1 = 0.0, f2 = 0.0;
    const bool z_inside = jz[k] >= P - 1;
    // mesh points j_max - p, wrapped by comparison (integer division is slow)
    for (int px = 0, gx = jx[k]; px < P; ++px, gx = gx == 0 ? M - 1 : gx - 1) {
      for (int py = 0, gy = jy[k]; py < P; ++py, gy = gy == 0 ? M - 1 : gy - 1) {
        const double wxy = wx[kp + px] * wy[kp + py];
        const long row = (static_cast<long>(gx) * M + gy) * M;
        if (z_inside) {  // no wrap in z: the same terms in the same order, without the test
          const long g0 = row + jz[k];
          for (int pz = 0; pz < P; ++pz) {
            const double w = wxy * wz[kp + pz];
            f0 += w * ex[g0 - pz];
            f1 += w * ey[g0 - pz];
            f2 += w * ez[g0 - pz];
          }
          continue;
        }
        for (int pz = 0, gz = jz[k]; pz < P; ++pz, gz = gz == 0 ? M - 1 : gz - 1) {
          const long g = row + gz;
          const double w = wxy * wz[kp + pz];
          f0 += w * ex[g];
          f1 += w * ey[g];
          f2 += w * ez[g];
        }
      }
    }
    const int i = order[k];
    const double s = K * qs[k];
    fx[i] += s * f0;
    fy[i] += s * f1;
    fz[i] += s * f2;
  }
};

/// Block b of a deterministic sum: v[b B] + ... in index order (plain and squared).
struct BlockSum {
  const double* v;
  long n, stride;
  bool square;
  double* out;
  HD void operator()(long b) const {
    const long end = (b + 1) * SUM_BLOCK < n ? (b + 1) * SUM_BLOCK : n;
    double s = 0.0;
    for (long i = b * SUM_BLOCK; i < end; ++i) {
      const double x = v[i * stride];
      s += square ? x * x : x;
    }
    out[b] = s;
  }
};

}  // namespace

struct Pppm::Impl {
  PppmParams params;
  double L, K, h, V;
  int M, P;
  Fft3d fft;
  DVec<double> G;               // influence function, r2c layout
  DVec<double> mesh;            // assigned charges (M^3)
  DVec<double> spectrum, work;  // 2 * complexSize doubles
  DVec<double> ex, ey, ez;      // field components on the mesh
  DVec<long long> key, cell;    // sort keys, cell of each sorted particle
  DVec<int> order, start, jx, jy, jz;
  DVec<double> wx, wy, wz, qs;
  DVec<double> terms, blocks;
  DVec<unsigned long long> mesh_fixed;  // ChargeAssignment::FixedPoint's mesh (ScatterFixedPoint)
  int tiles = 1;                 // tiles per dimension of the charge assignment (ScatterTile)
  double self_correction = 0.0;  // mean P3M self-energy error per unit q^2 (SelfEnergyTerm)
  PppmEnergies energies;
  bool computed = false;
  PhaseTimer* timer = nullptr;  // setPhaseTimer

  /// compute() for particle data with `stride` doubles between consecutive particles.
  double run(const double* x, const double* y, const double* z, const double* q, long stride,
             std::size_t n, double* fx, double* fy, double* fz, const int* id);

  Impl(const PppmParams& p, double L_, double K_)
      : params(p),
        L(L_),
        K(K_),
        h(L_ / p.mesh),
        V(L_ * L_ * L_),
        M(p.mesh),
        P(p.order),
        fft(p.mesh, p.mesh, p.mesh) {}

  /// Deterministic sum of n device values (squares if `square`): fixed blocks, then the block sums
  /// in order on the host.
  double sum(const double* v, long n, bool square, long stride = 1) {
    const long nb = (n + SUM_BLOCK - 1) / SUM_BLOCK;
    blocks.resize(nb);
    thrust::for_each(thrust::counting_iterator<long>(0), thrust::counting_iterator<long>(nb),
                     BlockSum{v, n, stride, square, raw(blocks)});
    std::vector<double> hb(nb);
    thrust::copy(blocks.begin(), blocks.end(), hb.begin());
    double s = 0.0;
    for (double b : hb) s += b;
    return s;
  }
};

Pppm::Pppm(const PppmParams& params, double L, double K) {
  std::ostringstream msg;
  if (!(L > 0.0) || !std::isfinite(L))
    msg << "Pppm requires a positive box length L (got " << L << ").";
  else if (!(K >= 0.0) || !std::isfinite(K))
    msg << "Pppm requires a coupling K >= 0 (got " << K << ").";
  else if (!(params.alpha > 0.0))
    msg << "Pppm requires alpha > 0 (got " << params.alpha << ").";
  else if (params.order < 2 || params.order > MAX_ORDER)
    msg << "Pppm requires order in 2..7 (got " << params.order << ").";
  else if (params.mesh < params.order)
    msg << "Pppm requires mesh >= order (got mesh " << params.mesh << ").";
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
  m_impl.reset(new Impl(params, L, K));
  Impl& s = *m_impl;
  const int M = s.M;
  // 1-D tables: alias sums of the denominator to convergence (terms fall off as m^{-2P}, P >= 2),
  // and per alias |m| <= ALIAS_RANGE the wave number, Gaussian and sinc^{2P} factors
  std::vector<double> den(M), tq(M * N_ALIAS), te(M * N_ALIAS), tu(M * N_ALIAS);
  const double inv_4a2 = 0.25 / (params.alpha * params.alpha);
  for (int i = 0; i < M; ++i) {
    const double k = 2.0 * PI / L * waveIndex(i, M);
    const double x = 0.5 * k * s.h;
    double d = 0.0;
    for (int m = -50; m <= 50; ++m) d += std::pow(sinc(x + PI * m), 2 * s.P);
    den[i] = d;
    for (int m = -ALIAS_RANGE; m <= ALIAS_RANGE; ++m) {
      const double q = k + 2.0 * PI / s.h * m;
      tq[i * N_ALIAS + m + ALIAS_RANGE] = q;
      te[i * N_ALIAS + m + ALIAS_RANGE] = std::exp(-q * q * inv_4a2);
      tu[i * N_ALIAS + m + ALIAS_RANGE] = std::pow(sinc(0.5 * q * s.h), 2 * s.P);
    }
  }
  const DVec<double> d_den(den.begin(), den.end()), d_tq(tq.begin(), tq.end()),
      d_te(te.begin(), te.end()), d_tu(tu.begin(), tu.end());
  const long nc = static_cast<long>(s.fft.complexSize());
  s.G.resize(nc);
  s.terms.resize(nc);
  thrust::for_each(
      thrust::counting_iterator<long>(0), thrust::counting_iterator<long>(nc),
      InfluenceFunction{M, raw(d_den), raw(d_tq), raw(d_te), raw(d_tu), raw(s.G), raw(s.terms)});
  s.self_correction = K / (2.0 * s.V) * s.sum(raw(s.terms), nc, false);
  const long nr = static_cast<long>(s.fft.realSize());
  s.mesh.resize(nr);
  s.ex.resize(nr);
  s.ey.resize(nr);
  s.ez.resize(nr);
  s.spectrum.resize(2 * nc);
  s.work.resize(2 * nc);
  s.start.resize(nr + 1);
  // largest even tile count with tiles at least P cells wide (1: one serial tile)
  s.tiles = (M / s.P) / 2 * 2;
  if (s.tiles < 2) s.tiles = 1;
}

Pppm::~Pppm() = default;

double Pppm::compute(const double* x, const double* y, const double* z, const double* q,
                     std::size_t n, double* fx, double* fy, double* fz, const int* id) {
  return m_impl->run(x, y, z, q, 1, n, fx, fy, fz, id);
}

double Pppm::compute(const double* pos4, std::size_t n, double* fx, double* fy, double* fz,
                     const int* id) {
  return m_impl->run(pos4, pos4 + 1, pos4 + 2, pos4 + 3, 4, n, fx, fy, fz, id);
}

double Pppm::Impl::run(const double* x, const double* y, const double* z, const double* q,
                       long stride, std::size_t n, double* fx, double* fy, double* fz,
                       const int* id) {
  Impl& s = *this;
  const int N = static_cast<int>(n);
  const int M = s.M, P = s.P;
  const long nr = static_cast<long>(s.fft.realSize());
  const long nc = static_cast<long>(s.fft.complexSize());
  const double inv_h = 1.0 / s.h;
  using thrust::counting_iterator;

  using Scope = PhaseTimer::Scope;
  // 1. sort particles by (stencil cell, id)
  std::optional<Scope> phase(std::in_place, s.timer, PhaseTimer::PppmSort);
  s.key.resize(n);
  s.order.resize(n);
  thrust::for_each(counting_iterator<int>(0), counting_iterator<int>(N),
                   CellKey{x, y, z, stride, id, inv_h, M, P, static_cast<long long>(n), raw(s.key),
                           raw(s.order)});
  thrust::sort_by_key(s.key.begin(), s.key.end(), s.order.begin());
  for (auto* v : {&s.wx, &s.wy, &s.wz}) v->resize(n * P);
  for (auto* v : {&s.jx, &s.jy, &s.jz}) v->resize(n);
  s.qs.resize(n);
  s.cell.resize(n);
  thrust::for_each(counting_iterator<int>(0), counting_iterator<int>(N),
                   SortedSetup{x, y, z, q, stride, raw(s.key), raw(s.order), inv_h, M, P,
                               static_cast<long long>(n), raw(s.wx), raw(s.wy), raw(s.wz),
                               raw(s.qs), raw(s.jx), raw(s.jy), raw(s.jz), raw(s.cell)});
  thrust::for_each(counting_iterator<long>(0), counting_iterator<long>(static_cast<long>(n) + 1),
                   CellStart{raw(s.cell), static_cast<long>(n), nr, raw(s.start)});
  // self and background energies from sum q, sum q^2, summed in the sorted order (cell, id):
  // the same bits whatever the order the caller stores its particles in (a restart's differs)
  const double sum_q = s.sum(raw(s.qs), N, false), sum_q2 = s.sum(raw(s.qs), N, true);
  s.energies.self = EwaldReference::selfEnergy(s.params.alpha, s.K, sum_q2);
  s.energies.background = EwaldReference::backgroundEnergy(s.params.alpha, s.K, s.L, sum_q);

  // 2. charge assignment (ChargeAssignment: tiles by colour, ScatterTile, or fixed-point
  // atomics, ScatterFixedPoint) and forward FFT
  phase.emplace(s.timer, PhaseTimer::PppmAssign);
  if (s.params.assignment == ChargeAssignment::FixedPoint) {
    // |any partial sum of a mesh point| <= sum |q| <= sqrt(N sum q^2) (Cauchy-Schwarz) = bound;
    // the largest power of two with bound * scale <= 2^61 leaves room for the terms' rounding
    const double bound = std::sqrt(static_cast<double>(n) * sum_q2);
    const double scale = bound > 0.0 ? std::ldexp(1.0, 60 - std::ilogb(bound)) : 1.0;
    s.mesh_fixed.resize(nr);
    thrust::fill(s.mesh_fixed.begin(), s.mesh_fixed.end(), 0ull);
    thrust::for_each(counting_iterator<int>(0), counting_iterator<int>(N),
                     ScatterFixedPoint{raw(s.wx), raw(s.wy), raw(s.wz), raw(s.qs), raw(s.jx),
                                       raw(s.jy), raw(s.jz), M, P, scale, raw(s.mesh_fixed)});
    thrust::transform(s.mesh_fixed.begin(), s.mesh_fixed.end(), s.mesh.begin(),
                      FromFixedPoint{1.0 / scale});
  } else {
    thrust::fill(s.mesh.begin(), s.mesh.end(), 0.0);
    const int T = s.tiles;
    const int colours = T == 1 ? 1 : 2;
    const int tiles_per_pass = T == 1 ? 1 : (T / 2) * (T / 2) * (T / 2);
    for (int cx = 0; cx < colours; ++cx)
      for (int cy = 0; cy < colours; ++cy)
        for (int cz = 0; cz < colours; ++cz)
          thrust::for_each(counting_iterator<int>(0), counting_iterator<int>(tiles_per_pass),
                           ScatterTile{raw(s.wx), raw(s.wy), raw(s.wz), raw(s.qs), raw(s.jx),
                                       raw(s.jy), raw(s.jz), raw(s.start), M, P, T, cx, cy, cz,
                                       raw(s.mesh)});
  }
  phase.emplace(s.timer, PhaseTimer::PppmFft);
  s.fft.forward(raw(s.mesh), raw(s.spectrum));
  phase.emplace(s.timer, PhaseTimer::PppmKspace);

  // 3. energy (K / 2V) sum_k G |Q|^2
  thrust::for_each(counting_iterator<long>(0), counting_iterator<long>(nc),
                   EnergyTerm{raw(s.G), raw(s.spectrum), M, raw(s.terms)});
  s.energies.kspace =
      s.K / (2.0 * s.V) * s.sum(raw(s.terms), nc, false) + s.self_correction * sum_q2;

  s.computed = true;
  if (!fx) return s.energies.total();  // the energy alone (Pppm.h): no field, no forces

  // 4. field by ik-differentiation: one inverse FFT per component (backward overwrites `work`)
  DVec<double>* field[3] = {&s.ex, &s.ey, &s.ez};
  for (int d = 0; d < 3; ++d) {
    phase.emplace(s.timer, PhaseTimer::PppmKspace);
    thrust::for_each(
        counting_iterator<long>(0), counting_iterator<long>(nc),
        FieldSpectrum{raw(s.G), raw(s.spectrum), M, d, 2.0 * PI / s.L / s.V, raw(s.work)});
    phase.emplace(s.timer, PhaseTimer::PppmFft);
    s.fft.backward(raw(s.work), raw(*field[d]));
  }
  phase.emplace(s.timer, PhaseTimer::PppmInterpolate);

  // 5. interpolation back to the particles
  thrust::for_each(
      counting_iterator<int>(0), counting_iterator<int>(N),
      Interpolate{raw(s.wx), raw(s.wy), raw(s.wz), raw(s.qs), raw(s.ex), raw(s.ey), raw(s.ez),
                  raw(s.jx), raw(s.jy), raw(s.jz), raw(s.order), M, P, s.K, fx, fy, fz});
  return s.energies.total();
}

CoulombResult Pppm::computeHost(const std::vector<double>& x, const std::vector<double>& y,
                                const std::vector<double>& z, const std::vector<double>& q) {
  const std::size_t n = x.size();
  if (y.size() != n || z.size() != n || q.size() != n)
    throw std::invalid_argument("Pppm::computeHost requires x, y, z and q of equal length.");
  DVec<double> dx(x.begin(), x.end()), dy(y.begin(), y.end()), dz(z.begin(), z.end()),
      dq(q.begin(), q.end());
  DVec<double> fx(n, 0.0), fy(n, 0.0), fz(n, 0.0);
  compute(raw(dx), raw(dy), raw(dz), raw(dq), n, raw(fx), raw(fy), raw(fz));
  CoulombResult r;
  r.energy_kspace = m_impl->energies.kspace;
  r.energy_self = m_impl->energies.self;
  r.energy_background = m_impl->energies.background;
  r.energy = m_impl->energies.total();
  r.fx.resize(n);
  r.fy.resize(n);
  r.fz.resize(n);
  thrust::copy(fx.begin(), fx.end(), r.fx.begin());
  thrust::copy(fy.begin(), fy.end(), r.fy.begin());
  thrust::copy(fz.begin(), fz.end(), r.fz.begin());
  return r;
}

const PppmEnergies& Pppm::lastEnergies() const {
  if (!m_impl->computed)
    throw std::logic_error("Pppm::lastEnergies: nothing has been computed yet.");
  return m_impl->energies;
}
const PppmParams& Pppm::params() const { return m_impl->params; }
double Pppm::boxLength() const { return m_impl->L; }
void Pppm::setPhaseTimer(PhaseTimer* timer) { m_impl->timer = timer; }

}  // namespace granagg::md
