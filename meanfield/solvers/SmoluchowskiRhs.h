#pragma once
/// \file SmoluchowskiRhs.h
/// Right-hand side of the discrete Smoluchowski equation for sizes k = 1..M:
///
///     dn_k/dt = 1/2 sum_{i+j=k} K(i,j) n_i n_j  -  n_k sum_{j=1}^{M} K(k,j) n_j
///
/// (truncated at M: aggregates larger than M leave the system, which shows up as lost mass).
///
/// Evaluated exactly in O(M log M) with FFTW for every kernel of the separable form
/// K(i,j) = K0 (i+j)^e sum_t w_t i^{p_t} j^{q_t} (Kernel.h): with x^{(p)}_i = i^p n_i,
///   gain_k = K0/2 k^e sum_t w_t (x^{(p_t)} * x^{(q_t)})_k               (convolutions)
///   loss_k = K0 n_k sum_t w_t k^{p_t} sum_j (k+j)^e x^{(q_t)}_j          (correlations)
/// A correlation with g(m) = m^e is conj(X) G in Fourier space (real x), so one forward transform
/// per distinct exponent and one inverse for the gain plus one per distinct q suffice (beta
/// kernel: 3 forward + 4 inverse real transforms of length L >= 2M+1). No kernel approximation;
/// the only error is FFT round-off, about 1e-16 max_k(n_k) in every component (docs/model.md
/// section 12), which sets a floor for absolute tolerances. For e = 0 the correlation is a plain
/// sum and needs no transform.
#include <memory>
#include <vector>

#include "meanfield/kernels/Kernel.h"

namespace granagg::meanfield {

class SmoluchowskiRhs {
 public:
  enum class Method { Auto, Fft, Direct };
  /// \param M largest size class (M >= 2); \param method Auto uses the direct O(M^2) sum for
  /// M <= 64 and FFTs above.
  SmoluchowskiRhs(const Kernel& kernel, int M, Method method = Method::Auto);
  ~SmoluchowskiRhs();
  SmoluchowskiRhs(const SmoluchowskiRhs&) = delete;
  SmoluchowskiRhs& operator=(const SmoluchowskiRhs&) = delete;

  /// dn/dt for n (n[k-1] = n_k, k = 1..M).
  void evaluate(const double* n, double* dndt);
  /// Diagonal of the Jacobian, d(dn_k/dt)/dn_k = -(sum_j K(k,j) n_j + K(k,k) n_k): the gain term
  /// has no n_k (i, j < k). Used to precondition BDF's Krylov solver; costs one evaluate().
  void jacobianDiagonal(const double* n, double* jdiag);
  /// The O(M^2) double sum with Kernel::operator(), the reference for tests.
  void evaluateDirect(const double* n, double* dndt) const;

  int size() const { return m_M; }
  bool usesFft() const { return m_use_fft; }
  /// FFT length L (0 when the direct sum is used).
  int fftLength() const;

 private:
  struct FftState;
  const Kernel m_kernel;
  int m_M;
  bool m_use_fft;
  std::unique_ptr<FftState> m_fft;
  std::vector<double> m_rate;  // sum_j K(k,j) n_j of the last evaluation (loss rate per cluster)
  std::vector<double> m_scratch;
};

/// Smallest n >= target whose prime factors are all in {2, 3, 5, 7} (fast FFTW sizes).
int fftFriendlySize(int target);

}  // namespace granagg::meanfield
