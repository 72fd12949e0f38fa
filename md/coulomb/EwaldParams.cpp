#include "md/coulomb/EwaldParams.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace granagg::md {

namespace {

constexpr double PI = 3.14159265358979323846;

/// Deserno & Holm (1998) II / LAMMPS pppm.cpp: coefficients a_{P,m} of the ik-differentiation
/// mesh error sum_{m<P} a_{P,m} (h alpha)^{2m}, for assignment order P = 1..7 (row P).
constexpr double ACONS[8][7] = {
    {0, 0, 0, 0, 0, 0, 0},
    {2.0 / 3.0, 0, 0, 0, 0, 0, 0},
    {1.0 / 50.0, 5.0 / 294.0, 0, 0, 0, 0, 0},
    {1.0 / 588.0, 7.0 / 1440.0, 21.0 / 3872.0, 0, 0, 0, 0},
    {1.0 / 4320.0, 3.0 / 1936.0, 7601.0 / 2271360.0, 143.0 / 28800.0, 0, 0, 0},
    {1.0 / 23232.0, 7601.0 / 13628160.0, 143.0 / 69120.0, 517231.0 / 106536960.0,
     106640677.0 / 11737571328.0, 0, 0},
    {691.0 / 68140800.0, 13.0 / 57600.0, 47021.0 / 35512320.0, 9694607.0 / 2095994880.0,
     733191589.0 / 59609088000.0, 326190917.0 / 11700633600.0, 0},
    {1.0 / 345600.0, 3617.0 / 35512320.0, 745739.0 / 838397952.0, 56399353.0 / 12773376000.0,
     25091609.0 / 1560084480.0, 1755948832039.0 / 36229939200000.0, 4887769399.0 / 37838389248.0},
};

[[noreturn]] void invalid(const std::string& what, double value) {
  std::ostringstream msg;
  msg << what << " (got " << value << ").";
  throw std::invalid_argument(msg.str());
}

void validateCommon(double accuracy, std::size_t n, double L, double sum_q2) {
  if (!(accuracy > 0.0) || !std::isfinite(accuracy))
    invalid("Coulomb accuracy must be positive and finite", accuracy);
  if (n == 0) invalid("Coulomb parameter choice needs at least one particle (n)", 0.0);
  if (!(L > 0.0) || !std::isfinite(L))
    invalid("Coulomb box length L must be positive and finite", L);
  if (!(sum_q2 > 0.0) || !std::isfinite(sum_q2))
    invalid(
        "Coulomb parameter choice needs sum_q2 = sum of squared charges > 0 (the error estimates "
        "scale with it)",
        sum_q2);
}

}  // namespace

double EwaldParams::estimatedError() const {
  return std::hypot(estimated_error_real, estimated_error_kspace);
}
double PppmParams::estimatedError() const {
  return std::hypot(estimated_error_real, estimated_error_kspace);
}

double ewaldRealSpaceError(double alpha, double r_cut, std::size_t n, double L, double sum_q2) {
  return 2.0 * sum_q2 * std::exp(-alpha * alpha * r_cut * r_cut) /
         std::sqrt(double(n) * r_cut * L * L * L);
}

double ewaldKspaceError(double alpha, int k_max, std::size_t n, double L, double sum_q2) {
  const double t = PI * k_max / (alpha * L);
  return 2.0 * sum_q2 * alpha / L * std::sqrt(1.0 / (PI * k_max * double(n))) * std::exp(-t * t);
}

double pppmKspaceError(double alpha, int mesh, int order, std::size_t n, double L, double sum_q2) {
  if (order < 1 || order > 7) invalid("PPPM order must be between 2 and 7", order);
  const double ha = L / mesh * alpha;
  double sum = 0.0;
  for (int m = 0; m < order; ++m) sum += ACONS[order][m] * std::pow(ha, 2.0 * m);
  return sum_q2 * std::pow(ha, order) *
         std::sqrt(alpha * L * std::sqrt(2.0 * PI) * sum / double(n)) / (L * L);
}

double realSpaceAlpha(double error_real, double r_cut, std::size_t n, double L, double sum_q2) {
  const double x = error_real * std::sqrt(double(n) * r_cut * L * L * L) / (2.0 * sum_q2);
  if (x >= 1.0) return (1.35 - 0.15 * std::log(error_real)) / r_cut;  // LAMMPS pppm.cpp fallback
  return std::sqrt(-std::log(x)) / r_cut;
}

int fftFriendlySize(int n_min) {
  for (int m = n_min < 1 ? 1 : n_min;; ++m) {
    int r = m;
    for (int f : {2, 3, 5})
      while (r % f == 0) r /= f;
    if (r == 1) return m;
  }
}

EwaldParams chooseEwaldParams(double accuracy, std::size_t n, double L, double sum_q2,
                              double r_cut) {
  validateCommon(accuracy, n, L, sum_q2);
  if (r_cut < 0.0 || !std::isfinite(r_cut))
    invalid("Ewald r_cut must be >= 0 (0 selects L/2)", r_cut);
  EwaldParams p;
  p.r_cut = r_cut == 0.0 ? 0.5 * L : r_cut;
  const double target = accuracy / std::sqrt(2.0);
  p.alpha = realSpaceAlpha(target, p.r_cut, n, L, sum_q2);
  p.estimated_error_real = ewaldRealSpaceError(p.alpha, p.r_cut, n, L, sum_q2);
  constexpr int K_MAX_LIMIT = 400;
  for (p.k_max = 1; p.k_max <= K_MAX_LIMIT; ++p.k_max)
    if (ewaldKspaceError(p.alpha, p.k_max, n, L, sum_q2) <= target) break;
  if (p.k_max > K_MAX_LIMIT)
    invalid("Ewald accuracy cannot be met with k_max <= 400; increase r_cut or accuracy", accuracy);
  p.estimated_error_kspace = ewaldKspaceError(p.alpha, p.k_max, n, L, sum_q2);
  return p;
}

PppmParams choosePppmParams(double accuracy, std::size_t n, double L, double sum_q2, double r_cut,
                            int order, int max_mesh) {
  validateCommon(accuracy, n, L, sum_q2);
  if (!(r_cut > 0.0) || r_cut > 0.5 * L)
    invalid("PPPM r_cut must lie in (0, L/2] (the real space uses the minimum image); L/2 = " +
                std::to_string(0.5 * L),
            r_cut);
  if (order < 2 || order > 7)
    invalid("PPPM order (charge-assignment order P) must be between 2 and 7", order);
  PppmParams p;
  p.r_cut = r_cut;
  p.order = order;
  const double target = accuracy / std::sqrt(2.0);
  p.alpha = realSpaceAlpha(target, r_cut, n, L, sum_q2);
  p.estimated_error_real = ewaldRealSpaceError(p.alpha, r_cut, n, L, sum_q2);
  // the assignment stencil (P points) must fit in the mesh without wrapping onto itself
  for (p.mesh = fftFriendlySize(order); p.mesh <= max_mesh; p.mesh = fftFriendlySize(p.mesh + 1))
    if (pppmKspaceError(p.alpha, p.mesh, order, n, L, sum_q2) <= target) break;
  if (p.mesh > max_mesh)
    invalid("PPPM accuracy cannot be met with at most " + std::to_string(max_mesh) +
                " mesh points per edge; increase r_cut, order or accuracy",
            accuracy);
  p.estimated_error_kspace = pppmKspaceError(p.alpha, p.mesh, order, n, L, sum_q2);
  return p;
}

double pppmCost(const PppmParams& p, std::size_t n, double L, const PppmCostModel& c) {
  const double N = double(n);
  const double density = N / (L * L * L);
  const double pairs = N * (4.0 * PI / 3.0) * p.r_cut * p.r_cut * p.r_cut * density;
  const double M3 = double(p.mesh) * p.mesh * p.mesh;
  const double P3 = double(p.order) * p.order * p.order;
  return c.pair * pairs + c.fft_point * 4.0 * M3 * std::log2(M3) + c.stencil * 2.0 * N * P3 +
         c.particle * N + c.mesh_point * M3;
}

PppmParams optimizePppmParams(double accuracy, std::size_t n, double L, double sum_q2,
                              double r_cut_min, double r_cut_max, const PppmCostModel& model) {
  validateCommon(accuracy, n, L, sum_q2);
  if (r_cut_max == 0.0) r_cut_max = 0.5 * L;
  if (!(r_cut_min > 0.0) || r_cut_min > r_cut_max)
    invalid("PPPM r_cut_min must lie in (0, r_cut_max]", r_cut_min);
  if (r_cut_max > 0.5 * L) invalid("PPPM r_cut_max must not exceed L/2", r_cut_max);
  PppmParams best;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int step = 0;; ++step) {
    const double rc = std::min(r_cut_min + 0.25 * step, r_cut_max);
    for (int order = 2; order <= 7; ++order) {
      PppmParams p;
      try {
        p = choosePppmParams(accuracy, n, L, sum_q2, rc, order);
      } catch (const std::invalid_argument&) {
        continue;  // this (r_cut, order) cannot reach the accuracy within the mesh limit
      }
      const double cost = pppmCost(p, n, L, model);
      if (cost < best_cost) {
        best_cost = cost;
        best = p;
      }
    }
    if (rc >= r_cut_max) break;
  }
  if (!(best_cost < std::numeric_limits<double>::infinity()))
    invalid("PPPM accuracy cannot be met for any r_cut in [r_cut_min, r_cut_max] and order 2..7",
            accuracy);
  return best;
}

}  // namespace granagg::md
