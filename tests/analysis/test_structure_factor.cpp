// The structure factor S(k) on a mesh against independent references: the direct sum over the
// particles at the same wave vectors, the ideal gas (S = 1 within its statistical spread), and
// Gaussian blobs on a lattice (the peak at 2 pi / spacing). Also S without the largest cluster.
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "analysis/clusters/ClusterSizes.h"
#include "analysis/io/Frame.h"
#include "analysis/stats/StructureFactor.h"

#include "TestUtil.h"

using namespace granagg::analysis;

namespace {

constexpr double PI = 3.14159265358979323846;

Frame uniformGas(std::size_t N, double L, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, L);
  Frame f;
  f.box = L;
  for (std::size_t i = 0; i < 3 * N; ++i) f.position.push_back(u(rng));
  for (std::size_t i = 0; i < N; ++i) f.id.push_back(static_cast<std::int64_t>(i));
  return f;
}

/// `per_blob` particles in a Gaussian of width sigma around each site of a cubic lattice of
/// spacing a filling the box of edge L (L / a sites per side), wrapped into the box.
Frame blobLattice(double L, double a, std::size_t per_blob, double sigma, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  const int n = static_cast<int>(std::lround(L / a));
  Frame f;
  f.box = L;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (std::size_t p = 0; p < per_blob; ++p) {
          const double c[3] = {i * a, j * a, k * a};
          for (double x : c) {
            double y = std::fmod(x + g(rng), L);
            if (y < 0) y += L;
            f.position.push_back(y);
          }
          f.id.push_back(static_cast<std::int64_t>(f.id.size()));
        }
  return f;
}

/// The shell mean of |sum_j exp(-i k.r_j)|^2 / N over the same independent wave vectors as the
/// mesh method (one of each +-k, shell m = round(|n|)), summed directly over the particles.
double directShell(const Frame& f, int m) {
  const double dk = 2 * PI / f.box;
  const std::size_t N = f.size();
  double sum = 0.0;
  int count = 0;
  for (int nx = -m - 1; nx <= m + 1; ++nx)
    for (int ny = -m - 1; ny <= m + 1; ++ny)
      for (int nz = 0; nz <= m + 1; ++nz) {
        if (nz == 0 && !(nx > 0 || (nx == 0 && ny > 0))) continue;
        if (std::lround(std::sqrt(double(nx * nx + ny * ny + nz * nz))) != m) continue;
        std::complex<double> rho = 0.0;
        for (std::size_t j = 0; j < N; ++j) {
          const double phase = dk * (nx * f.position[3 * j] + ny * f.position[3 * j + 1] +
                                     nz * f.position[3 * j + 2]);
          rho += std::polar(1.0, -phase);
        }
        sum += std::norm(rho) / static_cast<double>(N);
        ++count;
      }
  return sum / count;
}

}  // namespace

TEST_CASE("S(k) on the mesh equals the direct sum over particles at small k",
          "[analysis][structure]") {
  // a clustered configuration (blobs) and a uniform one; at k h = 2 pi m / L * h the CIC
  // correction is exact to O((k h / 2)^4): m <= 3 at L = 20, h = 0.5 gives k h / 2 <= 0.24,
  // (0.24)^4 = 3e-3 at most, less after the alias correction's own O(x^2) agreement
  for (const Frame& f : {blobLattice(20.0, 5.0, 40, 0.7, 3), uniformGas(3000, 20.0, 4)}) {
    const StructureFactor s = structureFactor(f);
    REQUIRE(s.mesh == 40);
    for (int m = 1; m <= 3; ++m) {
      const double direct = directShell(f, m);
      INFO("shell " << m << ": mesh " << s.S[m - 1] << ", direct " << direct);
      CHECK(s.k[m - 1] == Approx(m * 2 * PI / 20.0));
      CHECK(s.S[m - 1] == Approx(direct).epsilon(3e-3));
    }
  }
}

TEST_CASE("an ideal gas has S(k) = 1 within its statistical spread at every k",
          "[analysis][structure]") {
  // For uniform independent positions |rho_k|^2 / N has mean 1 at every k != 0 (the mesh's
  // alias correction makes this exact for the CIC-assigned field) and standard deviation 1 for
  // N >> 1 (exponentially distributed), so a shell mean over m independent wave vectors has
  // spread 1 / sqrt(m). Each shell is checked at 5 sigma: with 29 shells a false alarm has
  // probability below 1e-4 (and the seed is fixed).
  const Frame f = uniformGas(20000, 30.0, 11);
  const StructureFactor s = structureFactor(f);
  REQUIRE(s.k.size() >= 25);
  double all = 0.0;
  std::size_t modes = 0;
  for (std::size_t m = 0; m < s.k.size(); ++m) {
    INFO("k = " << s.k[m] << ": S = " << s.S[m] << " over " << s.modes[m] << " wave vectors");
    CHECK(std::fabs(s.S[m] - 1.0) < 5.0 / std::sqrt(double(s.modes[m])));
    all += s.S[m] * static_cast<double>(s.modes[m]);
    modes += s.modes[m];
  }
  CHECK(std::fabs(all / static_cast<double>(modes) - 1.0) < 5.0 / std::sqrt(double(modes)));
  // the length's baseline for S = 1: 2 pi over the mean shell centre up to k_c = pi
  double mean_k = 0.0;
  int shells = 0;
  for (double k : s.k)
    if (k <= PI) {
      mean_k += k;
      ++shells;
    }
  mean_k /= shells;
  CHECK(s.length == Approx(2 * PI / mean_k).epsilon(0.05));
}

TEST_CASE("Gaussian blobs on a lattice give the S(k) peak at 2 pi / spacing",
          "[analysis][structure]") {
  // blobs of 60 particles, sigma = 0.8, spacing a = 6 in L = 36: the lattice's first reciprocal
  // vectors |G| = 2 pi / 6 lie in shell m = 6, where S ~ N exp(-G^2 sigma^2) / (shell size)
  const double a = 6.0;
  const Frame f = blobLattice(36.0, a, 60, 0.8, 5);
  const StructureFactor s = structureFactor(f);
  std::size_t peak = 0;
  for (std::size_t m = 0; m < s.k.size(); ++m)
    if (s.S[m] > s.S[peak]) peak = m;
  CHECK(s.k[peak] == Approx(2 * PI / a));
  CHECK(s.S[peak] > 50.0);
  // the length follows the clustering: larger than the ideal gas's baseline of about 4 d
  const StructureFactor ideal = structureFactor(uniformGas(f.size(), 36.0, 6));
  CHECK(s.length > 1.2 * ideal.length);
}

TEST_CASE("S without the largest cluster leaves out one largest cluster",
          "[analysis][clusters]") {
  // sizes 1, 1, 2, 5, 10: sum s^2 = 131, mass 19; without the 10: 31 / 9
  const ClusterSizes c = ClusterSizes::fromSizes({1, 10, 2, 1, 5});
  CHECK(c.S == Approx(131.0 / 19.0));
  CHECK(c.S_without_largest == Approx(31.0 / 9.0));
  CHECK(c.largest_share == Approx(10.0 / 19.0));
  // two equal largest clusters: only one is left out
  const ClusterSizes d = ClusterSizes::fromSizes({4, 4, 1});
  CHECK(d.S_without_largest == Approx(17.0 / 5.0));
  CHECK(std::isnan(ClusterSizes::fromSizes({7}).S_without_largest));
  CHECK(ClusterSizes::fromSizes({7}).largest_share == 1.0);
}

TEST_CASE("a mesh kept between frames gives each frame's S(k) to the bit",
          "[analysis][structure]") {
  // A trajectory's frames share one StructureFactorMesh (FrameObservables); the buffers are
  // cleared and the plan reused, so each frame's result must equal a fresh mesh's exactly, also
  // after a frame of another box size (another M) in between.
  const Frame a = uniformGas(3000, 20.0, 3), b = uniformGas(3000, 24.0, 4);
  StructureFactorMesh mesh;
  const StructureFactorOptions o;
  for (const Frame* f : {&a, &b, &a, &a}) {
    const StructureFactor shared = structureFactor(*f, o, mesh), fresh = structureFactor(*f, o);
    CHECK(shared.mesh == fresh.mesh);
    CHECK(granagg::test::sameBits(shared.S, fresh.S));
    CHECK(granagg::test::sameBits(shared.k, fresh.k));
    CHECK(shared.length == fresh.length);
  }
}

namespace {

/// Velocities for frame `f`: Maxwellian noise of variance `noise` per component plus a shear
/// wave (v_x = A sin(2 pi y / L): transverse at k = 2 pi / L along y) and a compression wave
/// (v_x = B sin(2 pi 2 x / L): longitudinal at k = 4 pi / L along x).
void addVelocities(Frame& f, double noise, double A, double B, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, std::sqrt(noise));
  const double L = f.box;
  f.velocity.resize(3 * f.size());
  for (std::size_t j = 0; j < f.size(); ++j) {
    const double x = f.position[3 * j], y = f.position[3 * j + 1];
    f.velocity[3 * j] = g(rng) + A * std::sin(2 * PI * y / L) + B * std::sin(2 * PI * 2 * x / L);
    f.velocity[3 * j + 1] = g(rng);
    f.velocity[3 * j + 2] = g(rng);
  }
}

/// S_par and S_perp of shell m summed directly over the particles (the definitions of
/// VelocityStructure: peculiar velocities, one of each +-k, shell m = round(|n|)).
std::pair<double, double> directVelocityShell(const Frame& f, int m) {
  const double dk = 2 * PI / f.box;
  const std::size_t N = f.size();
  double mean[3] = {0, 0, 0}, c2 = 0;
  for (std::size_t j = 0; j < N; ++j)
    for (int a = 0; a < 3; ++a) mean[a] += f.velocity[3 * j + a] / double(N);
  for (std::size_t j = 0; j < 3 * N; ++j) c2 += std::pow(f.velocity[j] - mean[j % 3], 2);
  const double T = c2 / (3.0 * N);
  double par = 0, perp = 0;
  int count = 0;
  for (int nx = -m - 1; nx <= m + 1; ++nx)
    for (int ny = -m - 1; ny <= m + 1; ++ny)
      for (int nz = 0; nz <= m + 1; ++nz) {
        if (nz == 0 && !(nx > 0 || (nx == 0 && ny > 0))) continue;
        if (std::lround(std::sqrt(double(nx * nx + ny * ny + nz * nz))) != m) continue;
        std::complex<double> u[3] = {0.0, 0.0, 0.0};
        for (std::size_t j = 0; j < N; ++j) {
          const double phase = dk * (nx * f.position[3 * j] + ny * f.position[3 * j + 1] +
                                     nz * f.position[3 * j + 2]);
          const std::complex<double> e = std::polar(1.0, -phase);
          for (int a = 0; a < 3; ++a) u[a] += (f.velocity[3 * j + a] - mean[a]) * e;
        }
        const double n[3] = {double(nx), double(ny), double(nz)};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        std::complex<double> along = 0.0;
        double total = 0;
        for (int a = 0; a < 3; ++a) {
          along += n[a] / len * u[a];
          total += std::norm(u[a]);
        }
        par += std::norm(along);
        perp += total - std::norm(along);
        ++count;
      }
  return {par / (count * N * T), perp / (2.0 * count * N * T)};
}

}  // namespace

TEST_CASE("S_par and S_perp on the mesh equal the direct sums over particles at small k",
          "[analysis][structure]") {
  // a shear wave at m = 1 and a compression wave at m = 2 on noise: S_perp peaks at m = 1,
  // S_par at m = 2. The alias correction is exact for the uncorrelated part; the waves' own
  // power keeps the CIC window's O((k h / 2)^4) error per axis: 3 (0.24)^4 = 1e-2 at m = 3.
  Frame f = uniformGas(3000, 20.0, 11);
  addVelocities(f, 1.0, 1.5, 1.5, 12);
  StructureFactorMesh mesh;
  const VelocityStructure v = velocityStructure(f, {}, mesh);
  REQUIRE(v.mesh == 40);
  for (int m = 1; m <= 3; ++m) {
    const auto [par, perp] = directVelocityShell(f, m);
    INFO("shell " << m << ": mesh " << v.S_long[m - 1] << " " << v.S_trans[m - 1] << ", direct "
                  << par << " " << perp);
    CHECK(v.k[m - 1] == Approx(m * 2 * PI / 20.0));
    CHECK(v.S_long[m - 1] == Approx(par).epsilon(1e-2));
    CHECK(v.S_trans[m - 1] == Approx(perp).epsilon(1e-2));
  }
  CHECK(v.S_trans[0] > 10 * v.S_long[0]);  // the shear wave is transverse
  CHECK(v.S_long[1] > 10 * v.S_trans[1]);  // the compression wave is longitudinal
  // the density transform on the same mesh is unchanged by the velocity transforms
  CHECK(structureFactor(f, {}, mesh).S == structureFactor(f).S);
}

TEST_CASE("uncorrelated velocities give S_par = S_perp = 1 within their spread",
          "[analysis][structure]") {
  // shell m holds n_m independent modes; each |k^.u|^2 / (N T) is exponential with mean 1
  // (a sum over many particles: Gaussian u), so the shell mean has sd 1 / sqrt(n_m) for S_par
  // and 1 / sqrt(2 n_m) for S_perp (two components); 5 sd, shells with >= 50 modes
  Frame f = uniformGas(20000, 30.0, 21);
  addVelocities(f, 2.0, 0.0, 0.0, 22);
  StructureFactorMesh mesh;
  const VelocityStructure v = velocityStructure(f, {}, mesh);
  CHECK(v.T_g == Approx(2.0).epsilon(0.03));
  std::size_t checked = 0;
  for (std::size_t m = 0; m < v.k.size(); ++m) {
    if (v.modes[m] < 50) continue;
    const double n = static_cast<double>(v.modes[m]);
    INFO("k = " << v.k[m] << ", modes " << n);
    CHECK(std::fabs(v.S_long[m] - 1.0) < 5.0 / std::sqrt(n));
    CHECK(std::fabs(v.S_trans[m] - 1.0) < 5.0 / std::sqrt(2.0 * n));
    ++checked;
  }
  CHECK(checked > 20);
  Frame no_v = uniformGas(10, 5.0, 1);
  CHECK_THROWS_AS(velocityStructure(no_v, {}, mesh), std::invalid_argument);
}
