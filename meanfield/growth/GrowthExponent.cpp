#include "meanfield/growth/GrowthExponent.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "common/Csv.h"
#include "common/Statistics.h"

namespace granagg::meanfield {

namespace {
void checkSeries(const std::vector<double>& t, const std::vector<double>& S) {
  if (t.size() != S.size()) throw std::invalid_argument("t and S must have the same length.");
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!(t[i] > 0.0) || !std::isfinite(t[i]))
      throw std::invalid_argument("times must be positive and finite (t[" + std::to_string(i) +
                                  "] = " + common::formatReal(t[i]) + ").");
    if (i && !(t[i] > t[i - 1]))
      throw std::invalid_argument("times must increase strictly (t[" + std::to_string(i) +
                                  "] = " + common::formatReal(t[i]) + ").");
    if (!(S[i] > 0.0) || !std::isfinite(S[i]))
      throw std::invalid_argument("S must be positive and finite (S[" + std::to_string(i) +
                                  "] = " + common::formatReal(S[i]) + ").");
  }
}
}  // namespace

LocalSlope localSlope(const std::vector<double>& t, const std::vector<double>& S, double p) {
  if (!(p > 1.0))
    throw std::invalid_argument("the local-slope ratio p must be > 1 (got " +
                                common::formatReal(p) + ").");
  checkSeries(t, S);
  // (common/Statistics.h; NaN only where t_i / p precedes the first time: left out here)
  const std::vector<double> z = common::stats::localSlope(t, S, p);
  LocalSlope out;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (!std::isnan(z[i])) {
      out.t.push_back(t[i]);
      out.z.push_back(z[i]);
    }
  return out;
}

PowerLawFit fitPowerLaw(const std::vector<double>& t, const std::vector<double>& S, double t_min,
                        double t_max, double confidence) {
  checkSeries(t, S);
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("confidence must lie in (0, 1) (got " +
                                common::formatReal(confidence) + ").");
  std::vector<double> x, y;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] >= t_min && t[i] <= t_max) {
      x.push_back(std::log(t[i]));
      y.push_back(std::log(S[i]));
    }
  if (x.size() < 3)
    throw std::invalid_argument("power-law fit needs at least 3 points in the window [" +
                                common::formatReal(t_min) + ", " + common::formatReal(t_max) +
                                "], found " + std::to_string(x.size()) + ".");
  const common::stats::LineFit line = common::stats::fitLine(x, y);
  PowerLawFit f;
  f.z = line.slope;
  f.z_stderr = line.slope_se;
  const double half =
      common::stats::studentHalfWidth(f.z_stderr, static_cast<double>(x.size() - 2), confidence);
  f.z_low = f.z - half;
  f.z_high = f.z + half;
  f.prefactor = std::exp(line.intercept);
  f.confidence = confidence;
  f.points = static_cast<int>(x.size());
  f.t_min = std::exp(x.front());
  f.t_max = std::exp(x.back());
  f.chi2 = line.sumsq;
  return f;
}

AsymptoticExponent asymptoticExponent(const std::vector<double>& t, const std::vector<double>& S,
                                      double p, double tolerance) {
  if (!(tolerance > 0.0)) throw std::invalid_argument("tolerance must be positive.");
  const LocalSlope ls = localSlope(t, S, p);
  if (ls.t.size() < 3)
    throw std::invalid_argument(
        "asymptotic exponent needs at least 3 local slopes; extend the time range.");
  const double t_last = ls.t.back();
  std::vector<double> x, y;
  for (std::size_t i = 0; i < ls.t.size(); ++i)
    if (ls.t[i] >= t_last / 10.0) {
      x.push_back(1.0 / ls.t[i]);
      y.push_back(ls.z[i]);
    }
  AsymptoticExponent a;
  a.tolerance = tolerance;
  a.z_last = ls.z.back();
  a.points = static_cast<int>(x.size());
  if (x.size() >= 3) {
    a.z = common::stats::fitLine(x, y).intercept;  // at 1/t -> 0
  } else {
    a.z = a.z_last;
  }
  a.correction = a.z - a.z_last;
  a.change = a.z_last - y.front();
  a.converged = std::fabs(a.correction) < tolerance && std::fabs(a.change) < tolerance;
  return a;
}

std::string AsymptoticExponent::describe() const {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "z_inf = %.5f extrapolated in 1/t from the local slope over the last decade "
                "(z(t_last) = %.5f, "
                "correction %.1e, change over the decade %.1e): %s (criterion: both below %.0e)",
                z, z_last, correction, change, converged ? "converged" : "NOT converged",
                tolerance);
  return buf;
}

}  // namespace granagg::meanfield
