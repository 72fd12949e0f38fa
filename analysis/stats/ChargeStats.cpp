#include "analysis/stats/ChargeStats.h"

#include <algorithm>
#include <cmath>

namespace granagg::analysis {

ChargeMoments chargeMoments(const std::vector<double>& q) {
  ChargeMoments m;
  if (q.empty()) return m;
  double sa = 0, s2 = 0;
  for (double x : q) {
    sa += std::fabs(x);
    s2 += x * x;
    m.net += x;
    m.max_abs = std::max(m.max_abs, std::fabs(x));
  }
  m.mean_abs = sa / static_cast<double>(q.size());
  m.rms = std::sqrt(s2 / static_cast<double>(q.size()));
  return m;
}

std::vector<double> scaledCharges(const std::vector<double>& q) {
  const double rms = chargeMoments(q).rms;
  std::vector<double> out(q.size(), 0.0);
  if (rms > 0)
    for (std::size_t i = 0; i < q.size(); ++i) out[i] = q[i] / rms;
  return out;
}

double pearson(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = std::min(x.size(), y.size());
  if (n < 2) return std::nan("");
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  double sxx = 0, syy = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : std::nan("");
}

std::pair<std::vector<double>, std::vector<double>> chargingRate(const std::vector<double>& t,
                                                                 const std::vector<double>& m) {
  std::vector<double> tm, r;
  for (std::size_t k = 0; k + 1 < std::min(t.size(), m.size()); ++k) {
    const double dt = t[k + 1] - t[k];
    if (!(dt > 0)) continue;
    tm.push_back(t[k] > 0 ? std::sqrt(t[k] * t[k + 1]) : 0.5 * (t[k] + t[k + 1]));
    r.push_back((m[k + 1] - m[k]) / dt);
  }
  return {tm, r};
}

}  // namespace granagg::analysis
