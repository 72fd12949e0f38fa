#include "analysis/stats/VelocityStats.h"

#include <cmath>
#include <stdexcept>

#include "common/Csv.h"

namespace granagg::analysis {

namespace {
void meanVelocity(const std::vector<double>& v, double m[3]) {
  const std::size_t n = v.size() / 3;
  m[0] = m[1] = m[2] = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) m[d] += v[3 * i + d];
  for (int d = 0; d < 3; ++d) m[d] /= static_cast<double>(n);
}
}  // namespace

VelocityMoments velocityMoments(const std::vector<double>& v) {
  const std::size_t n = v.size() / 3;
  if (n < 2 || v.size() % 3 != 0)
    throw std::invalid_argument("velocityMoments needs at least 2 particles (3N values).");
  double m[3];
  meanVelocity(v, m);
  // Moments of u = c^2 and w = c^4 with their sample covariance for the delta method.
  double su = 0, sw = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double c2 = 0;
    for (int d = 0; d < 3; ++d) c2 += (v[3 * i + d] - m[d]) * (v[3 * i + d] - m[d]);
    su += c2;
    sw += c2 * c2;
  }
  const double N = static_cast<double>(n), mu = su / N, mw = sw / N;
  double vuu = 0, vww = 0, vuw = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double c2 = 0;
    for (int d = 0; d < 3; ++d) c2 += (v[3 * i + d] - m[d]) * (v[3 * i + d] - m[d]);
    const double du = c2 - mu, dw = c2 * c2 - mw;
    vuu += du * du;
    vww += dw * dw;
    vuw += du * dw;
  }
  vuu /= N - 1;
  vww /= N - 1;
  vuw /= N - 1;
  VelocityMoments r;
  r.n = n;
  r.T_g = mu / 3.0;
  r.a2 = 0.6 * mw / (mu * mu) - 1.0;
  // a2 = g(mu, mw) = 0.6 mw / mu^2 - 1; Var(a2) ~ grad g^T Cov(mean u, mean w) grad g with
  // Cov(mean) = Cov/N. For a Maxwellian this gives ~ sqrt(2/(3 N)) x O(1): 2.6e-3 at N = 1e5.
  const double gu = -1.2 * mw / (mu * mu * mu), gw = 0.6 / (mu * mu);
  const double var = (gu * gu * vuu + gw * gw * vww + 2 * gu * gw * vuw) / N;
  r.a2_err = var > 0 ? std::sqrt(var) : 0.0;
  return r;
}

double maxwellianScaledSpeedDensity(double x) {
  return std::sqrt(54.0 / M_PI) * x * x * std::exp(-1.5 * x * x);
}

double maxwellianScaledSpeedCdf(double x) {
  const double a = std::sqrt(1.5);
  return std::erf(a * x) - 2.0 / std::sqrt(M_PI) * a * x * std::exp(-a * a * x * x);
}

std::vector<double> scaledSpeeds(const std::vector<double>& v) {
  const std::size_t n = v.size() / 3;
  std::vector<double> s(n);
  if (n == 0) return s;
  double m[3];
  meanVelocity(v, m);
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double c2 = 0;
    for (int d = 0; d < 3; ++d) c2 += (v[3 * i + d] - m[d]) * (v[3 * i + d] - m[d]);
    s[i] = std::sqrt(c2);
    sum += c2;
  }
  const double scale = sum > 0 ? 1.0 / std::sqrt(sum / static_cast<double>(n)) : 0.0;
  for (double& x : s) x *= scale;
  return s;
}

SpeedHistogram::SpeedHistogram(double v_max, int bins) : m_vmax(v_max) {
  if (!(v_max > 0) || !std::isfinite(v_max))
    throw std::invalid_argument("SpeedHistogram requires v_max > 0, got " +
                                common::formatReal(v_max) + ".");
  if (bins < 1)
    throw std::invalid_argument("SpeedHistogram requires at least 1 bin, got " +
                                std::to_string(bins) + ".");
  m_width = v_max / bins;
  m_counts.assign(static_cast<std::size_t>(bins), 0.0);
}

std::vector<double> SpeedHistogram::add(const std::vector<double>& v) {
  std::vector<double> s = scaledSpeeds(v);
  for (double x : s) {
    const long k = static_cast<long>(x / m_width);
    if (k >= 0 && k < static_cast<long>(m_counts.size()))
      m_counts[static_cast<std::size_t>(k)] += 1.0;
  }
  m_total += static_cast<double>(s.size());
  return s;
}

std::vector<double> SpeedHistogram::density() const {
  std::vector<double> d(m_counts.size(), std::nan(""));
  if (m_total > 0)
    for (std::size_t k = 0; k < d.size(); ++k) d[k] = m_counts[k] / (m_total * m_width);
  return d;
}

void SpeedHistogram::reset() {
  std::fill(m_counts.begin(), m_counts.end(), 0.0);
  m_total = 0;
}

}  // namespace granagg::analysis
