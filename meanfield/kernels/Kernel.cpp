#include "meanfield/kernels/Kernel.h"

#include <cmath>
#include <stdexcept>

#include "common/Csv.h"

namespace granagg::meanfield {

Kernel::Kernel(KernelType type, double K0, double beta, double e, std::vector<Term> terms)
    : m_type(type), m_K0(K0), m_beta(beta), m_sum_exponent(e), m_terms(std::move(terms)) {
  if (!(K0 > 0.0) || !std::isfinite(K0))
    throw std::invalid_argument("kernel prefactor K0 must be positive and finite (got " +
                                common::formatReal(K0) + ").");
}

Kernel Kernel::constant(double K0) {
  return Kernel(KernelType::Constant, K0, 0.0, 0.0, {{1.0, 0.0, 0.0}});
}

Kernel Kernel::additive(double K0) {
  return Kernel(KernelType::Additive, K0, 0.0, 0.0, {{1.0, 1.0, 0.0}, {1.0, 0.0, 1.0}});
}

Kernel Kernel::multiplicative(double K0) {
  return Kernel(KernelType::Multiplicative, K0, 0.0, 0.0, {{1.0, 1.0, 1.0}});
}

Kernel Kernel::beta(double beta, double K0) {
  if (!(beta > 0.0) || !std::isfinite(beta))
    throw std::invalid_argument("--beta must be a positive finite number (got " +
                                common::formatReal(beta) + ").");
  const double b = 1.0 / beta;
  // (i^{1/3} + j^{1/3})^2 (ij)^{-1/beta} expanded into three separable terms
  return Kernel(
      KernelType::Beta, K0, beta, b,
      {{1.0, 2.0 / 3.0 - b, -b}, {2.0, 1.0 / 3.0 - b, 1.0 / 3.0 - b}, {1.0, -b, 2.0 / 3.0 - b}});
}

Kernel Kernel::fromName(const std::string& name, double beta_value, double K0) {
  if (name == "constant") return constant(K0);
  if (name == "additive") return additive(K0);
  if (name == "multiplicative") return multiplicative(K0);
  if (name == "beta") return beta(beta_value, K0);
  throw std::invalid_argument("unknown kernel '" + name +
                              "' (allowed: beta, constant, additive, multiplicative).");
}

double Kernel::operator()(double i, double j) const {
  switch (m_type) {
    case KernelType::Constant:
      return m_K0;
    case KernelType::Additive:
      return m_K0 * (i + j);
    case KernelType::Multiplicative:
      return m_K0 * i * j;
    case KernelType::Beta: {
      const double s = std::cbrt(i) + std::cbrt(j);
      return m_K0 * s * s * std::pow(1.0 / i + 1.0 / j, 1.0 / m_beta);
    }
  }
  return 0.0;
}

double Kernel::homogeneity() const {
  switch (m_type) {
    case KernelType::Constant:
      return 0.0;
    case KernelType::Additive:
      return 1.0;
    case KernelType::Multiplicative:
      return 2.0;
    case KernelType::Beta:
      return 2.0 / 3.0 - 1.0 / m_beta;
  }
  return 0.0;
}

double Kernel::scalingExponent() const {
  const double lambda = homogeneity();
  if (lambda >= 1.0)
    throw std::domain_error(
        "kernel '" + name() +
        "' has homogeneity >= 1: no power-law growth (gelation or exponential growth)");
  return 1.0 / (1.0 - lambda);
}

std::string Kernel::name() const {
  switch (m_type) {
    case KernelType::Constant:
      return "constant";
    case KernelType::Additive:
      return "additive";
    case KernelType::Multiplicative:
      return "multiplicative";
    case KernelType::Beta:
      return "beta";
  }
  return "?";
}

}  // namespace granagg::meanfield
