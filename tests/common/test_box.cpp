// Periodic box helpers (common/Box.h): the fast paths used by the MD hot loops against the general
// definitions, on random and on edge-case inputs.
#include <cmath>
#include <limits>
#include <random>

#include <catch2/catch.hpp>

#include "common/Box.h"

using granagg::common::Box;

TEST_CASE("minimumImageWrapped equals minimumImage for differences of wrapped coordinates",
          "[box]") {
  const Box box{34.62};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, box.L);
  for (int k = 0; k < 100000; ++k) {
    const double dx = u(rng) - u(rng);
    const double a = box.minimumImageWrapped(dx), b = box.minimumImage(dx);
    REQUIRE(a == b);
    REQUIRE(std::abs(a) <= 0.5 * box.L);
  }
  // extremes: both coordinates at the faces
  const double top = std::nextafter(box.L, 0.0);
  CHECK(box.minimumImageWrapped(top - 0.0) == box.minimumImage(top));
  CHECK(box.minimumImageWrapped(0.0 - top) == box.minimumImage(-top));
  CHECK(std::abs(box.minimumImageWrapped(0.5 * box.L)) == 0.5 * box.L);
}

TEST_CASE(
    "the branchless minimum image and the three-coordinate inside test agree with their plain "
    "forms",
    "[box]") {
  const Box box{34.62};
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, box.L), wide(-0.1 * box.L, 1.1 * box.L);
  const auto inside = [&](double x) { return x >= 0.0 && x < box.L; };
  for (int k = 0; k < 100000; ++k) {
    const double dx = u(rng) - u(rng);
    REQUIRE(box.minimumImageWrappedBranchless(dx) == box.minimumImageWrapped(dx));
    const double a = wide(rng), b = wide(rng), c = wide(rng);
    REQUIRE(box.insideAll(a, b, c) == (inside(a) && inside(b) && inside(c)));
  }
  const double top = std::nextafter(box.L, 0.0), tiny = -std::numeric_limits<double>::denorm_min();
  for (double dx : {top, -top, 0.5 * box.L, -0.5 * box.L, 0.0})
    CHECK(box.minimumImageWrappedBranchless(dx) == box.minimumImageWrapped(dx));
  // the faces: L and anything below 0 are outside; 0 itself is left to the full path (reported
  // outside)
  CHECK(box.insideAll(top, top, top));
  CHECK_FALSE(box.insideAll(box.L, 1.0, 1.0));
  CHECK_FALSE(box.insideAll(1.0, tiny, 1.0));
  CHECK_FALSE(box.insideAll(1.0, 1.0, std::nan("")));
  CHECK_FALSE(box.insideAll(0.0, 1.0, 1.0));
}

TEST_CASE("wrap returns a coordinate in 0 <= x < L and the image shift, fast path and general case",
          "[box]") {
  const Box box{10.0};
  struct Case {
    double x;
    double wrapped;
    int images;
  };
  const double tiny = 1e-17;
  for (const Case c : {Case{3.5, 3.5, 0}, Case{0.0, 0.0, 0}, Case{10.0, 0.0, 1}, Case{12.5, 2.5, 1},
                       Case{-0.5, 9.5, -1}, Case{-10.0, 0.0, -1}, Case{25.0, 5.0, 2},
                       Case{-25.0, 5.0, -3}, Case{-tiny, 0.0, 0}}) {
    double x = c.x;
    const int n = box.wrap(x);
    INFO("x = " << c.x);
    CHECK(x >= 0.0);
    CHECK(x < box.L);
    CHECK(n == c.images);
    CHECK(x == Approx(c.wrapped).margin(1e-15));
  }
  // random round trip: unwrapped = wrapped + images * L
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-35.0, 35.0);
  for (int k = 0; k < 100000; ++k) {
    const double x0 = u(rng);
    double x = x0;
    const int n = box.wrap(x);
    REQUIRE(x >= 0.0);
    REQUIRE(x < box.L);
    REQUIRE(x + n * box.L == Approx(x0).margin(1e-12));
  }
}
