#pragma once
/// \file Restitution.h
/// Coefficient of normal restitution e(v) of two viscoelastic (Hertz + dissipative) spheres
/// (docs/model.md section 3; docs/kinetic.md).
///
/// Units: nondimensional, particle diameter d = 1, mass m = 1, initial granular temperature
/// T0 = 1; speeds in sqrt(T0/m), times in sqrt(m d^2 / T0). Reduced mass m_eff = 1/2.
///
/// Contact model (docs/model.md section 3): for overlap xi = 1 - |r_ij| > 0 with rate xi' > 0 while
/// approaching, each partner feels the normal force F = E xi^{3/2} + D xi^{1/2} xi' and the
/// relative coordinate obeys m_eff xi'' = -F. "Clamped" (default) uses max(F, 0): a contact never
/// pulls (Poeschel & Schwager, Computational Granular Dynamics (Springer 2005), sec. 2.4; the
/// "delayed recovery" of Schwager & Poeschel, PRE 78, 051304 (2008)); "unclamped" keeps the
/// attractive tail. A collision starts at xi = 0 with xi' = v and ends when xi returns to 0;
/// e(v) = -xi'(end) / v.
///
/// Scaling (derived here, as in Ramirez, Poeschel, Brilliantov & Schwager, PRE 60, 4465 (1999),
/// sec. II): with xi = X x, t = tau s, X = (m_eff v^2 / E)^{2/5}, tau = X / v the equation
/// becomes
///
///     x'' = -x^{1/2} (x + b x'),   x(0) = 0, x'(0) = 1,   b = D m_eff^{-2/5} E^{-3/5} v^{1/5},
///
/// so e depends on (E, D, v) only through the single number b, and the contact time is
/// tau times a function of b. In Brilliantov & Poeschel's notation (their equation
/// m_eff xi'' + rho xi^{3/2} + (3/2) A rho xi^{1/2} xi' = 0) rho = E, A = 2 D / (3 E) and
/// b = A kappa^{2/5} v^{1/5} with kappa = (3/2)^{5/2} rho / m_eff (their kappa = (3/2)^{3/2}
/// Y sqrt(R_eff) / (m_eff (1 - nu^2)), Brilliantov & Poeschel, Lecture Notes in Physics 564, p. 100
/// (2000), with rho = 2 Y sqrt(R_eff) / (3 (1 - nu^2))).
///
/// At the defaults E = 278.6, D = 27.7: b = 1.2471 v^{1/5}, i.e. b = 0.685 at v = 0.05 and
/// e = 0.5055 (clamped), 0.4691 (unclamped). The small-damping series below needs b << 1 and is
/// far outside its range there (it gives e = 0.584 at v = 0.05 to second order).
#include <memory>

namespace granagg::meanfield {

/// Reduced mass of two unit-mass spheres, m_eff = m/2 (mass units m).
constexpr double M_EFF = 0.5;

/// Coefficient of the first-order term of the small-damping series, e = 1 - C1 b + C2 b^2 - ...
/// C1 = Gamma(3/5) sqrt(pi) / (2^{1/5} 5^{2/5} Gamma(21/10)) = 1.1534489, published as 1.15344
/// (Ramirez, Poeschel, Brilliantov & Schwager, PRE 60, 4465 (1999); Brilliantov & Poeschel,
/// Kinetic Theory of Granular Gases (OUP 2004)). Rederived in Restitution.cpp from the energy
/// lost along the elastic trajectory; the closed-form value is used. Dimensionless.
constexpr double RESTITUTION_C1 = 1.1534488580952884;
/// Coefficient of the second-order term, C2 = 3 C1^2 / 5 = 0.7982666, published as 0.79826 (same
/// sources). The integration reproduces it to 1e-5 (tests/meanfield/test_restitution.cpp).
/// Dimensionless.
constexpr double RESTITUTION_C2 = 0.6 * RESTITUTION_C1 * RESTITUTION_C1;
/// Dimensionless duration of an elastic Hertz contact (b = 0) in units of tau:
/// 2 (5/4)^{2/5} integral_0^1 (1 - u^{5/2})^{-1/2} du = (4/5) (5/4)^{2/5} B(2/5, 1/2)
/// = 3.2180654597 (docs/model.md section 6: 3.218065; Hertz 1882, Landau & Lifshitz, Theory of
/// Elasticity).
constexpr double HERTZ_CONTACT_TIME_FACTOR = 3.2180654597190435;

/// Contact parameters of the viscoelastic normal force F = E xi^{3/2} + D xi^{1/2} xi'.
struct ContactParams {
  double E = 278.6;     ///< elastic constant, force units m T0 / d per d^{3/2} (> 0)
  double D = 27.7;      ///< dissipative constant, force per (d^{1/2} * speed) (>= 0)
  bool clamped = true;  ///< true: F = max(F, 0) (a contact never pulls); false: keep F < 0
};

/// Throws std::invalid_argument naming the value unless E > 0 and finite, D >= 0 and finite.
void validateContactParams(const ContactParams& p);

/// Numerical options of the two-body integration.
struct RestitutionOptions {
  /// Absolute and relative tolerance of the Dormand-Prince (5)4 dense-output stepper on the
  /// scaled state (x, x') of order one. Dimensionless. Must lie in [1e-15, 1e-3].
  double tolerance = 1e-12;
  /// Longest scaled contact time before giving up (units of tau). Strongly damped unclamped
  /// contacts close slowly against their attractive tail (b = 200: 3200 tau, e = 1.6e-11).
  double max_scaled_time = 1e5;
};

/// Outcome of one collision.
struct CollisionResult {
  double restitution = 0.0;   ///< e = -xi'(end) / v, dimensionless
  double contact_time = 0.0;  ///< time from xi = 0 to xi = 0 again, units sqrt(m d^2 / T0)
  double max_overlap = 0.0;   ///< largest xi during the contact, units d
  /// Clamped: time at which the force reaches zero and the partners fly apart freely (the
  /// overlap closes at constant speed afterwards); unclamped: equals contact_time. Units as above.
  double release_time = 0.0;
  double scaling_parameter = 0.0;  ///< b = D m_eff^{-2/5} E^{-3/5} v^{1/5}, dimensionless
  long steps = 0;                  ///< accepted integrator steps
};

/// Integrates the scaled contact x'' = -x^{1/2}(x + b x') (clamped or not) for damping
/// parameter b >= 0 and returns e, the contact time and the largest overlap in the scaled units
/// (tau, X) described in the file comment. Throws std::invalid_argument for b < 0 or bad options,
/// std::runtime_error if the contact has not ended by options.max_scaled_time.
CollisionResult collideScaled(double b, bool clamped, const RestitutionOptions& options = {});

/// e(v), contact time and largest overlap of the viscoelastic contact by direct integration.
class Restitution {
 public:
  /// Validates the parameters (std::invalid_argument naming the value).
  explicit Restitution(const ContactParams& params = {}, const RestitutionOptions& options = {});

  /// Full collision at impact speed v (units sqrt(T0/m), > 0 and finite; std::invalid_argument).
  CollisionResult collide(double v) const;
  /// e(v), dimensionless.
  double restitution(double v) const { return collide(v).restitution; }
  /// Contact duration at impact speed v, units sqrt(m d^2 / T0).
  double contactTime(double v) const { return collide(v).contact_time; }

  /// b(v) = D m_eff^{-2/5} E^{-3/5} v^{1/5} (dimensionless): e depends on v, E, D only through b.
  double scalingParameter(double v) const;
  /// Time scale tau(v) = m_eff^{2/5} E^{-2/5} v^{-1/5} (units sqrt(m d^2/T0)) of the contact.
  double timeScale(double v) const;
  /// Overlap scale X(v) = (m_eff v^2 / E)^{2/5} (units d).
  double overlapScale(double v) const;

  /// Small-damping series to second order, e = 1 - C1 b + C2 b^2 (Ramirez et al. 1999; the
  /// b and b^2 terms of the complete series of Schwager & Poeschel, PRE 78, 051304 (2008)).
  /// Valid only for b << 1 (1 - e below ~0.1); at the default parameters it is far outside its
  /// range (b = 0.69 at v = 0.05).
  double seriesRestitution(double v) const;
  /// Elastic Hertz contact time t_c = 3.218065 (m_eff^2 / (E^2 v))^{1/5}, units sqrt(m d^2/T0)
  /// (docs/model.md section 6).
  double elasticContactTime(double v) const;

  const ContactParams& params() const { return m_params; }
  const RestitutionOptions& options() const { return m_options; }

 private:
  void checkSpeed(double v) const;
  ContactParams m_params;
  RestitutionOptions m_options;
};

/// Second-order small-damping series e = 1 - C1 b + C2 b^2 as a function of b (dimensionless).
double seriesRestitutionScaled(double b);

/// e(v) tabulated once on a logarithmic grid of the scaling parameter b and interpolated with a
/// GSL cubic spline, for fast repeated evaluation (velocity averages in Cooling.h). The spline
/// interpolates ln[(1 - e) / b] against ln b, which is smooth, tends to ln C1 as b -> 0 and to
/// -ln b for large b. Measured interpolation error with the default 600 points on [1e-6, 20]:
/// 1e-9 (clamped) and 1e-8 (unclamped, where e falls fastest near b = 2.7). Below the grid
/// (b < b_min) the second-order series is used: its error there is O(b^{5/2}) (below 1e-14 for
/// the default b_min = 1e-6). Above the grid the contact is integrated directly.
/// Copies share the immutable spline; evaluation is thread-safe.
class RestitutionTable {
 public:
  /// Builds the table: `points` direct integrations for b from b_min to b_max.
  /// Throws std::invalid_argument for bad parameters, 0 < b_min < b_max, points >= 8.
  explicit RestitutionTable(const ContactParams& params = {}, double b_min = 1e-6,
                            double b_max = 20.0, int points = 600,
                            const RestitutionOptions& options = {});

  /// e(v) from the table, dimensionless; v in sqrt(T0/m), v > 0 (std::invalid_argument).
  double restitution(double v) const;
  /// e(v) for v >= 0 without argument checks; e(0) = 1. For use inside integrands.
  double operator()(double v) const;
  /// e as a function of the scaling parameter b >= 0 (dimensionless).
  double restitutionScaled(double b) const;

  double bMin() const { return m_b_min; }
  double bMax() const { return m_b_max; }
  /// b(v) / v^{1/5} = D m_eff^{-2/5} E^{-3/5}, units (sqrt(T0/m))^{-1/5}.
  double bPerSpeed() const { return m_b1; }
  const ContactParams& params() const { return m_params; }

 private:
  struct Spline;
  ContactParams m_params;
  RestitutionOptions m_options;
  double m_b_min, m_b_max, m_b1;
  std::shared_ptr<const Spline> m_spline;
};

}  // namespace granagg::meanfield
