#include "analysis/stats/StructureFactor.h"

#include <fftw3.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/Csv.h"

namespace granagg::analysis {

namespace {

constexpr double PI = 3.14159265358979323846;

struct PlanDeleter {
  void operator()(fftw_plan_s* p) const { fftw_destroy_plan(p); }
};

/// index of a wrapped mesh coordinate
inline std::size_t wrap(long i, long M) { return static_cast<std::size_t>(((i % M) + M) % M); }

}  // namespace

struct StructureFactorMesh::Buffers {
  long M = 0;
  // one in-place real-to-complex transform: M x M x 2 (M/2 + 1) reals, the last dimension
  // padded as FFTW's in-place layout wants, so that the density and its transform share memory
  std::unique_ptr<double, decltype(&fftw_free)> data{nullptr, fftw_free};
  std::unique_ptr<fftw_plan_s, PlanDeleter> plan;
  // velocityStructure: k^.u(k) accumulated over the three components, in single precision (the
  // mesh's memory at M = 512 is 1.1 GB per double buffer; a statistic needs no more digits)
  std::vector<std::complex<float>> longitudinal;
  int threads = 0;  // FFTW threads the plan was made with
  double* rho() { return data.get(); }
  fftw_complex* rk() { return reinterpret_cast<fftw_complex*>(data.get()); }
};

StructureFactorMesh::StructureFactorMesh() : m_buffers(std::make_unique<Buffers>()) {}
StructureFactorMesh::~StructureFactorMesh() = default;

namespace {
/// FFTW's planner and fftw_init_threads are not thread-safe (md/fft/Fft3dFftw.cpp plans under its
/// own lock in the same process: the planner's global state is shared, so this lock is held while
/// planning and the thread count is set right before).
std::mutex planner_lock;

int fftwThreads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}
}  // namespace

StructureFactorMesh::Buffers& StructureFactorMesh::forSize(long M) {
  Buffers& b = *m_buffers;
  const int threads = fftwThreads();
  if (b.M == M && b.plan && b.threads == threads) return b;
  b.plan.reset();
  std::vector<std::complex<float>>().swap(b.longitudinal);
  if (b.M != M) {
    b.data.reset(fftw_alloc_real(static_cast<std::size_t>(M) * M * 2 * (M / 2 + 1)));
    if (!b.data) throw std::runtime_error("structure factor: no memory for the mesh");
  }
  {
    std::lock_guard<std::mutex> lock(planner_lock);
    static const bool threads_ok = fftw_init_threads() != 0;
    if (threads_ok) fftw_plan_with_nthreads(threads);
    // (FFTW_ESTIMATE does not touch the arrays)
    b.plan.reset(fftw_plan_dft_r2c_3d(static_cast<int>(M), static_cast<int>(M),
                                      static_cast<int>(M), b.rho(), b.rk(), FFTW_ESTIMATE));
  }
  if (!b.plan) throw std::runtime_error("structure factor: FFTW could not plan the mesh");
  b.M = M;
  b.threads = threads;
  return b;
}

namespace {

/// The mesh of a frame: M even with h = L / M <= h_max, at most max_mesh.
long meshSize(const Frame& f, const StructureFactorOptions& o, const char* what) {
  if (f.size() == 0) throw std::invalid_argument(std::string(what) + ": the frame has no particles");
  if (!(f.box > 0.0) || !std::isfinite(f.box))
    throw std::invalid_argument(std::string(what) + ": the box edge must be positive");
  if (!(o.h_max > 0.0) || !(o.k_cut > 0.0) || o.max_mesh < 8)
    throw std::invalid_argument(std::string(what) +
                                ": h_max and k_cut must be > 0, max_mesh >= 8");
  long M = static_cast<long>(std::ceil(f.box / o.h_max));
  M += M % 2;
  return std::clamp<long>(M, 8, static_cast<long>(o.max_mesh) - static_cast<long>(o.max_mesh % 2));
}

/// Cloud-in-cell assignment of the weights w_j (unit masses when `weights` is null) onto the
/// padded mesh (cell centres at (i + 1/2) h are not needed: a shift of the mesh changes only the
/// phase of the transform).
void assign(const Frame& f, long M, double h, const double* weights, std::size_t stride,
            double* rho) {
  const long P = 2 * (M / 2 + 1);
  std::fill(rho, rho + static_cast<std::size_t>(M) * M * P, 0.0);
  for (std::size_t j = 0; j < f.size(); ++j) {
    long i0[3];
    double w1[3];
    for (int a = 0; a < 3; ++a) {
      const double u = f.position[3 * j + a] / h;
      const double fl = std::floor(u);
      i0[a] = static_cast<long>(fl);
      w1[a] = u - fl;
    }
    const double q = weights ? weights[stride * j] : 1.0;
    for (int dx = 0; dx < 2; ++dx)
      for (int dy = 0; dy < 2; ++dy)
        for (int dz = 0; dz < 2; ++dz) {
          const double w =
              (dx ? w1[0] : 1.0 - w1[0]) * (dy ? w1[1] : 1.0 - w1[1]) * (dz ? w1[2] : 1.0 - w1[2]);
          rho[(wrap(i0[0] + dx, M) * M + wrap(i0[1] + dy, M)) * P + wrap(i0[2] + dz, M)] += q * w;
        }
  }
}

/// The wave vectors of the complete shells m = 1 .. shells below the Nyquist wavenumber pi / h
/// (every |n_a| < M / 2), one of each pair +-k (the transform at -k is the conjugate of that at
/// k), with the CIC window's aliased sum for uncorrelated positions (Jing 2005, eq. 20) from
/// per-axis tables and the shell from a table of |n|^2.
struct Modes {
  long M, Mz, shells;
  std::vector<double> alias;  // per index i: the window factor of component n(i)
  std::vector<long> shell;    // per |n|^2: round(|n|), or 0 when out of the shells
  std::vector<double> inv_norm;  // per |n|^2: 1 / |n| (0 for n = 0)
  Modes(long M_, double h, double dk, long shells_) : M(M_), Mz(M_ / 2 + 1), shells(shells_) {
    alias.resize(static_cast<std::size_t>(M));
    for (long i = 0; i < M; ++i) {
      const double s = std::sin(0.5 * dk * static_cast<double>(component(i)) * h);
      alias[static_cast<std::size_t>(i)] = 1.0 - (2.0 / 3.0) * s * s;
    }
    const long half = M / 2;
    shell.assign(static_cast<std::size_t>(3 * half * half + 1), 0);
    inv_norm.assign(shell.size(), 0.0);
    for (std::size_t n2 = 0; n2 < shell.size(); ++n2) {
      const double norm = std::sqrt(static_cast<double>(n2));
      const long m = std::lround(norm);
      shell[n2] = m <= shells ? m : 0;
      if (n2 > 0) inv_norm[n2] = 1.0 / norm;
    }
  }
  long component(long i) const { return i <= M / 2 ? i : i - M; }
};

/// Fixed blocks of the outermost mesh index: the per-shell sums are made per block and added in
/// block order, so that the result does not depend on the number of threads.
constexpr long MODE_BLOCKS = 64;

/// Calls visit(block, index, m, nx, ny, nz, window) for every mode of `modes` (threads over the
/// blocks); `index` addresses the transform.
template <class Visit>
void forEachMode(const Modes& modes, Visit&& visit) {
  const long M = modes.M, Mz = modes.Mz;
#pragma omp parallel for schedule(dynamic, 1)
  for (long block = 0; block < MODE_BLOCKS; ++block) {
    const long begin = block * M / MODE_BLOCKS, end = (block + 1) * M / MODE_BLOCKS;
    for (long ix = begin; ix < end; ++ix) {
      const long nx = modes.component(ix);
      const double ax = modes.alias[static_cast<std::size_t>(ix)];
      for (long iy = 0; iy < M; ++iy) {
        const long ny = modes.component(iy);
        const double axy = ax * modes.alias[static_cast<std::size_t>(iy)];
        const std::size_t row = (static_cast<std::size_t>(ix) * M + iy) * Mz;
        for (long nz = (nx > 0 || (nx == 0 && ny > 0)) ? 0 : 1; nz < Mz; ++nz) {
          const long m = modes.shell[static_cast<std::size_t>(nx * nx + ny * ny + nz * nz)];
          if (m < 1) continue;
          visit(block, row + static_cast<std::size_t>(nz), m, nx, ny, nz,
                axy * modes.alias[static_cast<std::size_t>(nz)]);
        }
      }
    }
  }
}

/// Per-block shell sums, added in block order.
struct ShellSums {
  std::size_t shells;
  std::vector<double> v;  // [block][shell]
  explicit ShellSums(long shells_)
      : shells(static_cast<std::size_t>(shells_) + 1), v(MODE_BLOCKS * shells, 0.0) {}
  double& at(long block, long m) {
    return v[static_cast<std::size_t>(block) * shells + static_cast<std::size_t>(m)];
  }
  std::vector<double> total() const {
    std::vector<double> t(shells, 0.0);
    for (long b = 0; b < MODE_BLOCKS; ++b)
      for (std::size_t m = 0; m < shells; ++m) t[m] += v[static_cast<std::size_t>(b) * shells + m];
    return t;
  }
};

/// The first moment k_1 = sum k_m S_m / sum S_m over the shells up to k_cut.
double firstMoment(const std::vector<double>& k, const std::vector<double>& S, double k_cut) {
  double moment = 0.0, norm = 0.0;
  for (std::size_t m = 0; m < k.size(); ++m)
    if (k[m] <= k_cut * (1.0 + 1e-12)) {
      moment += k[m] * S[m];
      norm += S[m];
    }
  return norm > 0.0 ? moment / norm : std::nan("");
}

}  // namespace

StructureFactor structureFactor(const Frame& f, const StructureFactorOptions& o) {
  StructureFactorMesh mesh;
  return structureFactor(f, o, mesh);
}

StructureFactor structureFactor(const Frame& f, const StructureFactorOptions& o,
                                StructureFactorMesh& mesh) {
  const std::size_t N = f.size();
  const long M = meshSize(f, o, "structure factor");
  const double L = f.box, dk = 2.0 * PI / L, h = L / static_cast<double>(M);
  StructureFactorMesh::Buffers& buffers = mesh.forSize(M);
  assign(f, M, h, nullptr, 0, buffers.rho());
  fftw_execute(buffers.plan.get());
  const fftw_complex* rk = buffers.rk();

  const long shells = static_cast<long>(std::floor(static_cast<double>(M) / 2.0 - 0.5));
  const Modes modes(M, h, dk, shells);
  ShellSums sums(shells), counts(shells);
  forEachMode(modes, [&](long b, std::size_t i, long m, long, long, long, double window) {
    const double power = rk[i][0] * rk[i][0] + rk[i][1] * rk[i][1];
    sums.at(b, m) += power / (static_cast<double>(N) * window);
    counts.at(b, m) += 1.0;
  });
  const std::vector<double> sum = sums.total(), count_real = counts.total();
  std::vector<std::size_t> count(count_real.size());
  for (std::size_t m = 0; m < count.size(); ++m) count[m] = static_cast<std::size_t>(count_real[m]);

  StructureFactor r;
  r.mesh = static_cast<std::size_t>(M);
  r.k_cut = std::min(o.k_cut, dk * static_cast<double>(shells));
  for (long m = 1; m <= shells; ++m) {
    const auto mm = static_cast<std::size_t>(m);
    if (count[mm] == 0) continue;
    r.k.push_back(dk * static_cast<double>(m));
    r.S.push_back(sum[mm] / static_cast<double>(count[mm]));
    r.modes.push_back(count[mm]);
  }
  r.k1 = firstMoment(r.k, r.S, r.k_cut);
  r.length = 2.0 * PI / r.k1;
  return r;
}

VelocityStructure velocityStructure(const Frame& f, const StructureFactorOptions& o,
                                    StructureFactorMesh& mesh) {
  if (!f.hasVelocities())
    throw std::invalid_argument("velocity structure: the frame has no velocities");
  const std::size_t N = f.size();
  const long M = meshSize(f, o, "velocity structure");
  const double L = f.box, dk = 2.0 * PI / L, h = L / static_cast<double>(M);
  // peculiar velocities c = v - <v> and T_g = <|c|^2> / 3
  double mean[3] = {0, 0, 0};
  for (std::size_t j = 0; j < N; ++j)
    for (int a = 0; a < 3; ++a) mean[a] += f.velocity[3 * j + a];
  for (double& m : mean) m /= static_cast<double>(N);
  std::vector<double> c(3 * N);
  double c2 = 0.0;
  for (std::size_t j = 0; j < 3 * N; ++j) {
    c[j] = f.velocity[j] - mean[j % 3];
    c2 += c[j] * c[j];
  }
  VelocityStructure r;
  r.T_g = c2 / (3.0 * static_cast<double>(N));
  StructureFactorMesh::Buffers& buffers = mesh.forSize(M);
  const long shells = static_cast<long>(std::floor(static_cast<double>(M) / 2.0 - 0.5));
  const Modes modes(M, h, dk, shells);
  ShellSums total_sums(shells), along_sums(shells), counts(shells);
  buffers.longitudinal.resize(static_cast<std::size_t>(M) * M * (M / 2 + 1));
  std::complex<float>* D = buffers.longitudinal.data();
  for (int a = 0; a < 3; ++a) {
    assign(f, M, h, c.data() + a, 3, buffers.rho());
    fftw_execute(buffers.plan.get());
    const fftw_complex* uk = buffers.rk();
    forEachMode(modes, [&](long b, std::size_t i, long m, long nx, long ny, long nz,
                           double window) {
      const double power = uk[i][0] * uk[i][0] + uk[i][1] * uk[i][1];
      total_sums.at(b, m) += power / window;
      if (a == 0) counts.at(b, m) += 1.0;
      const long na = a == 0 ? nx : a == 1 ? ny : nz;
      const double khat =
          static_cast<double>(na) *
          modes.inv_norm[static_cast<std::size_t>(nx * nx + ny * ny + nz * nz)];
      const std::complex<float> part(static_cast<float>(khat * uk[i][0]),
                                     static_cast<float>(khat * uk[i][1]));
      D[i] = a == 0 ? part : D[i] + part;  // every mode is visited once per component
    });
  }
  forEachMode(modes, [&](long b, std::size_t i, long m, long, long, long, double window) {
    along_sums.at(b, m) += static_cast<double>(std::norm(D[i])) / window;
  });
  // (kept for the next frame: freeing and faulting in 0.5 GB at M = 512 per frame cost 10 %)
  const std::vector<double> total = total_sums.total(), along = along_sums.total(),
                            count_real = counts.total();
  std::vector<std::size_t> count(count_real.size());
  for (std::size_t m = 0; m < count.size(); ++m) count[m] = static_cast<std::size_t>(count_real[m]);

  r.mesh = static_cast<std::size_t>(M);
  r.k_cut = std::min(o.k_cut, dk * static_cast<double>(shells));
  const double norm = static_cast<double>(N) * r.T_g;
  for (long m = 1; m <= shells; ++m) {
    const auto mm = static_cast<std::size_t>(m);
    if (count[mm] == 0) continue;
    const double n = static_cast<double>(count[mm]) * norm;
    r.k.push_back(dk * static_cast<double>(m));
    r.S_long.push_back(along[mm] / n);
    r.S_trans.push_back((total[mm] - along[mm]) / (2.0 * n));
    r.modes.push_back(count[mm]);
  }
  r.length_long = 2.0 * PI / firstMoment(r.k, r.S_long, r.k_cut);
  r.length_trans = 2.0 * PI / firstMoment(r.k, r.S_trans, r.k_cut);
  return r;
}

}  // namespace granagg::analysis
