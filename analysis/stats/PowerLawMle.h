#pragma once
/// \file PowerLawMle.h
/// Maximum-likelihood fit of a discrete power law p(x) = x^-tau / zeta(tau, xmin), x >= xmin,
/// with xmin chosen by the Kolmogorov-Smirnov distance (Clauset, Shalizi & Newman, SIAM Rev. 51,
/// 661 (2009), sections 3.1 and 3.3). Used for the Fisher exponent of N_s(s) ~ s^-tau; the
/// paper's "Fisher exponents" (slopes of log N_s vs log s) are -tau (docs/model.md section 11).
/// zeta(tau, xmin) is the Hurwitz zeta function (GSL gsl_sf_hzeta); the likelihood is maximised
/// with GSL's Brent minimiser.
#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

namespace granagg::analysis {

struct PowerLawMleResult {
  bool valid = false;      ///< false when the tail is too small or the likelihood has no maximum
  double tau = 0.0;        ///< MLE of the exponent (> 1)
  double tau_err = 0.0;    ///< standard error 1/sqrt(n I(tau)), I the Fisher information per sample
                           ///  (second derivative of ln zeta(tau, xmin); Clauset et al. eq. 3.6)
  std::uint64_t xmin = 0;  ///< lower bound of the power-law tail
  std::size_t n_tail = 0;  ///< samples >= xmin
  double ks = 0.0;         ///< KS distance between the tail's empirical CDF and the fitted law
};

/// MLE of tau for fixed xmin (samples below xmin are ignored). Needs at least 2 tail samples
/// with at least two distinct values; otherwise `valid` is false.
PowerLawMleResult fitDiscretePowerLaw(const std::vector<std::uint64_t>& samples,
                                      std::uint64_t xmin);

/// MLE with xmin chosen among the sample values by the smallest KS distance, considering only
/// candidates that leave at least `min_tail` samples in the tail (small tails make spuriously
/// small KS distances; Clauset et al. recommend n_tail of order 50 or more for a reliable fit).
PowerLawMleResult fitDiscretePowerLawKs(const std::vector<std::uint64_t>& samples,
                                        std::size_t min_tail = 10);

/// Same from a size histogram (value -> count), e.g. ClusterSizes::n_s: O(distinct values^2).
PowerLawMleResult fitDiscretePowerLawKs(const std::map<std::uint64_t, std::uint64_t>& counts,
                                        std::size_t min_tail = 10);

/// P(X >= x) of the discrete power law: zeta(tau, x) / zeta(tau, xmin).
double discretePowerLawCcdf(double tau, std::uint64_t xmin, std::uint64_t x);

}  // namespace granagg::analysis
