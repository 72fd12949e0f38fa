#include "meanfield/fit/BetaFit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_rng.h>
#include <gsl/gsl_roots.h>
#include <gsl/gsl_spline.h>

#include "common/Csv.h"
#include "common/Statistics.h"
#include "common/Strings.h"
#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/SectionalSolver.h"
#include "meanfield/solvers/SmolResult.h"

namespace granagg::meanfield {

using common::formatReal;

namespace {

constexpr double NaN = std::numeric_limits<double>::quiet_NaN();

using common::stats::median;

/// Mean over the runs chosen by `pick` (indices into data.runs), at every time.
std::vector<double> resampledMean(const GrowthData& data, const std::vector<std::size_t>& pick) {
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
void ols(const std::vector<double>& x, const std::vector<double>& y, double& slope,
         double& intercept, double& se_slope) {
  const common::stats::LineFit f = common::stats::fitLine(x, y);
  slope = f.slope;
  intercept = f.intercept;
  se_slope = f.slope_se;
}

/// The bootstrap interval rule of common/Statistics.h, into low and high.
void bootstrapInterval(const std::vector<double>& values, double estimate, std::size_t runs,
                       double confidence, double& low, double& high) {
  const common::stats::Interval in =
      common::stats::bootstrapInterval(values, estimate, runs, confidence);
  low = in.low;
  high = in.high;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Data

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

// ---------------------------------------------------------------------------------------------
// z fit

ZFit fitGrowthExponent(const GrowthData& data, const SlopeWindow& window,
                       const BootstrapOptions& o) {
  validateGrowthData(data);
  if (!(o.confidence > 0.0 && o.confidence < 1.0))
    throw std::invalid_argument("confidence must lie in (0, 1).");
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < data.t.size(); ++i)
    if (data.t[i] >= window.t0 && data.t[i] <= window.t1) idx.push_back(i);
  if (idx.size() < 3)
    throw std::invalid_argument("too few points in the window [" + formatReal(window.t0) + ", " +
                                formatReal(window.t1) + "]: " + std::to_string(idx.size()) +
                                ", at least 3 needed.");
  std::vector<double> x, y;
  for (std::size_t i : idx) {
    x.push_back(std::log(data.t[i]));
    y.push_back(std::log(data.S[i]));
  }
  ZFit f;
  const auto [y_lo, y_hi] = std::minmax_element(y.begin(), y.end());
  if (*y_hi - *y_lo <= 1e-12) {
    f.z = f.z_low = f.z_high = NaN;
    f.S0 = f.S1 = f.prefactor = std::exp(*y_lo);
    f.t0 = data.t[idx.front()];
    f.t1 = data.t[idx.back()];
    f.points = static_cast<int>(idx.size());
    f.confidence = o.confidence;
    f.interval_method = "none";
    f.note = "S is " + common::formatShort(f.S0) + " at every sample of the window [" + common::formatShort(f.t0) +
             ", " + common::formatShort(f.t1) + "]: it does not grow, no growth exponent.";
    return f;
  }
  double c0, se;
  ols(x, y, f.z, c0, se);
  f.prefactor = std::exp(c0);
  f.t0 = data.t[idx.front()];
  f.t1 = data.t[idx.back()];
  f.points = static_cast<int>(idx.size());
  f.S0 = std::exp(c0 + f.z * x.front());
  f.S1 = std::exp(c0 + f.z * x.back());
  f.confidence = o.confidence;
  constexpr double ROUNDOFF = 1e-12;
  if (data.runs.size() >= static_cast<std::size_t>(std::max(o.min_runs, 2)) && o.replicates_z > 0) {
    Rng rng(o.seed);
    std::vector<double> zs;
    for (int b = 0; b < o.replicates_z; ++b) {
      const std::vector<double> S = resampledMean(data, rng.resample(data.runs.size()));
      std::vector<double> yb;
      for (std::size_t i : idx) yb.push_back(std::log(S[i]));
      double zb, cb, sb;
      ols(x, yb, zb, cb, sb);
      zs.push_back(zb);
    }
    bootstrapInterval(zs, f.z, data.runs.size(), o.confidence, f.z_low, f.z_high);
    f.z_low = std::min(f.z_low, f.z - ROUNDOFF);
    f.z_high = std::max(f.z_high, f.z + ROUNDOFF);
    f.interval_method = "bootstrap-runs";
    f.replicates = o.replicates_z;
  } else {
    const double half = std::max(
        common::stats::studentHalfWidth(se, static_cast<double>(idx.size() - 2), o.confidence),
        ROUNDOFF);
    f.z_low = f.z - half;
    f.z_high = f.z + half;
    f.interval_method = "student-t";
  }
  return f;
}

// ---------------------------------------------------------------------------------------------
// Mean-field curves

struct MeanFieldCurves::Node {
  double beta = 0.0;
  double s_end = 0.0;     // S at which the last solve was asked to stop
  bool complete = false;  // solved to s_cap: beyond, extrapolate
  std::vector<double> lt, lS;
  gsl_interp_accel* acc = nullptr;
  gsl_spline* spline = nullptr;
  double tail_slope = 0.0;
  ~Node() {
    if (spline) gsl_spline_free(spline);
    if (acc) gsl_interp_accel_free(acc);
  }

  double eval(double lt_q) const {
    if (lt_q <= lt.front()) {  // early linear growth S = 1 + (S_1 - 1) t / t_1
      return std::log1p(std::expm1(lS.front()) * std::exp(lt_q - lt.front()));
    }
    if (lt_q >= lt.back()) return lS.back() + tail_slope * (lt_q - lt.back());
    return gsl_spline_eval(spline, lt_q, acc);
  }
};

MeanFieldCurves::MeanFieldCurves(const MeanFieldCurveOptions& options) : m_options(options) {
  if (!(options.ratio > 1.0)) throw std::invalid_argument("mean-field grid ratio must be > 1.");
  if (!(options.beta_step > 0.0)) throw std::invalid_argument("beta_step must be positive.");
  if (!(options.initial_s_end > 10.0) || !(options.s_cap >= options.initial_s_end))
    throw std::invalid_argument("need 10 < initial_s_end <= s_cap.");
  if (options.per_decade < 10) throw std::invalid_argument("per_decade must be at least 10.");
}

MeanFieldCurves::~MeanFieldCurves() = default;

int MeanFieldCurves::solves() const { return m_solves; }

MeanFieldCurves::Node& MeanFieldCurves::node(int k, double t_needed) {
  auto& slot = m_nodes[k];
  auto solve = [&](double s_end) {
    const double beta = k * m_options.beta_step;
    if (!(beta > 0.0))
      throw std::invalid_argument("mean-field curves need beta > 0 (got " + formatReal(beta) +
                                  ").");
    SectionalOptions so;
    so.ratio = m_options.ratio;
    so.rtol = m_options.rtol;
    so.s_end = s_end;
    so.integrator = s_end <= 1e5 ? "adams" : "bdf";
    so.max_size = std::max(1e12, 1e4 * s_end);
    // Up to 1e16 time units: S = 1e8 needs t ~ 1e8^{1/z}, z >= 0.75 for beta >= 1.
    const int decades = 22;
    so.times = logSpacedTimes(1e-6, 1e16, decades * m_options.per_decade + 1);
    const SmolResult r = solveSectional(Kernel::beta(beta), so);
    ++m_solves;
    auto nd = std::make_unique<Node>();
    nd->beta = beta;
    nd->s_end = s_end;
    for (const auto& s : r.samples)
      if (s.valid) {
        nd->lt.push_back(std::log(s.t));
        nd->lS.push_back(std::log(s.S));
      }
    if (nd->lt.size() < 8)
      throw std::runtime_error(
          "mean-field solve for beta = " + formatReal(beta) + " returned only " +
          std::to_string(nd->lt.size()) + " valid samples" +
          (r.stopped_early.empty() ? std::string() : " (" + r.stopped_early + ")"));
    nd->complete = s_end >= m_options.s_cap || std::exp(nd->lS.back()) < 0.5 * s_end;
    nd->acc = gsl_interp_accel_alloc();
    nd->spline = gsl_spline_alloc(gsl_interp_cspline, nd->lt.size());
    gsl_spline_init(nd->spline, nd->lt.data(), nd->lS.data(), nd->lt.size());
    // local slope over a factor ~2 in t at the end
    const std::size_t m = std::max<std::size_t>(
        1, static_cast<std::size_t>(std::lround(0.30103 * m_options.per_decade)));
    const std::size_t last = nd->lt.size() - 1;
    const std::size_t m_used = std::min(m, last);
    nd->tail_slope =
        (nd->lS[last] - nd->lS[last - m_used]) / (nd->lt[last] - nd->lt[last - m_used]);
    slot = std::move(nd);
  };
  if (!slot) solve(m_options.initial_s_end);
  while (!slot->complete && std::log(t_needed) > slot->lt.back())
    solve(std::min(m_options.s_cap, 10.0 * slot->s_end));
  return *slot;
}

double MeanFieldCurves::logS(double t, double beta) {
  if (!(t > 0.0)) throw std::invalid_argument("mean-field S needs t > 0.");
  const double h = m_options.beta_step;
  if (!(beta > 2.0 * h))
    throw std::invalid_argument("mean-field curves need beta > " + formatReal(2.0 * h) + ".");
  const double lt = std::log(t);
  const double x = beta / h;
  const double kr = std::round(x);
  if (std::fabs(x - kr) < 1e-9) return node(static_cast<int>(kr), t).eval(lt);
  const int k = static_cast<int>(std::floor(x));
  const double u = x - k;
  const double p0 = node(k - 1, t).eval(lt), p1 = node(k, t).eval(lt), p2 = node(k + 1, t).eval(lt),
               p3 = node(k + 2, t).eval(lt);
  // Catmull-Rom: C1 cubic through p1 (u = 0) and p2 (u = 1) with central-difference tangents.
  return p1 + 0.5 * u * (p2 - p0) + u * u * (p0 - 2.5 * p1 + 2.0 * p2 - 0.5 * p3) +
         u * u * u * (1.5 * (p1 - p2) + 0.5 * (p3 - p0));
}

double MeanFieldCurves::timeAtS(double S, double beta) {
  if (!(S > 1.0) || !std::isfinite(S))
    throw std::invalid_argument("the mean-field S starts at 1: no time has S = " + formatReal(S) +
                                ".");
  const double target = std::log(S);
  double lo = std::log(1e-8), hi = 0.0;
  while (logS(std::exp(hi), beta) < target) {
    lo = hi;
    hi += 2.0;
    if (hi > 80.0) throw std::runtime_error("mean-field S never reaches " + formatReal(S) + ".");
  }
  for (int it = 0; it < 200 && hi - lo > 1e-13; ++it) {
    const double mid = 0.5 * (lo + hi);
    (logS(std::exp(mid), beta) < target ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

double MeanFieldCurves::exponentBetween(double S0, double S1, double beta) {
  if (!(S1 > S0)) throw std::invalid_argument("exponentBetween needs S1 > S0.");
  const double t0 = timeAtS(S0, beta), t1 = timeAtS(S1, beta);
  const auto ts = logSpacedTimes(t0, t1, 64);
  std::vector<double> x, y;
  for (double t : ts) {
    x.push_back(std::log(t));
    y.push_back(logS(t, beta));
  }
  double z, c, se;
  ols(x, y, z, c, se);
  return z;
}

// ---------------------------------------------------------------------------------------------
// beta from z

void validateBetaRange(double beta_min, double beta_max) {
  if (!(beta_min >= BETA_LOWEST) || !(beta_min <= BETA_HIGHEST))
    throw std::invalid_argument("--beta-min must lie in [" + formatReal(BETA_LOWEST) + ", " +
                                formatReal(BETA_HIGHEST) + "] (got " + formatReal(beta_min) + ").");
  if (!(beta_max >= BETA_LOWEST) || !(beta_max <= BETA_HIGHEST))
    throw std::invalid_argument("--beta-max must lie in [" + formatReal(BETA_LOWEST) + ", " +
                                formatReal(BETA_HIGHEST) + "] (got " + formatReal(beta_max) + ").");
  if (!(beta_max - beta_min >= 0.1))
    throw std::invalid_argument("--beta-max must exceed --beta-min by at least 0.1 (got " +
                                formatReal(beta_min) + ", " + formatReal(beta_max) + ").");
}

namespace {
struct RootParams {
  MeanFieldCurves* curves;
  double S0, S1, z;
};
double zResidual(double beta, void* p) {
  auto* r = static_cast<RootParams*>(p);
  return r->curves->exponentBetween(r->S0, r->S1, beta) - r->z;
}
}  // namespace

BetaFromZ betaAsymptotic(double z, double z_low, double z_high) {
  BetaFromZ out;
  out.S0 = out.S1 = out.z_at_beta_min = out.z_at_beta_max = NaN;
  // beta(z) = 3 z / (3 - z), increasing on (0, 3) from 0 to +inf.
  auto beta = [](double x) {
    if (!std::isfinite(x)) return NaN;
    if (x <= 0.0) return 0.0;
    if (x >= 3.0) return std::numeric_limits<double>::infinity();
    return 3.0 * x / (3.0 - x);
  };
  if (!std::isfinite(z) || z <= 0.0 || z >= 3.0) {
    out.beta = out.beta_low = out.beta_high = NaN;
    out.note =
        std::isfinite(z)
            ? (z <= 0.0 ? "z = " + common::formatShort(z) + " <= 0: S does not grow, no beta."
                        : "z = " + common::formatShort(z) +
                              " >= 3: faster than 3 beta/(beta + 3) for every beta, no beta.")
            : "z is not finite: no beta.";
    return out;
  }
  out.beta = beta(z);
  out.beta_low = beta(z_low);
  out.beta_high = beta(z_high);
  if (std::isfinite(z_high) && z_high >= 3.0)
    out.note += "z_high = " + common::formatShort(z_high) + " >= 3: no upper bound on beta. ";
  if (std::isfinite(z_low) && z_low <= 0.0)
    out.note += "z_low = " + common::formatShort(z_low) + " <= 0: the interval reaches beta = 0. ";
  if (!out.note.empty()) out.note.pop_back();
  return out;
}

BetaFromZ betaFromZ(MeanFieldCurves& curves, double z, double z_low, double z_high, double S0,
                    double S1, double beta_min, double beta_max) {
  validateBetaRange(beta_min, beta_max);
  BetaFromZ out;
  std::string note;
  const double S_floor = 1.0001;
  if (S0 < S_floor) {
    note += "window starts at S = " + common::formatShort(S0) +
            " <= 1, the mean field's initial S; compared from S = 1.0001. ";
    S0 = S_floor;
  }
  out.S0 = S0;
  out.S1 = S1;
  if (!(S1 > S0 * 1.0001)) {
    out.beta = out.beta_low = out.beta_high = out.z_at_beta_min = out.z_at_beta_max = NaN;
    out.note = note + "S does not grow over the window: no mean-field exponent to compare with.";
    return out;
  }
  out.z_at_beta_min = curves.exponentBetween(S0, S1, beta_min);
  out.z_at_beta_max = curves.exponentBetween(S0, S1, beta_max);
  gsl_error_handler_t* old = gsl_set_error_handler_off();
  const double h = curves.options().beta_step;
  std::map<int, double> zNodes;
  auto zNode = [&](int k) {
    auto it = zNodes.find(k);
    if (it == zNodes.end()) it = zNodes.emplace(k, curves.exponentBetween(S0, S1, k * h)).first;
    return it->second;
  };
  auto invert = [&](double zt, bool central, const char* what) -> double {
    if (!std::isfinite(zt)) return NaN;
    if (zt <= out.z_at_beta_min || zt >= out.z_at_beta_max) {
      const bool below = zt <= out.z_at_beta_min;
      note += std::string(what) + " = " + common::formatShort(zt) + " lies " + (below ? "below" : "above") +
              " the mean-field z = " + common::formatShort(below ? out.z_at_beta_min : out.z_at_beta_max) +
              " at beta = " + formatReal(below ? beta_min : beta_max) +
              (central ? ": no beta" : ": clamped to the range") + ". ";
      return central ? NaN : (below ? beta_min : beta_max);
    }
    // Bracket on the beta nodes first (exact nodes need one solve each, interpolated betas four):
    // bisection over node indices, then Brent's method inside one node cell.
    double lo = beta_min, hi = beta_max;
    int klo = static_cast<int>(std::ceil(beta_min / h - 1e-9)),
        khi = static_cast<int>(std::floor(beta_max / h + 1e-9));
    if (klo <= khi) {
      if (zt < zNode(klo)) {
        hi = klo * h;
      } else if (zt >= zNode(khi)) {
        lo = khi * h;
      } else {
        while (khi - klo > 1) {
          const int mid = (klo + khi) / 2;
          (zNode(mid) <= zt ? klo : khi) = mid;
        }
        lo = klo * h;
        hi = khi * h;
      }
    }
    RootParams rp{&curves, S0, S1, zt};
    gsl_function F{&zResidual, &rp};
    gsl_root_fsolver* s = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    gsl_root_fsolver_set(s, &F, lo, hi);
    double root = NaN;
    for (int it = 0; it < 100; ++it) {
      if (gsl_root_fsolver_iterate(s) != GSL_SUCCESS) break;
      root = gsl_root_fsolver_root(s);
      if (gsl_root_test_interval(gsl_root_fsolver_x_lower(s), gsl_root_fsolver_x_upper(s), 1e-7,
                                 0.0) == GSL_SUCCESS)
        break;
    }
    gsl_root_fsolver_free(s);
    return root;
  };
  out.beta = invert(z, true, "z");
  out.beta_low = invert(z_low, false, "z_low");
  out.beta_high = invert(z_high, false, "z_high");
  gsl_set_error_handler(old);
  out.note = note;
  while (!out.note.empty() && out.note.back() == ' ') out.note.pop_back();
  return out;
}

// ---------------------------------------------------------------------------------------------
// Full-curve fit

namespace {

/// The fit's parameters are (u, ln S_c, ln tau_c) with beta = beta_min + (beta_max - beta_min) /
/// (1 + e^-u): the logistic map takes the whole real line onto the open search range, so the fit
/// needs no clamp and its intervals, formed in u and mapped back, stay inside the range. (Formed
/// in beta, a covariance interval of a poorly determined beta could reach negative values.) Near
/// the middle of the range the map is close to linear: intervals are those in beta.
struct CurveProblem {
  MeanFieldCurves* curves;
  const std::vector<double>* lt;  // ln t_i
  std::vector<double> y;          // ln S_i
  double beta_min, beta_max;
  double betaOf(double u) const { return beta_min + (beta_max - beta_min) / (1.0 + std::exp(-u)); }
  /// The inverse, for a start value (kept 1e-3 of the range away from the bounds: finite u).
  double uOf(double beta) const {
    const double f = std::min(std::max((beta - beta_min) / (beta_max - beta_min), 1e-3), 1 - 1e-3);
    return std::log(f / (1.0 - f));
  }
  double model(double lt_i, double beta, double ln_tau) const {
    return curves->logS(std::exp(lt_i - ln_tau), beta);
  }
};

int curveResidual(const gsl_vector* x, void* params, gsl_vector* f) {
  auto* p = static_cast<CurveProblem*>(params);
  const double u = gsl_vector_get(x, 0), lnSc = gsl_vector_get(x, 1), lntau = gsl_vector_get(x, 2);
  if (!std::isfinite(u) || !std::isfinite(lnSc) || !std::isfinite(lntau) ||
      std::fabs(lntau) > 200.0)
    return GSL_EDOM;
  const double beta = p->betaOf(u);
  try {
    for (std::size_t i = 0; i < p->y.size(); ++i)
      gsl_vector_set(f, i, p->y[i] - lnSc - p->model((*p->lt)[i], beta, lntau));
  } catch (const std::exception&) {
    return GSL_EDOM;
  }
  return GSL_SUCCESS;
}

struct LmResult {
  double u, beta, lnSc, lntau, chi2;  // beta = betaOf(u); cov is of (u, ln S_c, ln tau_c)
  double cov[3][3];
  int iterations;
  bool ok;
};

LmResult runLm(CurveProblem& prob, double u0, double lnSc0, double lntau0, bool covariance) {
  const std::size_t n = prob.y.size(), p = 3;
  gsl_multifit_nlinear_parameters params = gsl_multifit_nlinear_default_parameters();
  params.trs = gsl_multifit_nlinear_trs_lm;
  params.fdtype = GSL_MULTIFIT_NLINEAR_CTRDIFF;
  gsl_multifit_nlinear_workspace* w =
      gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &params, n, p);
  gsl_multifit_nlinear_fdf fdf;
  fdf.f = &curveResidual;
  fdf.df = nullptr;  // finite differences
  fdf.fvv = nullptr;
  fdf.n = n;
  fdf.p = p;
  fdf.params = &prob;
  gsl_vector* x = gsl_vector_alloc(p);
  gsl_vector_set(x, 0, u0);
  gsl_vector_set(x, 1, lnSc0);
  gsl_vector_set(x, 2, lntau0);
  LmResult r{};
  r.ok = gsl_multifit_nlinear_init(x, &fdf, w) == GSL_SUCCESS;
  int info = 0;
  if (r.ok) {
    const int status =
        gsl_multifit_nlinear_driver(200, 1e-10, 1e-10, 0.0, nullptr, nullptr, &info, w);
    r.ok = status == GSL_SUCCESS || status == GSL_EMAXITER || status == GSL_ENOPROG;
  }
  const gsl_vector* xs = gsl_multifit_nlinear_position(w);
  r.u = gsl_vector_get(xs, 0);
  r.beta = prob.betaOf(r.u);
  r.lnSc = gsl_vector_get(xs, 1);
  r.lntau = gsl_vector_get(xs, 2);
  const gsl_vector* f = gsl_multifit_nlinear_residual(w);
  double chi2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) chi2 += gsl_vector_get(f, i) * gsl_vector_get(f, i);
  r.chi2 = chi2;
  r.iterations = static_cast<int>(gsl_multifit_nlinear_niter(w));
  if (covariance) {
    gsl_matrix* cov = gsl_matrix_alloc(p, p);
    gsl_multifit_nlinear_covar(gsl_multifit_nlinear_jac(w), 0.0, cov);
    for (std::size_t a = 0; a < p; ++a)
      for (std::size_t b = 0; b < p; ++b) r.cov[a][b] = gsl_matrix_get(cov, a, b);
    gsl_matrix_free(cov);
  }
  gsl_vector_free(x);
  gsl_multifit_nlinear_free(w);
  return r;
}

}  // namespace

CurveFit fitCurve(MeanFieldCurves& curves, const GrowthData& data, const CurveFitOptions& o) {
  validateGrowthData(data);
  validateBetaRange(o.beta_min, o.beta_max);
  const std::size_t n = data.t.size();
  if (n < 5)
    throw std::invalid_argument("too few points for the curve fit: " + std::to_string(n) +
                                ", at least 5 needed.");
  std::vector<double> lt(n);
  for (std::size_t i = 0; i < n; ++i) lt[i] = std::log(data.t[i]);
  CurveProblem prob{&curves, &lt, {}, o.beta_min, o.beta_max};
  prob.y.resize(n);
  for (std::size_t i = 0; i < n; ++i) prob.y[i] = std::log(data.S[i]);

  // Coarse scan: beta from beta_min in steps of 1 (and beta_max), ln tau_c in steps of 0.2, ln S_c
  // profiled out (the mean residual). ln tau_c runs from the value at which the last sample sits at
  // S_MF = S_scan = 4 S_max / S_min (clamped to [1e3, s_cap]: S_c down to S_min / 4) to the value
  // at which the last sample sits at t/tau_c = 1e-3 (all data in the early linear regime).
  const double y_min = *std::min_element(prob.y.begin(), prob.y.end());
  const double y_max = *std::max_element(prob.y.begin(), prob.y.end());
  const double S_scan =
      std::min(curves.options().s_cap, std::max(1e3, 4.0 * std::exp(y_max - y_min)));
  std::vector<double> betas{o.beta_min};
  for (double b = o.beta_min + 1.0; b < o.beta_max - 0.25; b += 1.0) betas.push_back(b);
  betas.push_back(o.beta_max);
  double best = std::numeric_limits<double>::infinity(), b0 = betas.front(), s0 = 0.0, tau0 = 0.0;
  for (double beta : betas) {
    const double lt_lo = lt.back() - std::log(curves.timeAtS(S_scan, beta));
    const double lt_hi = lt.back() + std::log(1e3);
    for (double lntau = lt_lo; lntau <= lt_hi; lntau += 0.2) {
      std::vector<double> m(n);
      double mean = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        m[i] = prob.model(lt[i], beta, lntau);
        mean += prob.y[i] - m[i];
      }
      mean /= static_cast<double>(n);
      double ssr = 0.0;
      for (std::size_t i = 0; i < n; ++i)
        ssr += (prob.y[i] - m[i] - mean) * (prob.y[i] - m[i] - mean);
      if (ssr < best) {
        best = ssr;
        b0 = beta;
        s0 = mean;
        tau0 = lntau;
      }
    }
  }

  gsl_error_handler_t* old = gsl_set_error_handler_off();
  const LmResult r = runLm(prob, prob.uOf(b0), s0, tau0, true);
  if (!r.ok) {
    gsl_set_error_handler(old);
    throw std::runtime_error("the full-curve fit (gsl_multifit_nlinear) failed to converge.");
  }
  CurveFit fit;
  fit.points = static_cast<int>(n);
  fit.iterations = r.iterations;
  fit.beta = r.beta;
  fit.S_c = std::exp(r.lnSc);
  fit.tau_c = std::exp(r.lntau);
  const double dof = static_cast<double>(n - 3);
  fit.chi2_dof = r.chi2 / dof;
  const double conf = o.bootstrap.confidence;
  if (data.runs.size() >= static_cast<std::size_t>(std::max(o.bootstrap.min_runs, 2)) &&
      o.bootstrap.replicates_curve > 0) {
    Rng rng(o.bootstrap.seed);
    std::vector<double> bs, ss, ts;
    CurveProblem pb = prob;
    for (int b = 0; b < o.bootstrap.replicates_curve; ++b) {
      const std::vector<double> S = resampledMean(data, rng.resample(data.runs.size()));
      for (std::size_t i = 0; i < n; ++i) pb.y[i] = std::log(S[i]);
      const LmResult rb = runLm(pb, r.u, r.lnSc, r.lntau, false);
      if (!rb.ok) continue;
      bs.push_back(rb.u);
      ss.push_back(rb.lnSc);
      ts.push_back(rb.lntau);
    }
    if (bs.size() < 10) {
      gsl_set_error_handler(old);
      throw std::runtime_error("the bootstrap of the full-curve fit failed in most replicates.");
    }
    const std::size_t R = data.runs.size();
    double lo, hi;
    bootstrapInterval(bs, r.u, R, conf, lo, hi);
    fit.beta_low = prob.betaOf(lo);
    fit.beta_high = prob.betaOf(hi);
    bootstrapInterval(ss, r.lnSc, R, conf, lo, hi);
    fit.S_c_low = std::exp(lo);
    fit.S_c_high = std::exp(hi);
    bootstrapInterval(ts, r.lntau, R, conf, lo, hi);
    fit.tau_c_low = std::exp(lo);
    fit.tau_c_high = std::exp(hi);
    fit.interval_method = "bootstrap-runs";
    fit.replicates = static_cast<int>(bs.size());
  } else {
    const double scale = fit.chi2_dof;  // covariance scaled by chi^2/dof (unit weights)
    auto half = [&](int k) {
      return common::stats::studentHalfWidth(std::sqrt(std::max(r.cov[k][k] * scale, 0.0)), dof,
                                             conf);
    };
    fit.beta_low = prob.betaOf(r.u - half(0));
    fit.beta_high = prob.betaOf(r.u + half(0));
    fit.S_c_low = std::exp(r.lnSc - half(1));
    fit.S_c_high = std::exp(r.lnSc + half(1));
    fit.tau_c_low = std::exp(r.lntau - half(2));
    fit.tau_c_high = std::exp(r.lntau + half(2));
    fit.interval_method = "covariance";
  }
  gsl_set_error_handler(old);
  const double edge = 1e-4 * (o.beta_max - o.beta_min);
  fit.at_bound = fit.beta <= o.beta_min + edge || fit.beta >= o.beta_max - edge;
  if (fit.at_bound) {  // no interval: the data do not determine beta within the range
    fit.beta_low = fit.beta_high = std::numeric_limits<double>::quiet_NaN();
    fit.note = "beta_fit lies at the bound " +
               formatReal(fit.beta <= o.beta_min + edge ? o.beta_min : o.beta_max) +
               " of the search range, so beta is not determined there; granagg fit-beta with a "
               "wider --beta-min/--beta-max searches further.";
  }
  fit.S_fitted.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    fit.S_fitted[i] = fit.S_c * std::exp(prob.model(lt[i], fit.beta, r.lntau));
  return fit;
}

}  // namespace granagg::meanfield
