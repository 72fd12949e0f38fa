#pragma once
/// \file Kernel.h
/// Aggregation kernels K(i,j) for the Smoluchowski equation (docs/model.md section 12).
///
/// Sizes i, j are in units of the monomer (particle) mass; K0 sets the time unit of the mean-field
/// solution (t is measured in 1 / (K0 n_1(0)) for a monodisperse start with n_1(0) = 1).
///
/// Every kernel here has the separable form used by the O(M log M) right-hand side:
///
///     K(i,j) = K0 * (i+j)^e * sum_t w_t * i^{p_t} * j^{q_t}
///
/// - beta kernel (Singh & Mazza 2018, eq. kernel_beta with its typo corrected, docs/model.md
/// section 9):
///     K = K0 (i^{1/3} + j^{1/3})^2 (1/i + 1/j)^{1/beta}
///       = K0 (i+j)^{1/beta} [ i^{2/3} + 2 i^{1/3} j^{1/3} + j^{2/3} ] (ij)^{-1/beta}
///   homogeneity lambda = 2/3 - 1/beta;
/// - constant K0 (lambda = 0), additive K0 (i+j) (lambda = 1), multiplicative K0 i j (lambda = 2,
///   gels at t = 1/K0 from a monodisperse start).
#include <string>
#include <vector>

namespace granagg::meanfield {

enum class KernelType { Constant, Additive, Multiplicative, Beta };

class Kernel {
 public:
  /// One separable term w * i^p * j^q.
  struct Term {
    double weight;
    double p;
    double q;
  };

  static Kernel constant(double K0 = 1.0);
  static Kernel additive(double K0 = 1.0);
  static Kernel multiplicative(double K0 = 1.0);
  /// The beta kernel; beta > 0 (beta = 2: ballistic neutral aggregation, Singh & Mazza 2018).
  static Kernel beta(double beta, double K0 = 1.0);
  /// By name ("constant", "additive", "multiplicative", "beta"); throws std::invalid_argument
  /// naming the allowed names.
  static Kernel fromName(const std::string& name, double beta = 2.0, double K0 = 1.0);

  /// K(i, j) for real sizes i, j > 0 (sectional pivots are not integers).
  double operator()(double i, double j) const;
  /// Homogeneity lambda: K(a i, a j) = a^lambda K(i, j).
  double homogeneity() const;
  /// Growth exponent of the mean size predicted by scaling, z = 1 / (1 - lambda), for lambda < 1.
  /// For the beta kernel z = 3 beta / (beta + 3) (docs/model.md section 12).
  double scalingExponent() const;
  /// True for kernels with lambda > 1, whose solutions gel in finite time.
  bool gels() const { return homogeneity() > 1.0; }

  KernelType type() const { return m_type; }
  std::string name() const;
  double betaValue() const { return m_beta; }
  double K0() const { return m_K0; }
  /// Exponent e of the (i+j)^e factor of the separable form.
  double sumExponent() const { return m_sum_exponent; }
  const std::vector<Term>& terms() const { return m_terms; }

 private:
  Kernel(KernelType type, double K0, double beta, double e, std::vector<Term> terms);
  KernelType m_type;
  double m_K0;
  double m_beta;  // only meaningful for KernelType::Beta
  double m_sum_exponent;
  std::vector<Term> m_terms;
};

}  // namespace granagg::meanfield
