#pragma once
/// \file HertzViscoelastic.h
/// Viscoelastic Hertz contact (Singh & Mazza 2018, eq. of motion; Brilliantov et al. 1996;
/// docs/model.md section 3). For two spheres of diameter 1 with overlap xi = 1 - |r_ij| > 0
/// approaching at rate xi' (> 0 while approaching), each partner feels the normal force
///
///     F = E xi^{3/2} + D xi^{1/2} xi'        (reduced units: force in T0/d)
///
/// along n_ji (repulsive when F > 0). The sum turns negative near the end of a contact; `clamp`
/// (default) cuts it at zero so that a contact never pulls (Poeschel & Schwager, Computational
/// Granular Dynamics; LAMMPS limit_damping). Restitution at impact speed 0.05: 0.506 clamped,
/// 0.469 unclamped.
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "common/HostDevice.h"
#include "md/config/MdConfig.h"

namespace granagg::md {

struct HertzViscoelastic {
  struct Params {
    double E;    ///< elastic constant (>= 0)
    double D;    ///< dissipative constant (>= 0)
    bool clamp;  ///< force never negative
  };
  static constexpr const char* name = "hertz";

  /// Normal force magnitude on each partner for overlap xi > 0 and approach rate xi_dot.
  HD static double normalForce(double xi, double xi_dot, const Params& p) {
    const double s = sqrt(xi);
    const double f = s * (p.E * xi + p.D * xi_dot);
    return (p.clamp && f < 0.0) ? 0.0 : f;
  }
  /// Elastic energy of the contact, (2/5) E xi^{5/2} (F_el = dV/dxi).
  HD static double elasticEnergy(double xi, const Params& p) {
    return 0.4 * p.E * xi * xi * sqrt(xi);
  }
  /// Duration of an elastic (D = 0) Hertz contact at impact speed v for reduced mass m_eff:
  /// t_c = 3.218065 (m_eff^2 / (E^2 v))^{1/5} (Landau & Lifshitz, Theory of Elasticity, sec. 9;
  /// docs/model.md section 6). Longer for slower impacts and with damping.
  static double contactTime(double v, const Params& p, double m_eff = 0.5) {
    return 3.218065 * std::pow(m_eff * m_eff / (p.E * p.E * v), 0.2);
  }

  // the model's hooks for the engine (md/potentials/ContactModels.h)
  /// contact.E, contact.D, contact.clamp
  static Params fromConfig(const ContactConfig& c, double /*m_eff*/) { return {c.E, c.D, c.clamp}; }
  /// The contact time that sets the automatic dt: the elastic one at the fastest impact speed;
  /// `why` says so.
  static double autoContactTime(const Params& p, double impact_speed, double m_eff,
                                std::string& why) {
    if (!(p.E > 0.0))
      throw std::invalid_argument(
          "integrator.dt = \"auto\" needs contact.E > 0 (the Hertz contact time is infinite for "
          "E = 0); give integrator.dt explicitly.");
    const double tc = contactTime(impact_speed, p, m_eff);
    std::ostringstream s;
    s << "elastic Hertz contact time " << tc << " at impact speed " << impact_speed;
    why = s.str();
    return tc;
  }
  /// The strongest attraction a static contact balances (docs/model.md section 4): an attractive
  /// Coulomb pair K |q_i q_j| / (1 - xi)^2 has an equilibrium overlap only if it is at most the
  /// maximum over xi of E xi^{3/2} (1 - xi)^2, which is (3/7)^{3/2} (4/7)^2 E = 0.0916 E at
  /// xi = 3/7; `how` says so.
  static double attractionLimit(const Params& p, std::string& how) {
    how = "max over xi of E xi^{3/2} (1 - xi)^2 = 0.0916 E";
    return std::pow(3.0 / 7.0, 1.5) * (16.0 / 49.0) * p.E;
  }
};

}  // namespace granagg::md
