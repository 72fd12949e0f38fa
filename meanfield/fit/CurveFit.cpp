// The fit of the whole curve S(t) by the mean-field curve (BetaFit.h: CurveFit).
#include "meanfield/fit/BetaFit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>

#include "common/Csv.h"
#include "common/Statistics.h"
#include "meanfield/fit/FitSupport.h"

namespace granagg::meanfield {

using common::formatReal;
using namespace detail;

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

/// Turns GSL's abort-on-error handler off while in scope: the fit reads failures from return
/// codes, and a throw on the way out restores the handler too.
class GslErrorsAsCodes {
 public:
  GslErrorsAsCodes() : m_old(gsl_set_error_handler_off()) {}
  ~GslErrorsAsCodes() { gsl_set_error_handler(m_old); }
  GslErrorsAsCodes(const GslErrorsAsCodes&) = delete;
  GslErrorsAsCodes& operator=(const GslErrorsAsCodes&) = delete;

 private:
  gsl_error_handler_t* m_old;
};

struct StartValues {
  double beta, lnSc, lntau;
};

/// Coarse scan for the start values: beta from beta_min in steps of 1 (and beta_max), ln tau_c in
/// steps of 0.2, ln S_c profiled out (the mean residual). ln tau_c runs from the value at which
/// the last sample sits at S_MF = S_scan = 4 S_max / S_min (clamped to [1e3, s_cap]: S_c down to
/// S_min / 4) to the value at which the last sample sits at t/tau_c = 1e-3 (all data in the
/// early linear regime).
StartValues coarseScan(MeanFieldCurves& curves, const CurveProblem& prob,
                       const CurveFitOptions& o) {
  const std::vector<double>& lt = *prob.lt;
  const std::size_t n = lt.size();
  const double y_min = *std::min_element(prob.y.begin(), prob.y.end());
  const double y_max = *std::max_element(prob.y.begin(), prob.y.end());
  const double S_scan =
      std::min(curves.options().s_cap, std::max(1e3, 4.0 * std::exp(y_max - y_min)));
  std::vector<double> betas{o.beta_min};
  for (double b = o.beta_min + 1.0; b < o.beta_max - 0.25; b += 1.0) betas.push_back(b);
  betas.push_back(o.beta_max);
  double best = std::numeric_limits<double>::infinity();
  StartValues start{betas.front(), 0.0, 0.0};
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
        start = {beta, mean, lntau};
      }
    }
  }
  return start;
}

/// Intervals from refits to run-resampled means (the runs are the independent samples).
void bootstrapIntervals(const CurveProblem& prob, const LmResult& r, const GrowthData& data,
                        const CurveFitOptions& o, CurveFit& fit) {
  Rng rng(o.bootstrap.seed);
  std::vector<double> bs, ss, ts;
  CurveProblem pb = prob;
  for (int b = 0; b < o.bootstrap.replicates_curve; ++b) {
    const std::vector<double> S = resampledMean(data, rng.resample(data.runs.size()));
    for (std::size_t i = 0; i < pb.y.size(); ++i) pb.y[i] = std::log(S[i]);
    const LmResult rb = runLm(pb, r.u, r.lnSc, r.lntau, false);
    if (!rb.ok) continue;
    bs.push_back(rb.u);
    ss.push_back(rb.lnSc);
    ts.push_back(rb.lntau);
  }
  if (bs.size() < 10)
    throw std::runtime_error("the bootstrap of the full-curve fit failed in most replicates.");
  const std::size_t R = data.runs.size();
  const double conf = o.bootstrap.confidence;
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
}

/// Intervals from the fit's covariance, scaled by chi^2/dof (unit weights), Student's t.
void covarianceIntervals(const CurveProblem& prob, const LmResult& r, double dof, double conf,
                         CurveFit& fit) {
  const double scale = fit.chi2_dof;
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

  const StartValues start = coarseScan(curves, prob, o);
  const GslErrorsAsCodes gsl_errors;
  const LmResult r = runLm(prob, prob.uOf(start.beta), start.lnSc, start.lntau, true);
  if (!r.ok)
    throw std::runtime_error("the full-curve fit (gsl_multifit_nlinear) failed to converge.");
  CurveFit fit;
  fit.points = static_cast<int>(n);
  fit.iterations = r.iterations;
  fit.beta = r.beta;
  fit.S_c = std::exp(r.lnSc);
  fit.tau_c = std::exp(r.lntau);
  const double dof = static_cast<double>(n - 3);
  fit.chi2_dof = r.chi2 / dof;
  if (data.runs.size() >= static_cast<std::size_t>(std::max(o.bootstrap.min_runs, 2)) &&
      o.bootstrap.replicates_curve > 0)
    bootstrapIntervals(prob, r, data, o, fit);
  else
    covarianceIntervals(prob, r, dof, o.bootstrap.confidence, fit);
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
