#include "md/coulomb/Ewald.h"

#include <cmath>
#include <complex>
#include <sstream>
#include <stdexcept>

#include "md/coulomb/RealSpace.h"

namespace granagg::md {

namespace {
constexpr double PI = 3.14159265358979323846;

/// Minimum image of a separation component into [-L/2, L/2].
double minimumImage(double d, double L) { return d - L * std::nearbyint(d / L); }
}  // namespace

EwaldReference::EwaldReference(const EwaldParams& params, double L, double K)
    : m_params(params), m_L(L), m_K(K) {
  std::ostringstream msg;
  if (!(L > 0.0) || !std::isfinite(L))
    msg << "EwaldReference requires a positive box length L (got " << L << ").";
  else if (!(K >= 0.0) || !std::isfinite(K))
    msg << "EwaldReference requires a coupling K >= 0 (got " << K << ").";
  else if (!(params.alpha > 0.0))
    msg << "EwaldReference requires alpha > 0 (got " << params.alpha << ").";
  else if (!(params.r_cut > 0.0))
    msg << "EwaldReference requires r_cut > 0 (got " << params.r_cut << ").";
  else if (params.k_max < 1)
    msg << "EwaldReference requires k_max >= 1 (got " << params.k_max << ").";
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
}

double EwaldReference::selfEnergy(double alpha, double K, double sum_q2) {
  return -K * alpha / std::sqrt(PI) * sum_q2;
}

double EwaldReference::backgroundEnergy(double alpha, double K, double L, double q_total) {
  return -K * PI * q_total * q_total / (2.0 * alpha * alpha * L * L * L);
}

double EwaldReference::realSpace(const double* x, const double* y, const double* z, const double* q,
                                 std::size_t n, double L, double K, double alpha, double r_cut,
                                 double* fx, double* fy, double* fz) {
  // images n L with |d0 + n L| < r_cut for a minimum-image d0 in [-L/2, L/2] need |n| < r_cut/L +
  // 1/2
  const int s = static_cast<int>(std::ceil(r_cut / L - 0.5));
  const double rc2 = r_cut * r_cut;
  std::vector<double> e(n, 0.0);
  const long N = static_cast<long>(n);
#pragma omp parallel for schedule(dynamic, 16)
  for (long i = 0; i < N; ++i) {
    double f0 = 0.0, f1 = 0.0, f2 = 0.0, ei = 0.0;
    for (long j = 0; j < N; ++j) {
      if (j == i && s == 0) continue;
      const double dx0 = minimumImage(x[i] - x[j], L), dy0 = minimumImage(y[i] - y[j], L),
                   dz0 = minimumImage(z[i] - z[j], L);
      const double qq = q[i] * q[j];
      for (int a = -s; a <= s; ++a)
        for (int b = -s; b <= s; ++b)
          for (int c = -s; c <= s; ++c) {
            if (j == i && a == 0 && b == 0 && c == 0) continue;
            const double dx = dx0 + a * L, dy = dy0 + b * L, dz = dz0 + c * L;
            const double r2 = dx * dx + dy * dy + dz * dz;
            if (r2 >= rc2) continue;
            const double r = std::sqrt(r2);
            const double fr = ewaldRealForceOverR(qq, r, alpha, K);
            f0 += fr * dx;
            f1 += fr * dy;
            f2 += fr * dz;
            ei += 0.5 *
                  ewaldRealEnergy(qq, r, alpha, K);  // each pair (and image) seen from both ends
          }
    }
    fx[i] += f0;
    fy[i] += f1;
    fz[i] += f2;
    e[i] = ei;
  }
  double energy = 0.0;
  for (double v : e) energy += v;  // fixed order: independent of the thread count
  return energy;
}

CoulombResult EwaldReference::compute(const std::vector<double>& x, const std::vector<double>& y,
                                      const std::vector<double>& z,
                                      const std::vector<double>& q) const {
  const std::size_t n = x.size();
  if (y.size() != n || z.size() != n || q.size() != n)
    throw std::invalid_argument("EwaldReference::compute requires x, y, z and q of equal length.");
  const double alpha = m_params.alpha, L = m_L, K = m_K;
  const double V = L * L * L;
  CoulombResult res;
  res.fx.assign(n, 0.0);
  res.fy.assign(n, 0.0);
  res.fz.assign(n, 0.0);
  res.energy_real = realSpace(x.data(), y.data(), z.data(), q.data(), n, L, K, alpha,
                              m_params.r_cut, res.fx.data(), res.fy.data(), res.fz.data());

  double sum_q = 0.0, sum_q2 = 0.0;
  for (double v : q) {
    sum_q += v;
    sum_q2 += v * v;
  }
  res.energy_self = selfEnergy(alpha, K, sum_q2);
  res.energy_background = backgroundEnergy(alpha, K, L, sum_q);

  // Reciprocal space. Tables exp(i 2 pi m x / L) for m = 0..k_max per particle and dimension; the
  // k vectors n with |n| <= k_max are taken in a half space (k and -k give equal contributions).
  const int km = m_params.k_max;
  const int W = km + 1;
  using C = std::complex<double>;
  std::vector<C> ex(n * W), ey(n * W), ez(n * W);
  for (std::size_t i = 0; i < n; ++i) {
    const double t[3] = {2.0 * PI * x[i] / L, 2.0 * PI * y[i] / L, 2.0 * PI * z[i] / L};
    C* tab[3] = {&ex[i * W], &ey[i * W], &ez[i * W]};
    for (int d = 0; d < 3; ++d)
      for (int m = 0; m < W; ++m)
        tab[d][m] = std::polar(1.0, m * t[d]);  // direct, no recursion drift
  }
  struct KVec {
    int a, b, c;
    double weight;  // 2 (4 pi / k^2) exp(-k^2 / 4 alpha^2): the factor 2 for the -k partner
  };
  std::vector<KVec> ks;
  const double unit = 2.0 * PI / L;
  for (int a = 0; a <= km; ++a)
    for (int b = -km; b <= km; ++b)
      for (int c = -km; c <= km; ++c) {
        if (a * a + b * b + c * c > km * km) continue;
        const bool upper = a > 0 || (a == 0 && (b > 0 || (b == 0 && c > 0)));
        if (!upper) continue;
        const double k2 = unit * unit * (a * a + b * b + c * c);
        ks.push_back({a, b, c, 2.0 * 4.0 * PI / k2 * std::exp(-k2 / (4.0 * alpha * alpha))});
      }
  auto eikr = [&](std::size_t i, const KVec& k) {
    const C cy = k.b >= 0 ? ey[i * W + k.b] : std::conj(ey[i * W - k.b]);
    const C cz = k.c >= 0 ? ez[i * W + k.c] : std::conj(ez[i * W - k.c]);
    return ex[i * W + k.a] * cy * cz;
  };
  const long NK = static_cast<long>(ks.size());
  std::vector<C> S(ks.size());
#pragma omp parallel for schedule(static)
  for (long m = 0; m < NK; ++m) {
    C s = 0.0;
    for (std::size_t j = 0; j < n; ++j) s += q[j] * eikr(j, ks[m]);
    S[m] = s;
  }
  double e_k = 0.0;
  for (long m = 0; m < NK; ++m) e_k += ks[m].weight * std::norm(S[m]);
  res.energy_kspace = K / (2.0 * V) * e_k;
  // F_i = (K q_i / V) sum_{all k} (4 pi / k^2) exp(-k^2/4alpha^2) k Im(exp(i k.r_i) conj S(k))
  const long N = static_cast<long>(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < N; ++i) {
    double f0 = 0.0, f1 = 0.0, f2 = 0.0;
    for (long m = 0; m < NK; ++m) {
      const double im = std::imag(eikr(i, ks[m]) * std::conj(S[m])) * ks[m].weight;
      f0 += im * ks[m].a;
      f1 += im * ks[m].b;
      f2 += im * ks[m].c;
    }
    const double pre = K * q[i] / V * unit;
    res.fx[i] += pre * f0;
    res.fy[i] += pre * f1;
    res.fz[i] += pre * f2;
  }
  res.energy = res.energy_real + res.energy_kspace + res.energy_self + res.energy_background;
  return res;
}

}  // namespace granagg::md
