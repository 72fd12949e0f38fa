// Grid and particle clusters on built configurations with known clusters, including clusters
// that wrap across periodic faces, edges and corners: exact N_s and S.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "analysis/clusters/ClusterSizes.h"
#include "analysis/clusters/GridClusters.h"
#include "analysis/clusters/ParticleClusters.h"
#include "analysis/clusters/UnionFind.h"
#include "common/Box.h"

using namespace granagg::analysis;

namespace {

using Ns = std::map<std::uint64_t, std::uint64_t>;

/// `count` particle centres inside grid cell (ix, iy, iz) of edge h, spread around its centre.
void fillCell(std::vector<double>& pos, int ix, int iy, int iz, double h, int count) {
  for (int k = 0; k < count; ++k) {
    const double off =
        -0.6 + 1.2 * k / std::max(1, count - 1);  // within +-0.6 of the centre (h = 2)
    pos.push_back((ix + 0.5) * h + off);
    pos.push_back((iy + 0.5) * h - off * 0.5);
    pos.push_back((iz + 0.5) * h + off * 0.25);
  }
}

/// Minimum-image distance based clusters, O(N^2): the independent reference.
Ns bruteForceClusters(const std::vector<double>& pos, double L, double rc) {
  const std::size_t n = pos.size() / 3;
  UnionFind uf(n);
  const granagg::common::Box box{L};
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double dx = box.minimumImage(pos[3 * i + d] - pos[3 * j + d]);
        r2 += dx * dx;
      }
      if (r2 <= rc * rc) uf.unite(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
    }
  Ns out;
  for (std::size_t i = 0; i < n; ++i)
    if (uf.find(static_cast<std::uint32_t>(i)) == i)
      ++out[uf.rootSize(static_cast<std::uint32_t>(i))];
  return out;
}

}  // namespace

TEST_CASE("ClusterSizes gives N_s and S = sum s^2 N_s / sum s N_s", "[analysis][clusters]") {
  const ClusterSizes c = ClusterSizes::fromSizes({1, 1, 1, 3, 4, 8});
  CHECK(c.n_s == Ns{{1, 3}, {3, 1}, {4, 1}, {8, 1}});
  CHECK(c.clusters == 6);
  CHECK(c.mass == 18);
  CHECK(c.largest == 8);
  CHECK(c.S == Approx(92.0 / 18.0).epsilon(1e-15));
  CHECK(std::isnan(ClusterSizes::fromSizes({}).S));
  CHECK(c.samples() == std::vector<std::uint64_t>{1, 1, 1, 3, 4, 8});
}

TEST_CASE("grid clusters of built blobs wrapping faces, edges and corners are exact",
          "[analysis][clusters]") {
  const double L = 20.0;  // 10 cells of h = 2 per side; threshold ceil(0.25 * 8 / (pi/6)) = 4
  std::vector<double> pos;
  // corner: the 2x2x2 block of cells {9, 0}^3 (wraps all three faces) -> 8 sites
  for (int x : {9, 0})
    for (int y : {9, 0})
      for (int z : {9, 0}) fillCell(pos, x, y, z, 2.0, 4);
  // face: a line of 3 cells across the x face -> 3 sites
  for (int x : {9, 0, 1}) fillCell(pos, x, 5, 5, 2.0, 5);
  // edge: the 2x2 square of cells across the y and z faces -> 4 sites
  for (int y : {9, 0})
    for (int z : {9, 0}) fillCell(pos, 5, y, z, 2.0, 4);
  // single site, and two sites touching only along an edge: 6-connectivity makes them 2 clusters
  fillCell(pos, 3, 3, 3, 2.0, 6);
  fillCell(pos, 7, 3, 3, 2.0, 4);
  fillCell(pos, 8, 4, 3, 2.0, 4);
  // 3 centres: below the threshold, never occupied
  fillCell(pos, 2, 7, 7, 2.0, 3);
  for (double& x : pos) x = std::fmod(x + L, L);

  GridClusters gc;  // defaults: spacing 2, min_fill 0.25
  CHECK_THROWS_AS(gc.result(), std::logic_error);
  gc.compute(pos.data(), pos.size() / 3, L);
  CHECK(gc.cellsPerSide() == 10);
  CHECK(gc.minCount() == 4.0);
  const Ns expected{{1, 3}, {3, 1}, {4, 1}, {8, 1}};
  CHECK(gc.result().n_s == expected);
  CHECK(gc.result().S == Approx(92.0 / 18.0).epsilon(1e-15));
  CHECK(gc.occupiedFraction() == Approx(18.0 / 1000.0));
  // labels: every site of the corner block carries one label, other cells -1
  const auto& lab = gc.labels();
  auto idx = [](int x, int y, int z) { return (x * 10 + y) * 10 + z; };
  CHECK(lab[idx(9, 9, 9)] >= 0);
  CHECK(lab[idx(0, 0, 0)] == lab[idx(9, 9, 9)]);
  CHECK(lab[idx(0, 9, 0)] == lab[idx(9, 0, 9)]);
  CHECK(lab[idx(7, 3, 3)] != lab[idx(8, 4, 3)]);
  CHECK(lab[idx(2, 7, 7)] == -1);
  CHECK(gc.occupancy()[idx(2, 7, 7)] == 0);

  SECTION("translating everything by whole cells (with wrap) changes nothing") {
    for (const auto& shift : {std::vector<double>{2, 0, 0}, {0, 6, 0}, {0, 0, 14}, {4, 8, 18}}) {
      std::vector<double> moved = pos;
      for (std::size_t j = 0; j < moved.size(); ++j)
        moved[j] = std::fmod(moved[j] + shift[j % 3], L);
      GridClusters g2;
      g2.compute(moved.data(), moved.size() / 3, L);
      CHECK(g2.result().n_s == expected);
    }
  }
  SECTION("min_count overrides min_fill; a higher threshold empties the 4-centre cells") {
    GridClusters g5(GridClustersParams{2.0, 0.25, 5, GridAssignment::Nearest});
    g5.compute(pos.data(), pos.size() / 3, L);
    CHECK(g5.minCount() == 5.0);
    CHECK(g5.result().n_s == Ns{{1, 1}, {3, 1}});  // the 6-centre site and the 5-centre line
  }
}

TEST_CASE("grid threshold is the integer count of filling fraction min_fill in the actual cell",
          "[analysis][clusters]") {
  GridClusters g;
  std::vector<double> one{0.5, 0.5, 0.5};
  g.compute(one.data(), 1, 23.97);  // the quick preset's box: 11 cells of h = 2.179
  CHECK(g.cellsPerSide() == 11);
  CHECK(g.cellSize() == Approx(23.97 / 11));
  CHECK(g.minCount() == std::ceil(0.25 * std::pow(23.97 / 11, 3) / (M_PI / 6)));  // = 5
  CHECK(g.result().clusters == 0);
  CHECK(std::isnan(g.result().S));
}

TEST_CASE("cloud-in-cell smoothing keeps the total weight and finds a dense blob",
          "[analysis][clusters]") {
  GridClustersParams p;
  p.assignment = GridAssignment::CloudInCell;
  GridClusters g(p);
  std::vector<double> pos;
  for (int k = 0; k < 40; ++k) {  // 40 centres at the corner node shared by 8 cells
    pos.push_back(std::fmod(20.0 + 0.01 * (k % 5) - 0.02, 20.0));
    pos.push_back(std::fmod(20.0 + 0.01 * (k % 3) - 0.01, 20.0));
    pos.push_back(std::fmod(20.0 + 0.01 * (k % 7) - 0.03, 20.0));
  }
  g.compute(pos.data(), 40, 20.0);
  double total = 0;
  for (double c : g.counts()) total += c;
  CHECK(total == Approx(40.0).epsilon(1e-12));
  CHECK(g.result().n_s == Ns{{8, 1}});  // ~5 per cell in the 8 cells around the corner, one cluster
}

TEST_CASE("grid and particle clusters reject bad parameters", "[analysis][clusters]") {
  CHECK_THROWS_AS(GridClusters(GridClustersParams{0.0, 0.25, 0, GridAssignment::Nearest}),
                  std::invalid_argument);
  CHECK_THROWS_AS(GridClusters(GridClustersParams{2.0, 1.5, 0, GridAssignment::Nearest}),
                  std::invalid_argument);
  CHECK_THROWS_AS(GridClusters(GridClustersParams{2.0, 0.25, -1, GridAssignment::Nearest}),
                  std::invalid_argument);
  CHECK_THROWS_AS(ParticleClusters(ParticleClustersParams{-0.1}), std::invalid_argument);
  CHECK_THROWS_WITH(ParticleClusters(ParticleClustersParams{std::nan("")}),
                    Catch::Contains("tolerance"));
}

TEST_CASE("particle clusters of built blobs wrapping faces, edges and corners are exact",
          "[analysis][clusters]") {
  const double L = 20.0, a = 1.02;  // bond length 1.02 <= 1.05; diagonals 1.44 are not bonds
  std::vector<double> pos;
  auto add = [&](double x, double y, double z) {
    for (double v : {x, y, z}) pos.push_back(std::fmod(v + L, L));
  };
  // corner: a 2x2x2 cube of particles centred on the box corner -> 8
  for (double x : {-a / 2, a / 2})
    for (double y : {-a / 2, a / 2})
      for (double z : {-a / 2, a / 2}) add(x, y, z);
  // face: a chain of 3 across the x face -> 3
  add(L - a, 7, 7);
  add(0, 7, 7);
  add(a, 7, 7);
  // edge: a square of 4 around the edge y = z = 0 at x = 10 -> 4
  for (double y : {-a / 2, a / 2})
    for (double z : {-a / 2, a / 2}) add(10, y, z);
  // singles, and a pair 1.06 apart (just beyond 1 + tolerance): 5 clusters of 1
  add(5, 5, 5);
  add(15, 15, 5);
  add(5, 15, 15);
  add(15, 5, 12);
  add(15, 5, 12 + 1.06);

  ParticleClusters pc;
  CHECK_THROWS_AS(pc.result(), std::logic_error);
  pc.compute(pos.data(), pos.size() / 3, L);
  const Ns expected{{1, 5}, {3, 1}, {4, 1}, {8, 1}};
  CHECK(pc.result().n_s == expected);
  CHECK(pc.result().S == Approx((5.0 + 9 + 16 + 64) / 20.0).epsilon(1e-15));
  CHECK(pc.contacts()[0] == 3);  // a cube corner touches 3 neighbours
  CHECK(pc.contacts()[9] == 2);  // middle of the chain
  CHECK(pc.bonds() == 12 + 2 + 4);
  CHECK(pc.labels()[0] != pc.labels()[8]);
  CHECK(pc.labels()[8] == pc.labels()[10]);
  CHECK(pc.result().n_s == bruteForceClusters(pos, L, 1.05));

  SECTION(
      "a small box (fewer than 3 cells per side) takes the all-pairs path with the same answer") {
    std::vector<double> small;
    const double Ls = 2.5;
    for (double x : {0.1, 1.1, 2.12})  // 2.12 -> 0.1 is 0.48 across the face: all bonded
      for (int k = 0; k < 1; ++k) {
        small.push_back(x);
        small.push_back(0.5);
        small.push_back(0.5);
      }
    ParticleClusters p2;
    p2.compute(small.data(), 3, Ls);
    CHECK(p2.result().n_s == Ns{{3, 1}});
  }
}

TEST_CASE("particle clusters of a random dense gas match an O(N^2) reference",
          "[analysis][clusters]") {
  for (unsigned seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    const double L = 9.0;  // 8 cells per side
    std::uniform_real_distribution<double> U(0.0, L);
    std::vector<double> pos(3 * 600);
    for (auto& x : pos) x = U(rng);
    for (double tol : {0.0, 0.05, 0.3}) {
      ParticleClusters pc(ParticleClustersParams{tol});
      pc.compute(pos.data(), 600, L);
      CHECK(pc.result().n_s == bruteForceClusters(pos, L, 1.0 + tol));
    }
  }
}
