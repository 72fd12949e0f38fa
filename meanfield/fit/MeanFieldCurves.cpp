// The mean-field curves S(t; beta) of the Smoluchowski equation, tabulated per beta
// (BetaFit.h: MeanFieldCurves).
#include "meanfield/fit/BetaFit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gsl/gsl_spline.h>

#include "common/Csv.h"
#include "meanfield/fit/FitSupport.h"
#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/SectionalSolver.h"
#include "meanfield/solvers/SmolResult.h"

namespace granagg::meanfield {

using common::formatReal;
using namespace detail;

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

}  // namespace granagg::meanfield
