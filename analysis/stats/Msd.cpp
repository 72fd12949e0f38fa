#include "analysis/stats/Msd.h"

#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

#include <fftw3.h>

namespace granagg::analysis {

void MsdFromOrigin::accumulate(const Frame& f) {
  if (!f.hasImages())
    throw std::invalid_argument("MSD needs image counts (or unwrapped positions); frame " +
                                std::to_string(f.index) + " has none");
  const std::size_t n = f.size();
  if (m_t.empty()) {
    m_origin.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) m_origin[3 * i + d] = f.unwrapped(i, d);
  } else if (3 * n != m_origin.size()) {
    throw std::invalid_argument("MSD: frame " + std::to_string(f.index) + " has " +
                                std::to_string(n) + " particles, the origin had " +
                                std::to_string(m_origin.size() / 3));
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      const double dx = f.unwrapped(i, d) - m_origin[3 * i + d];
      sum += dx * dx;
    }
  m_t.push_back(f.time);
  m_msd.push_back(n ? sum / static_cast<double>(n) : 0.0);
}

void MsdFromOrigin::reset() {
  m_origin.clear();
  m_t.clear();
  m_msd.clear();
}

void MsdFromOrigin::restore(State s) {
  if (s.t.size() != s.msd.size() || s.origin.size() % 3 != 0)
    throw std::invalid_argument("MsdFromOrigin::restore: inconsistent state");
  m_origin = std::move(s.origin);
  m_t = std::move(s.t);
  m_msd = std::move(s.msd);
}

void MsdAllOrigins::restore(State s) {
  if (s.xyz.size() != 3 * s.n * s.frames && s.available)
    throw std::invalid_argument("MsdAllOrigins::restore: inconsistent state");
  m_n = s.n;
  m_frames = s.frames;
  m_available = s.available;
  m_reason = std::move(s.reason);
  m_t0 = s.t0;
  m_dt = s.dt;
  m_xyz = std::move(s.xyz);
}

MsdAllOrigins::MsdAllOrigins(std::size_t max_bytes) : m_max_bytes(max_bytes) {}

void MsdAllOrigins::giveUp(const std::string& why) {
  m_available = false;
  m_reason = why;
  std::vector<double>().swap(m_xyz);
}

void MsdAllOrigins::accumulate(const Frame& f) {
  if (!m_available) return;
  if (!f.hasImages()) return giveUp("the trajectory has no image counts");
  if (m_frames == 0) {
    m_n = f.size();
    m_t0 = f.time;
  } else {
    if (f.size() != m_n) return giveUp("the particle count changes");
    const double dt = f.time - m_t0 - m_dt * static_cast<double>(m_frames - 1);
    if (m_frames == 1) {
      m_dt = f.time - m_t0;
      if (!(m_dt > 0)) return giveUp("frame times do not increase");
    } else if (std::fabs(dt - m_dt) > 1e-6 * m_dt) {
      return giveUp("frames are not evenly spaced in time (frame " + std::to_string(f.index) + ")");
    }
  }
  if ((m_xyz.size() + 3 * m_n) * sizeof(double) > m_max_bytes)
    return giveUp("storing every frame would exceed the memory budget (--msd-max-memory)");
  for (std::size_t i = 0; i < m_n; ++i)
    for (int d = 0; d < 3; ++d) m_xyz.push_back(f.unwrapped(i, d));
  ++m_frames;
}

std::vector<double> MsdAllOrigins::compute(std::vector<double>& lag) const {
  if (!available())
    throw std::logic_error("MsdAllOrigins::compute: unavailable (" + m_reason + ")");
  const std::size_t F = m_frames, N = m_n, P = 2 * F;  // zero padding to 2F: no circular wrap
  lag.resize(F);
  for (std::size_t m = 0; m < F; ++m) lag[m] = m_dt * static_cast<double>(m);
  std::vector<double> total(F, 0.0);
  std::vector<double> in(P);
  std::vector<std::complex<double>> spec(P / 2 + 1);
  std::vector<double> ac(P), D(F);
  // FFTW planning is not thread-safe and this loop is cheap next to the frame loop: one thread.
  fftw_plan fwd = fftw_plan_dft_r2c_1d(static_cast<int>(P), in.data(),
                                       reinterpret_cast<fftw_complex*>(spec.data()), FFTW_ESTIMATE);
  fftw_plan bwd = fftw_plan_dft_c2r_1d(
      static_cast<int>(P), reinterpret_cast<fftw_complex*>(spec.data()), ac.data(), FFTW_ESTIMATE);
  for (std::size_t i = 0; i < N; ++i) {
    std::fill(D.begin(), D.end(), 0.0);
    std::vector<double> s2(F, 0.0);
    for (int d = 0; d < 3; ++d) {
      for (std::size_t k = 0; k < F; ++k) {
        // relative to frame 0: the MSD is shift invariant and S1 - 2 S2 cancels less
        const double x = m_xyz[(k * N + i) * 3 + d] - m_xyz[i * 3 + d];
        in[k] = x;
        D[k] += x * x;
      }
      std::fill(in.begin() + static_cast<long>(F), in.end(), 0.0);
      fftw_execute(fwd);
      for (auto& c : spec) c = std::norm(c);
      fftw_execute(bwd);  // unnormalised: divide by P
      for (std::size_t m = 0; m < F; ++m)
        s2[m] += ac[m] / static_cast<double>(P) / static_cast<double>(F - m);
    }
    // S1(m) = (1/(F-m)) sum_{k=0}^{F-1-m} [D(k) + D(k+m)], by the recursion Q(m) = Q(m-1) - D(m-1)
    // - D(F-m).
    double Q = 0;
    for (double v : D) Q += 2 * v;
    for (std::size_t m = 0; m < F; ++m) {
      if (m > 0) Q -= D[m - 1] + D[F - m];
      total[m] += Q / static_cast<double>(F - m) - 2 * s2[m];
    }
  }
  fftw_destroy_plan(fwd);
  fftw_destroy_plan(bwd);
  for (double& v : total) v /= static_cast<double>(N);
  return total;
}

void MsdAllOrigins::reset() {
  m_n = m_frames = 0;
  m_available = true;
  m_reason.clear();
  std::vector<double>().swap(m_xyz);
}

std::vector<double> msdAllOriginsDirect(const std::vector<std::vector<double>>& x) {
  const std::size_t F = x.size();
  std::vector<double> out(F, 0.0);
  for (std::size_t m = 0; m < F; ++m) {
    double s = 0;
    for (std::size_t k = 0; k + m < F; ++k)
      for (int d = 0; d < 3; ++d) s += (x[k + m][d] - x[k][d]) * (x[k + m][d] - x[k][d]);
    out[m] = s / static_cast<double>(F - m);
  }
  return out;
}

}  // namespace granagg::analysis
