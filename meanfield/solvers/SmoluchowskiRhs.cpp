#include "meanfield/solvers/SmoluchowskiRhs.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

#include <fftw3.h>
#include <omp.h>

namespace granagg::meanfield {

int fftFriendlySize(int target) {
  if (target < 1) return 1;
  for (int n = target;; ++n) {
    int m = n;
    for (int p : {2, 3, 5, 7})
      while (m % p == 0) m /= p;
    if (m == 1) return n;
  }
}

namespace {
struct FftwFree {
  void operator()(void* p) const { fftw_free(p); }
};
using RealBuf = std::unique_ptr<double[], FftwFree>;
using CplxBuf = std::unique_ptr<fftw_complex[], FftwFree>;
RealBuf allocReal(int n) { return RealBuf(fftw_alloc_real(n)); }
CplxBuf allocCplx(int n) { return CplxBuf(fftw_alloc_complex(n)); }

// index of value v in a list of distinct exponents (adds it if new)
int exponentIndex(std::vector<double>& list, double v) {
  for (std::size_t i = 0; i < list.size(); ++i)
    if (list[i] == v) return static_cast<int>(i);
  list.push_back(v);
  return static_cast<int>(list.size() - 1);
}
}  // namespace

struct SmoluchowskiRhs::FftState {
  int L = 0;                            // transform length
  int Lc = 0;                           // complex length L/2+1
  std::vector<double> exponents;        // distinct exponents among p_t, q_t
  std::vector<std::vector<double>> pw;  // pw[e][k-1] = k^{exponents[e]}
  struct TermIdx {
    double w;
    int p;
    int q;
    int iq;  // index into distinct_q (correlation buffer)
  };
  std::vector<TermIdx> terms;
  std::vector<int> distinct_q;  // exponent indices used as q (one correlation each)
  std::vector<double> sum_pow;  // k^e for the gain prefactor, k = 1..M
  bool plain_sum = false;       // e == 0: correlations are plain sums
  RealBuf work_real;
  std::vector<CplxBuf> spectra;  // forward transforms of x^{(e)}
  CplxBuf gain_spec, work_spec;
  CplxBuf phi_spec;           // transform of g(m) = m^e, m = 2..2M
  std::vector<RealBuf> corr;  // correlation results per distinct q
  RealBuf conv;               // gain convolution result
  fftw_plan fwd = nullptr, inv = nullptr;
  ~FftState() {
    if (fwd) fftw_destroy_plan(fwd);
    if (inv) fftw_destroy_plan(inv);
  }
};

SmoluchowskiRhs::SmoluchowskiRhs(const Kernel& kernel, int M, Method method)
    : m_kernel(kernel), m_M(M) {
  if (M < 2)
    throw std::invalid_argument("the largest size class M must be at least 2 (got " +
                                std::to_string(M) + ").");
  m_use_fft = method == Method::Fft || (method == Method::Auto && M > 64);
  if (!m_use_fft) return;

  auto st = std::make_unique<FftState>();
  const double e = kernel.sumExponent();
  st->plain_sum = (e == 0.0);
  // Linear convolution of sequences on 1..M needs L >= 2M; the correlation sum_j g(k+j) y_j
  // reaches k + j = 2M and must not wrap: L >= 2M + 1.
  st->L = fftFriendlySize(2 * M + 1);
  st->Lc = st->L / 2 + 1;
  for (const auto& t : kernel.terms()) {
    FftState::TermIdx ti{t.weight, exponentIndex(st->exponents, t.p),
                         exponentIndex(st->exponents, t.q), 0};
    auto it = std::find(st->distinct_q.begin(), st->distinct_q.end(), ti.q);
    ti.iq = static_cast<int>(it - st->distinct_q.begin());
    if (it == st->distinct_q.end()) st->distinct_q.push_back(ti.q);
    st->terms.push_back(ti);
  }
  st->pw.resize(st->exponents.size());
  for (std::size_t x = 0; x < st->exponents.size(); ++x) {
    st->pw[x].resize(M);
    for (int k = 1; k <= M; ++k) st->pw[x][k - 1] = std::pow(double(k), st->exponents[x]);
  }
  st->sum_pow.resize(M);
  for (int k = 1; k <= M; ++k) st->sum_pow[k - 1] = std::pow(double(k), e);

  const int L = st->L, Lc = st->Lc;
  st->work_real = allocReal(L);
  st->conv = allocReal(L);
  st->gain_spec = allocCplx(Lc);
  st->work_spec = allocCplx(Lc);
  for (std::size_t x = 0; x < st->exponents.size(); ++x) st->spectra.push_back(allocCplx(Lc));
  if (!st->plain_sum)
    for (std::size_t q = 0; q < st->distinct_q.size(); ++q) st->corr.push_back(allocReal(L));
  // FFTW_ESTIMATE: planning is instant; the solver re-plans whenever the active range grows.
  // Threads (fftw3_omp) pay off only for long transforms.
  {
    static const bool threads_ok = fftw_init_threads() != 0;  // once per process
    const int nthreads = (threads_ok && L >= (1 << 15)) ? omp_get_max_threads() : 1;
    if (threads_ok) fftw_plan_with_nthreads(nthreads);
  }
  st->fwd = fftw_plan_dft_r2c_1d(L, st->work_real.get(), st->work_spec.get(), FFTW_ESTIMATE);
  st->inv = fftw_plan_dft_c2r_1d(L, st->work_spec.get(), st->conv.get(), FFTW_ESTIMATE);
  if (!st->fwd || !st->inv)
    throw std::runtime_error("FFTW could not create a plan of length " + std::to_string(L));

  if (!st->plain_sum) {
    st->phi_spec = allocCplx(Lc);
    double* g = st->work_real.get();
    std::fill(g, g + L, 0.0);
    for (int m = 2; m <= 2 * M; ++m) g[m] = std::pow(double(m), e);
    fftw_execute_dft_r2c(st->fwd, g, st->phi_spec.get());
  }
  m_fft = std::move(st);
}

SmoluchowskiRhs::~SmoluchowskiRhs() = default;

int SmoluchowskiRhs::fftLength() const { return m_fft ? m_fft->L : 0; }

void SmoluchowskiRhs::evaluate(const double* n, double* dndt) {
  m_rate.resize(m_M);
  if (!m_use_fft) {
    evaluateDirect(n, dndt);
    for (int k = 1; k <= m_M; ++k) {
      double rate = 0.0;
      for (int j = 1; j <= m_M; ++j) rate += m_kernel(k, j) * n[j - 1];
      m_rate[k - 1] = rate;
    }
    return;
  }
  FftState& st = *m_fft;
  const int M = m_M, L = st.L, Lc = st.Lc;
  const double K0 = m_kernel.K0();
  const double inv_L = 1.0 / L;
  double* x = st.work_real.get();

  // forward transforms of x^{(e)}_k = k^e n_k (index k, zero elsewhere)
  std::vector<double> sums(st.exponents.size(), 0.0);
  for (std::size_t ex = 0; ex < st.exponents.size(); ++ex) {
    const double* p = st.pw[ex].data();
    x[0] = 0.0;
    double s = 0.0;
    for (int k = 1; k <= M; ++k) {
      x[k] = p[k - 1] * n[k - 1];
      s += x[k];
    }
    std::fill(x + M + 1, x + L, 0.0);
    sums[ex] = s;
    fftw_execute_dft_r2c(st.fwd, x, st.spectra[ex].get());
  }

  // gain: one inverse transform of sum_t w_t X_p X_q
  {
    auto* g = reinterpret_cast<std::complex<double>*>(st.work_spec.get());
    std::fill(g, g + Lc, std::complex<double>(0.0));
    for (const auto& t : st.terms) {
      const auto* a = reinterpret_cast<const std::complex<double>*>(st.spectra[t.p].get());
      const auto* b = reinterpret_cast<const std::complex<double>*>(st.spectra[t.q].get());
#pragma omp parallel for schedule(static) if (Lc > (1 << 15))
      for (int f = 0; f < Lc; ++f) g[f] += t.w * a[f] * b[f];
    }
    fftw_execute_dft_c2r(st.inv, st.work_spec.get(), st.conv.get());
  }
  // correlations c_q(k) = sum_j (k+j)^e x^{(q)}_j = IDFT[ G * conj(X_q) ](k)
  if (!st.plain_sum) {
    const auto* G = reinterpret_cast<const std::complex<double>*>(st.phi_spec.get());
    for (std::size_t iq = 0; iq < st.distinct_q.size(); ++iq) {
      const auto* X =
          reinterpret_cast<const std::complex<double>*>(st.spectra[st.distinct_q[iq]].get());
      auto* w = reinterpret_cast<std::complex<double>*>(st.work_spec.get());
#pragma omp parallel for schedule(static) if (Lc > (1 << 15))
      for (int f = 0; f < Lc; ++f) w[f] = G[f] * std::conj(X[f]);
      fftw_execute_dft_c2r(st.inv, st.work_spec.get(), st.corr[iq].get());
    }
  }

  const double* conv = st.conv.get();
#pragma omp parallel for schedule(static) if (M > (1 << 14))
  for (int k = 1; k <= M; ++k) {
    const double gain = 0.5 * K0 * st.sum_pow[k - 1] * conv[k] * inv_L;
    double rate = 0.0;  // sum_j K(k,j) n_j / K0
    for (const auto& t : st.terms) {
      const double c = st.plain_sum ? sums[t.q] : st.corr[t.iq][k] * inv_L;
      rate += t.w * st.pw[t.p][k - 1] * c;
    }
    m_rate[k - 1] = K0 * rate;
    dndt[k - 1] = gain - K0 * n[k - 1] * rate;
  }
}

void SmoluchowskiRhs::jacobianDiagonal(const double* n, double* jdiag) {
  m_scratch.resize(m_M);
  evaluate(n, m_scratch.data());  // fills m_rate
  for (int k = 1; k <= m_M; ++k) jdiag[k - 1] = -(m_rate[k - 1] + m_kernel(k, k) * n[k - 1]);
}

void SmoluchowskiRhs::evaluateDirect(const double* n, double* dndt) const {
  const int M = m_M;
  for (int k = 1; k <= M; ++k) {
    double gain = 0.0;
    for (int i = 1; i < k; ++i) gain += m_kernel(i, k - i) * n[i - 1] * n[k - i - 1];
    double rate = 0.0;
    for (int j = 1; j <= M; ++j) rate += m_kernel(k, j) * n[j - 1];
    dndt[k - 1] = 0.5 * gain - n[k - 1] * rate;
  }
}

}  // namespace granagg::meanfield
