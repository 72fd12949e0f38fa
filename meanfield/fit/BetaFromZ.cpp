// beta from a measured z: the asymptotic relation and the curves' exponent between two sizes
// (BetaFit.h: BetaFromZ).
#include "meanfield/fit/BetaFit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

#include "common/Csv.h"
#include "common/Strings.h"
#include "meanfield/fit/FitSupport.h"

namespace granagg::meanfield {

using common::formatReal;
using namespace detail;

void validateBetaRange(double beta_min, double beta_max) {
  if (!(beta_min >= BETA_LOWEST) || !(beta_min <= BETA_HIGHEST))
    throw std::invalid_argument("--beta-min must lie in [" + formatReal(BETA_LOWEST) + ", " +
                                formatReal(BETA_HIGHEST) + "] (got " + formatReal(beta_min) + ").");
  if (!(beta_max >= BETA_LOWEST) || !(beta_max <= BETA_HIGHEST))
    throw std::invalid_argument("--beta-max must lie in [" + formatReal(BETA_LOWEST) + ", " +
                                formatReal(BETA_HIGHEST) + "] (got " + formatReal(beta_max) + ").");
  if (!(beta_max - beta_min >= 0.1))
    throw std::invalid_argument("--beta-max must exceed --beta-min by at least 0.1 (got " +
                                formatReal(beta_min) + ", " + formatReal(beta_max) + ").");
}

namespace {
struct RootParams {
  MeanFieldCurves* curves;
  double S0, S1, z;
};
double zResidual(double beta, void* p) {
  auto* r = static_cast<RootParams*>(p);
  return r->curves->exponentBetween(r->S0, r->S1, beta) - r->z;
}
}  // namespace

BetaFromZ betaAsymptotic(double z, double z_low, double z_high) {
  BetaFromZ out;
  out.S0 = out.S1 = out.z_at_beta_min = out.z_at_beta_max = NaN;
  // beta(z) = 3 z / (3 - z), increasing on (0, 3) from 0 to +inf.
  auto beta = [](double x) {
    if (!std::isfinite(x)) return NaN;
    if (x <= 0.0) return 0.0;
    if (x >= 3.0) return std::numeric_limits<double>::infinity();
    return 3.0 * x / (3.0 - x);
  };
  if (!std::isfinite(z) || z <= 0.0 || z >= 3.0) {
    out.beta = out.beta_low = out.beta_high = NaN;
    out.note =
        std::isfinite(z)
            ? (z <= 0.0 ? "z = " + common::formatShort(z) + " <= 0: S does not grow, no beta."
                        : "z = " + common::formatShort(z) +
                              " >= 3: faster than 3 beta/(beta + 3) for every beta, no beta.")
            : "z is not finite: no beta.";
    return out;
  }
  out.beta = beta(z);
  out.beta_low = beta(z_low);
  out.beta_high = beta(z_high);
  if (std::isfinite(z_high) && z_high >= 3.0)
    out.note += "z_high = " + common::formatShort(z_high) + " >= 3: no upper bound on beta. ";
  if (std::isfinite(z_low) && z_low <= 0.0)
    out.note += "z_low = " + common::formatShort(z_low) + " <= 0: the interval reaches beta = 0. ";
  if (!out.note.empty()) out.note.pop_back();
  return out;
}

BetaFromZ betaFromZ(MeanFieldCurves& curves, double z, double z_low, double z_high, double S0,
                    double S1, double beta_min, double beta_max) {
  validateBetaRange(beta_min, beta_max);
  BetaFromZ out;
  std::string note;
  const double S_floor = 1.0001;
  if (S0 < S_floor) {
    note += "window starts at S = " + common::formatShort(S0) +
            " <= 1, the mean field's initial S; compared from S = 1.0001. ";
    S0 = S_floor;
  }
  out.S0 = S0;
  out.S1 = S1;
  if (!(S1 > S0 * 1.0001)) {
    out.beta = out.beta_low = out.beta_high = out.z_at_beta_min = out.z_at_beta_max = NaN;
    out.note = note + "S does not grow over the window: no mean-field exponent to compare with.";
    return out;
  }
  out.z_at_beta_min = curves.exponentBetween(S0, S1, beta_min);
  out.z_at_beta_max = curves.exponentBetween(S0, S1, beta_max);
  gsl_error_handler_t* old = gsl_set_error_handler_off();
  const double h = curves.options().beta_step;
  std::map<int, double> zNodes;
  auto zNode = [&](int k) {
    auto it = zNodes.find(k);
    if (it == zNodes.end()) it = zNodes.emplace(k, curves.exponentBetween(S0, S1, k * h)).first;
    return it->second;
  };
  auto invert = [&](double zt, bool central, const char* what) -> double {
    if (!std::isfinite(zt)) return NaN;
    if (zt <= out.z_at_beta_min || zt >= out.z_at_beta_max) {
      const bool below = zt <= out.z_at_beta_min;
      note += std::string(what) + " = " + common::formatShort(zt) + " lies " +
              (below ? "below" : "above") + " the mean-field z = " +
              common::formatShort(below ? out.z_at_beta_min : out.z_at_beta_max) +
              " at beta = " + formatReal(below ? beta_min : beta_max) +
              (central ? ": no beta" : ": clamped to the range") + ". ";
      return central ? NaN : (below ? beta_min : beta_max);
    }
    // Bracket on the beta nodes first (exact nodes need one solve each, interpolated betas four):
    // bisection over node indices, then Brent's method inside one node cell.
    double lo = beta_min, hi = beta_max;
    int klo = static_cast<int>(std::ceil(beta_min / h - 1e-9)),
        khi = static_cast<int>(std::floor(beta_max / h + 1e-9));
    if (klo <= khi) {
      if (zt < zNode(klo)) {
        hi = klo * h;
      } else if (zt >= zNode(khi)) {
        lo = khi * h;
      } else {
        while (khi - klo > 1) {
          const int mid = (klo + khi) / 2;
          (zNode(mid) <= zt ? klo : khi) = mid;
        }
        lo = klo * h;
        hi = khi * h;
      }
    }
    RootParams rp{&curves, S0, S1, zt};
    gsl_function F{&zResidual, &rp};
    gsl_root_fsolver* s = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    gsl_root_fsolver_set(s, &F, lo, hi);
    double root = NaN;
    for (int it = 0; it < 100; ++it) {
      if (gsl_root_fsolver_iterate(s) != GSL_SUCCESS) break;
      root = gsl_root_fsolver_root(s);
      if (gsl_root_test_interval(gsl_root_fsolver_x_lower(s), gsl_root_fsolver_x_upper(s), 1e-7,
                                 0.0) == GSL_SUCCESS)
        break;
    }
    gsl_root_fsolver_free(s);
    return root;
  };
  out.beta = invert(z, true, "z");
  out.beta_low = invert(z_low, false, "z_low");
  out.beta_high = invert(z_high, false, "z_high");
  gsl_set_error_handler(old);
  out.note = note;
  while (!out.note.empty() && out.note.back() == ' ') out.note.pop_back();
  return out;
}

}  // namespace granagg::meanfield
