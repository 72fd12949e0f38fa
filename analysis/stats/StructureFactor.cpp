#include "analysis/stats/StructureFactor.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <stdexcept>
#include <string>

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
  std::unique_ptr<double, decltype(&fftw_free)> rho{nullptr, fftw_free};
  std::unique_ptr<fftw_complex, decltype(&fftw_free)> rk{nullptr, fftw_free};
  std::unique_ptr<fftw_plan_s, PlanDeleter> plan;
};

StructureFactorMesh::StructureFactorMesh() : m_buffers(std::make_unique<Buffers>()) {}
StructureFactorMesh::~StructureFactorMesh() = default;

StructureFactorMesh::Buffers& StructureFactorMesh::forSize(long M) {
  Buffers& b = *m_buffers;
  if (b.M == M && b.plan) return b;
  b.plan.reset();
  const std::size_t cells = static_cast<std::size_t>(M) * M * M;
  b.rho.reset(fftw_alloc_real(cells));
  b.rk.reset(fftw_alloc_complex(static_cast<std::size_t>(M) * M * (M / 2 + 1)));
  if (!b.rho || !b.rk) throw std::runtime_error("structure factor: no memory for the mesh");
  // (FFTW_ESTIMATE does not touch the arrays)
  b.plan.reset(fftw_plan_dft_r2c_3d(static_cast<int>(M), static_cast<int>(M), static_cast<int>(M),
                                    b.rho.get(), b.rk.get(), FFTW_ESTIMATE));
  if (!b.plan) throw std::runtime_error("structure factor: FFTW could not plan the mesh");
  b.M = M;
  return b;
}

StructureFactor structureFactor(const Frame& f, const StructureFactorOptions& o) {
  StructureFactorMesh mesh;
  return structureFactor(f, o, mesh);
}

StructureFactor structureFactor(const Frame& f, const StructureFactorOptions& o,
                                StructureFactorMesh& mesh) {
  const std::size_t N = f.size();
  const double L = f.box;
  if (N == 0) throw std::invalid_argument("structure factor: the frame has no particles");
  if (!(L > 0.0) || !std::isfinite(L))
    throw std::invalid_argument("structure factor: the box edge must be positive");
  if (!(o.h_max > 0.0) || !(o.k_cut > 0.0) || o.max_mesh < 8)
    throw std::invalid_argument("structure factor: h_max and k_cut must be > 0, max_mesh >= 8");
  const double dk = 2.0 * PI / L;
  // an even mesh with h = L / M <= h_max, at most max_mesh
  long M = static_cast<long>(std::ceil(L / o.h_max));
  M += M % 2;
  M = std::clamp<long>(M, 8, static_cast<long>(o.max_mesh) - static_cast<long>(o.max_mesh % 2));
  const double h = L / static_cast<double>(M);

  // cloud-in-cell assignment of unit masses (cell centres at (i + 1/2) h are not needed: a shift
  // of the mesh changes only the phase of rho_k)
  const std::size_t cells = static_cast<std::size_t>(M) * M * M;
  const long Mz = M / 2 + 1;
  StructureFactorMesh::Buffers& buffers = mesh.forSize(M);
  double* rho = buffers.rho.get();
  const fftw_complex* rk = buffers.rk.get();
  std::fill(rho, rho + cells, 0.0);
  for (std::size_t j = 0; j < N; ++j) {
    long i0[3];
    double w1[3];
    for (int a = 0; a < 3; ++a) {
      const double u = f.position[3 * j + a] / h;
      const double fl = std::floor(u);
      i0[a] = static_cast<long>(fl);
      w1[a] = u - fl;
    }
    for (int dx = 0; dx < 2; ++dx)
      for (int dy = 0; dy < 2; ++dy)
        for (int dz = 0; dz < 2; ++dz) {
          const double w =
              (dx ? w1[0] : 1.0 - w1[0]) * (dy ? w1[1] : 1.0 - w1[1]) * (dz ? w1[2] : 1.0 - w1[2]);
          rho[(wrap(i0[0] + dx, M) * M + wrap(i0[1] + dy, M)) * M + wrap(i0[2] + dz, M)] += w;
        }
  }
  fftw_execute(buffers.plan.get());

  // complete shells below the Nyquist wavenumber pi / h: every component |n_a| < M / 2
  const long shells = static_cast<long>(std::floor(static_cast<double>(M) / 2.0 - 0.5));
  std::vector<double> sum(static_cast<std::size_t>(shells) + 1, 0.0);
  std::vector<std::size_t> count(sum.size(), 0);
  auto component = [M](long i) { return i <= M / 2 ? i : i - M; };
  // the CIC window's aliased sum for uncorrelated positions, per axis (Jing 2005, eq. 20)
  auto alias = [h](double k) {
    const double s = std::sin(0.5 * k * h);
    return 1.0 - (2.0 / 3.0) * s * s;
  };
  for (long ix = 0; ix < M; ++ix) {
    const long nx = component(ix);
    for (long iy = 0; iy < M; ++iy) {
      const long ny = component(iy);
      for (long nz = 0; nz < Mz; ++nz) {
        // one of each pair +-k: rho_{-k} is the conjugate of rho_k
        if (nz == 0 && !(nx > 0 || (nx == 0 && ny > 0))) continue;
        const double n2 = static_cast<double>(nx * nx + ny * ny + nz * nz);
        const long m = std::lround(std::sqrt(n2));
        if (m < 1 || m > shells) continue;
        const fftw_complex& c = rk[(static_cast<std::size_t>(ix) * M + iy) * Mz + nz];
        const double power = c[0] * c[0] + c[1] * c[1];
        const double window = alias(dk * nx) * alias(dk * ny) * alias(dk * nz);
        sum[static_cast<std::size_t>(m)] += power / (static_cast<double>(N) * window);
        ++count[static_cast<std::size_t>(m)];
      }
    }
  }

  StructureFactor r;
  r.mesh = static_cast<std::size_t>(M);
  r.k_cut = std::min(o.k_cut, dk * static_cast<double>(shells));
  double moment = 0.0, norm = 0.0;
  for (long m = 1; m <= shells; ++m) {
    const auto mm = static_cast<std::size_t>(m);
    if (count[mm] == 0) continue;
    const double km = dk * static_cast<double>(m), S = sum[mm] / static_cast<double>(count[mm]);
    r.k.push_back(km);
    r.S.push_back(S);
    r.modes.push_back(count[mm]);
    if (km <= r.k_cut * (1.0 + 1e-12)) {
      moment += km * S;
      norm += S;
    }
  }
  r.k1 = norm > 0.0 ? moment / norm : std::nan("");
  r.length = 2.0 * PI / r.k1;
  return r;
}

}  // namespace granagg::analysis
