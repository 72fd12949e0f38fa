// The O(M log M) FFT right-hand side of the discrete Smoluchowski equation against the plain
// O(M^2) double sum over Kernel::operator() (an independent evaluation of the same equation).
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/SmoluchowskiRhs.h"

using namespace granagg::meanfield;

namespace {
std::vector<double> randomDistribution(int M, unsigned seed, int support) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> n(M, 0.0);
  for (int k = 1; k <= support; ++k) n[k - 1] = u(rng) * std::exp(-double(k) / (0.2 * support));
  return n;
}
}  // namespace

TEST_CASE("kernels: values, symmetry and homogeneity", "[meanfield][kernel]") {
  const Kernel kb = Kernel::beta(3.0, 2.0);
  // K(i,j) = K0 (i^{1/3}+j^{1/3})^2 (1/i+1/j)^{1/beta}, evaluated by hand for i = 1, j = 8:
  // (1 + 2)^2 (1 + 1/8)^{1/3} * 2
  CHECK(kb(1, 8) == Approx(2.0 * 9.0 * std::cbrt(1.125)).epsilon(1e-14));
  CHECK(kb(3, 7) == Approx(kb(7, 3)).epsilon(1e-15));
  for (double beta : {2.0, 2.5, 3.0, 4.0}) {
    const Kernel k = Kernel::beta(beta);
    CHECK(k.homogeneity() == Approx(2.0 / 3.0 - 1.0 / beta));
    CHECK(k.scalingExponent() == Approx(3.0 * beta / (beta + 3.0)).epsilon(1e-14));
    // K(a i, a j) = a^lambda K(i, j)
    CHECK(k(10.0 * 3, 10.0 * 5) ==
          Approx(std::pow(10.0, k.homogeneity()) * k(3, 5)).epsilon(1e-13));
    // separable representation reproduces the kernel
    double sep = 0.0;
    for (const auto& t : k.terms()) sep += t.weight * std::pow(3.0, t.p) * std::pow(5.0, t.q);
    CHECK(k(3, 5) == Approx(std::pow(8.0, k.sumExponent()) * sep).epsilon(1e-13));
  }
  CHECK(Kernel::constant(2)(4, 9) == 2);
  CHECK(Kernel::additive()(4, 9) == 13);
  CHECK(Kernel::multiplicative()(4, 9) == 36);
  CHECK(Kernel::multiplicative().gels());
  CHECK_FALSE(Kernel::beta(2).gels());
  CHECK_THROWS_AS(Kernel::beta(0.0), std::invalid_argument);
  CHECK_THROWS_AS(Kernel::beta(-1.0), std::invalid_argument);
  CHECK_THROWS_WITH(Kernel::fromName("gaussian"), Catch::Contains("unknown kernel 'gaussian'"));
}

TEST_CASE("FFT right-hand side equals the direct double sum", "[meanfield][rhs]") {
  const int M = 300;
  for (const Kernel& k : {Kernel::constant(), Kernel::additive(), Kernel::multiplicative(),
                          Kernel::beta(2.0), Kernel::beta(3.0, 0.7)}) {
    SmoluchowskiRhs fft(k, M, SmoluchowskiRhs::Method::Fft);
    REQUIRE(fft.usesFft());
    REQUIRE(fft.fftLength() >= 2 * M + 1);
    const auto n = randomDistribution(M, 42, M);
    std::vector<double> a(M), b(M);
    fft.evaluate(n.data(), a.data());
    fft.evaluateDirect(n.data(), b.data());
    double scale = 0.0;
    for (double v : b) scale = std::max(scale, std::fabs(v));
    double err = 0.0;
    for (int i = 0; i < M; ++i) err = std::max(err, std::fabs(a[i] - b[i]));
    INFO("kernel " << k.name() << ": max |fft - direct| / max |direct| = " << err / scale);
    // FFT round-off is O(1e-16 * log L) relative to the largest term; 1e-12 leaves ample margin
    CHECK(err <= 1e-12 * scale);
  }
}

TEST_CASE("right-hand side conserves mass when nothing reaches the truncation",
          "[meanfield][rhs]") {
  const int M = 400;
  for (const Kernel& k : {Kernel::constant(), Kernel::multiplicative(), Kernel::beta(2.5)}) {
    SmoluchowskiRhs rhs(k, M);
    const auto n = randomDistribution(M, 7, M / 2);  // i + j <= M for every occupied pair
    std::vector<double> f(M);
    rhs.evaluate(n.data(), f.data());
    double dM1 = 0.0, scale = 0.0;
    for (int i = 1; i <= M; ++i) {
      dM1 += i * f[i - 1];
      scale += i * std::fabs(f[i - 1]);
    }
    INFO("kernel " << k.name());
    CHECK(std::fabs(dM1) <= 1e-13 * scale);
  }
}

TEST_CASE("bad sizes are rejected", "[meanfield][rhs]") {
  CHECK_THROWS_AS(SmoluchowskiRhs(Kernel::constant(), 1), std::invalid_argument);
  CHECK(fftFriendlySize(601) == 625);
  CHECK(fftFriendlySize(1025) == 1029);
}
