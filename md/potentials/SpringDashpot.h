#pragma once
/// \file SpringDashpot.h
/// Linear spring-dashpot contact with a constant coefficient of restitution epsilon, used for the
/// Haff's-law figure (Singh & Mazza 2018, Fig. 1(a)). Normal force on each partner
///
///     F = k_n xi + gamma_n xi'      (xi' > 0 while approaching)
///
/// With reduced mass m_eff, zeta = gamma_n / (2 m_eff) and omega0^2 = k_n / m_eff, a contact that
/// ends at xi = 0 (unclamped) rebounds with epsilon = exp(-pi zeta / omega), omega = sqrt(omega0^2
/// - zeta^2), for every impact speed; inverted: zeta = -ln(eps) omega0 / sqrt(pi^2 + ln(eps)^2)
/// (e.g. Schaefer, Dippel & Wolf, J. Phys. I France 6, 5 (1996)). Contact time pi / omega. With
/// `clamp` the force is cut at zero and the rebound is slightly more elastic than epsilon.
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "common/HostDevice.h"
#include "md/config/MdConfig.h"

namespace granagg::md {

struct SpringDashpot {
  struct Params {
    double k;      ///< stiffness k_n (> 0)
    double gamma;  ///< damping gamma_n (>= 0)
    bool clamp;
  };
  static constexpr const char* name = "spring_dashpot";

  HD static double normalForce(double xi, double xi_dot, const Params& p) {
    const double f = p.k * xi + p.gamma * xi_dot;
    return (p.clamp && f < 0.0) ? 0.0 : f;
  }
  HD static double elasticEnergy(double xi, const Params& p) { return 0.5 * p.k * xi * xi; }

  /// Parameters giving restitution epsilon in (0, 1] for stiffness k (unclamped closed form above).
  static Params makeParams(double k, double epsilon, bool clamp, double m_eff = 0.5) {
    if (!(k > 0.0)) throw std::invalid_argument("contact.stiffness must be positive.");
    if (!(epsilon > 0.0 && epsilon <= 1.0))
      throw std::invalid_argument("contact.restitution must lie in (0, 1].");
    const double omega0 = std::sqrt(k / m_eff);
    const double le = std::log(epsilon);
    const double zeta = -le * omega0 / std::sqrt(M_PI * M_PI + le * le);
    return {k, 2.0 * m_eff * zeta, clamp};
  }
  /// Contact duration pi / omega (independent of the impact speed).
  static double contactTime(const Params& p, double m_eff = 0.5) {
    const double zeta = p.gamma / (2.0 * m_eff);
    return M_PI / std::sqrt(p.k / m_eff - zeta * zeta);
  }

  // the model's hooks for the engine (md/potentials/ContactModels.h)
  /// contact.stiffness, contact.restitution, contact.clamp
  static Params fromConfig(const ContactConfig& c, double m_eff) {
    return makeParams(c.stiffness, c.restitution, c.clamp, m_eff);
  }
  /// The contact time that sets the automatic dt: pi / omega, whatever the impact speed.
  static double autoContactTime(const Params& p, double /*impact_speed*/, double m_eff,
                                std::string& why) {
    const double tc = contactTime(p, m_eff);
    std::ostringstream s;
    s << "spring-dashpot contact time " << tc;
    why = s.str();
    return tc;
  }
  /// The strongest attraction a static contact balances: the maximum over xi of
  /// k xi (1 - xi)^2, which is 4 k / 27 at xi = 1/3 (HertzViscoelastic::attractionLimit); `how`
  /// says so.
  static double attractionLimit(const Params& p, std::string& how) {
    how = "max over xi of k xi (1 - xi)^2 = 4 k / 27";
    return 4.0 * p.k / 27.0;
  }
};

}  // namespace granagg::md
