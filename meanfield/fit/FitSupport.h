#pragma once
/// \file FitSupport.h
/// Helpers the parts of the beta fit share (GrowthData.cpp, GrowthExponentFit.cpp,
/// MeanFieldCurves.cpp, BetaFromZ.cpp, CurveFit.cpp): the ensemble mean of resampled runs, a
/// seeded GSL generator for the bootstrap, and common/Statistics.h's line fit and bootstrap
/// interval in the shape the fits use. Internal to meanfield/fit.
#include <cstdint>
#include <limits>
#include <vector>

#include <gsl/gsl_rng.h>

#include "common/Statistics.h"
#include "meanfield/fit/BetaFit.h"

namespace granagg::meanfield::detail {

constexpr double NaN = std::numeric_limits<double>::quiet_NaN();

using common::stats::median;

/// Mean over the runs chosen by `pick` (indices into data.runs), at every time.
inline std::vector<double> resampledMean(const GrowthData& data,
                                         const std::vector<std::size_t>& pick) {
  std::vector<double> S(data.t.size(), 0.0);
  for (std::size_t r : pick)
    for (std::size_t i = 0; i < S.size(); ++i) S[i] += data.runs[r][i];
  for (double& s : S) s /= static_cast<double>(pick.size());
  return S;
}

/// RAII wrapper of a GSL random number generator (mt19937 with a fixed seed).
struct Rng {
  gsl_rng* r;
  explicit Rng(std::uint64_t seed) : r(gsl_rng_alloc(gsl_rng_mt19937)) {
    gsl_rng_set(r, static_cast<unsigned long>(seed));
  }
  ~Rng() { gsl_rng_free(r); }
  Rng(const Rng&) = delete;
  Rng& operator=(const Rng&) = delete;
  std::vector<std::size_t> resample(std::size_t n) {
    std::vector<std::size_t> pick(n);
    for (auto& k : pick) k = gsl_rng_uniform_int(r, n);
    return pick;
  }
};

/// OLS slope and intercept of y on x (common/Statistics.h).
inline void ols(const std::vector<double>& x, const std::vector<double>& y, double& slope,
                double& intercept, double& se_slope) {
  const common::stats::LineFit f = common::stats::fitLine(x, y);
  slope = f.slope;
  intercept = f.intercept;
  se_slope = f.slope_se;
}

/// The bootstrap interval rule of common/Statistics.h, into low and high.
inline void bootstrapInterval(const std::vector<double>& values, double estimate, std::size_t runs,
                              double confidence, double& low, double& high) {
  const common::stats::Interval in =
      common::stats::bootstrapInterval(values, estimate, runs, confidence);
  low = in.low;
  high = in.high;
}

}  // namespace granagg::meanfield::detail
