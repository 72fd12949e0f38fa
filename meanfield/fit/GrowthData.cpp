// The growth data S(t) and the windows of the z fit (BetaFit.h: GrowthData, SlopeWindow).
#include "meanfield/fit/BetaFit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/Csv.h"
#include "meanfield/fit/FitSupport.h"

namespace granagg::meanfield {

using common::formatReal;
using namespace detail;

GrowthData growthFromSeries(std::vector<double> t, std::vector<double> S) {
  GrowthData d;
  d.t = std::move(t);
  d.S = std::move(S);
  return d;
}

GrowthData growthFromRuns(std::vector<double> t, std::vector<std::vector<double>> runs) {
  if (runs.empty()) throw std::invalid_argument("growthFromRuns needs at least one run.");
  GrowthData d;
  d.t = std::move(t);
  for (const auto& r : runs)
    if (r.size() != d.t.size())
      throw std::invalid_argument("every run must have one S per time (" +
                                  std::to_string(d.t.size()) + "), found " +
                                  std::to_string(r.size()) + ".");
  if (runs.size() == 1) {
    d.S = std::move(runs.front());
    return d;
  }
  d.runs = std::move(runs);
  std::vector<std::size_t> all(d.runs.size());
  for (std::size_t r = 0; r < all.size(); ++r) all[r] = r;
  d.S = resampledMean(d, all);
  return d;
}

void validateGrowthData(const GrowthData& d) {
  if (d.t.size() != d.S.size())
    throw std::invalid_argument("t and S must have the same length (" + std::to_string(d.t.size()) +
                                " and " + std::to_string(d.S.size()) + ").");
  for (std::size_t i = 0; i < d.t.size(); ++i) {
    if (!(d.t[i] > 0.0) || !std::isfinite(d.t[i]))
      throw std::invalid_argument("t must be positive and finite (t = " + formatReal(d.t[i]) +
                                  " at row " + std::to_string(i + 1) + ").");
    if (i && !(d.t[i] > d.t[i - 1]))
      throw std::invalid_argument("t must increase strictly (t = " + formatReal(d.t[i]) +
                                  " follows " + formatReal(d.t[i - 1]) + " at row " +
                                  std::to_string(i + 1) + ").");
    if (!(d.S[i] > 0.0) || !std::isfinite(d.S[i]))
      throw std::invalid_argument("S must be positive and finite (S = " + formatReal(d.S[i]) +
                                  " at t = " + formatReal(d.t[i]) + ").");
  }
  for (std::size_t r = 0; r < d.runs.size(); ++r) {
    if (d.runs[r].size() != d.t.size())
      throw std::invalid_argument("run " + std::to_string(r) + " has " +
                                  std::to_string(d.runs[r].size()) + " values of S for " +
                                  std::to_string(d.t.size()) + " times.");
    for (std::size_t i = 0; i < d.t.size(); ++i)
      if (!(d.runs[r][i] > 0.0) || !std::isfinite(d.runs[r][i]))
        throw std::invalid_argument(
            "S must be positive and finite (S = " + formatReal(d.runs[r][i]) + " in run " +
            std::to_string(r) + " at t = " + formatReal(d.t[i]) + ").");
  }
}

// ---------------------------------------------------------------------------------------------
// Windows

SlopeWindow explicitWindow(const GrowthData& data, double t0, double t1, int min_points) {
  if (!(t0 < t1) || !std::isfinite(t0) || !std::isfinite(t1))
    throw std::invalid_argument("the window must satisfy T0 < T1 (got " + formatReal(t0) + ", " +
                                formatReal(t1) + ").");
  SlopeWindow w;
  w.automatic = false;
  bool first = true;
  // Ends include samples within a relative 1e-4: MD frames sit on whole steps, so the frame
  // meant for t = 1000 may be at 1000.001 and must not drop out of a window [., 1000].
  for (double t : data.t)
    if (t >= t0 * (1 - 1e-4) && t <= t1 * (1 + 1e-4)) {
      if (first) w.t0 = t;
      first = false;
      w.t1 = t;
      ++w.points;
    }
  if (w.points < min_points)
    throw std::invalid_argument("too few points in the window [" + formatReal(t0) + ", " +
                                formatReal(t1) + "]: " + std::to_string(w.points) +
                                " samples, at least " + std::to_string(min_points) + " needed.");
  w.rule = "window given by the user: [" + formatReal(t0) + ", " + formatReal(t1) + "]";
  return w;
}

SlopeWindow automaticWindow(const GrowthData& data, const WindowOptions& o) {
  validateGrowthData(data);
  if (o.min_points < 3) throw std::invalid_argument("a window needs at least 3 points.");
  const std::size_t n = data.t.size();
  const std::size_t min_points = static_cast<std::size_t>(o.min_points);
  if (n < min_points)
    throw std::invalid_argument("too few points: S(t) has " + std::to_string(n) +
                                " samples, a window needs at least " +
                                std::to_string(o.min_points) + ".");
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = std::log(data.t[i]);
    y[i] = std::log(data.S[i]);
  }

  // Noise of ln S.
  double sigma = 0.0;
  std::string noise_from;
  if (data.runs.size() >= 2) {
    const double R = static_cast<double>(data.runs.size());
    std::vector<double> se;
    for (std::size_t i = 0; i < n; ++i) {
      double v = 0.0;
      for (const auto& r : data.runs) v += (r[i] - data.S[i]) * (r[i] - data.S[i]);
      se.push_back(std::sqrt(v / (R - 1.0) / R) / data.S[i]);
    }
    sigma = median(se);
    noise_from = "standard error over runs";
  } else if (n >= 3) {
    std::vector<double> d2;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      // second difference on a non-uniform grid, normalised to the noise of one sample
      const double h0 = x[i] - x[i - 1], h1 = x[i + 1] - x[i];
      const double w0 = h1 / (h0 + h1), w1 = h0 / (h0 + h1);  // y_i - (w0 y_{i-1} + w1 y_{i+1})
      d2.push_back(std::fabs(y[i] - w0 * y[i - 1] - w1 * y[i + 1]) /
                   std::sqrt(1.0 + w0 * w0 + w1 * w1));
    }
    sigma = 1.4826 * median(d2);
    noise_from = "scatter about neighbours";
  }
  // Slope of a least-squares line through (x, y) on [i, j), and its standard error for noise sigma.
  auto slope = [&](std::size_t i, std::size_t j, double& se) {
    double xm = 0.0, ym = 0.0;
    for (std::size_t k = i; k < j; ++k) {
      xm += x[k];
      ym += y[k];
    }
    xm /= static_cast<double>(j - i);
    ym /= static_cast<double>(j - i);
    double sxx = 0.0, sxy = 0.0;
    for (std::size_t k = i; k < j; ++k) {
      sxx += (x[k] - xm) * (x[k] - xm);
      sxy += (x[k] - xm) * (y[k] - ym);
    }
    se = sigma / std::sqrt(sxx);
    return sxy / sxx;
  };
  // A stretch [a, n) is flat when the exponents fitted to its earlier and later halves (split at
  // the middle in ln t) differ by at most max(noise_factor x the standard error of the difference,
  // min_tolerance).
  auto flat = [&](std::size_t a) {
    const double mid = 0.5 * (x[a] + x[n - 1]);
    std::size_t m = a;
    while (m < n && x[m] <= mid) ++m;
    if (m - a < 3 || n - m < 3) return true;
    double se1, se2;
    const double z1 = slope(a, m, se1), z2 = slope(m, n, se2);
    return std::fabs(z2 - z1) <=
           std::max(o.noise_factor * std::sqrt(se1 * se1 + se2 * se2), o.min_tolerance);
  };
  std::size_t a = n - min_points;
  while (a > 0 && flat(a - 1)) --a;

  SlopeWindow w;
  w.automatic = true;
  w.sigma_lnS = sigma;
  w.tolerance = o.min_tolerance;
  w.t0 = data.t[a];
  w.t1 = data.t.back();
  w.points = static_cast<int>(n - a);
  const bool fallback = a == n - min_points && a > 0;  // the loop stopped at its first test
  const std::string tail =
      fallback ? ", no longer flat stretch: the last " + std::to_string(o.min_points) + " samples"
               : std::string();
  char buf[600];
  std::snprintf(buf, sizeof buf,
                "automatic: longest stretch ending at the last sample over which the local slope "
                "is flat -- power-law "
                "exponents of its earlier and later halves (in ln t) agree within max(%g standard "
                "errors, %g); noise "
                "of ln S %.3g (%s)%s",
                o.noise_factor, o.min_tolerance, sigma, noise_from.c_str(), tail.c_str());
  w.rule = buf;
  return w;
}

}  // namespace granagg::meanfield
