/// `granagg kinetic`: kinetic-theory references (meanfield/kinetic): viscoelastic restitution,
/// Haff's law, viscoelastic cooling, Enskog collision frequency, charging-rate exponent.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Strings.h"
#include "meanfield/kinetic/Charging.h"
#include "meanfield/kinetic/Cooling.h"
#include "meanfield/kinetic/Restitution.h"

namespace granagg::cli {
namespace mf = granagg::meanfield;
using common::formatReal;

namespace {

const char* const UNITS =
    "Reduced units: diameter d = 1, mass m = 1, initial temperature T0 = 1; speeds in sqrt(T0/m), "
    "times in "
    "sqrt(m d^2/T0).";

void require(bool ok, const std::string& sentence) {
  if (!ok) throw std::invalid_argument(sentence);
}

struct ContactArgs {
  double E = 278.6;
  double D = 27.7;
  bool unclamped = false;
  mf::ContactParams params() const {
    require(E > 0.0 && std::isfinite(E),
            "--E must be positive and finite (got " + formatReal(E) + ").");
    require(D >= 0.0 && std::isfinite(D),
            "--D must be non-negative and finite (got " + formatReal(D) + ").");
    return mf::ContactParams{E, D, !unclamped};
  }
};

void addContactOptions(CLI::App* cmd, ContactArgs& c) {
  cmd->add_option("--E", c.E,
                  "Elastic constant E of F = E xi^{3/2} + D xi^{1/2} xi' (> 0, reduced units)")
      ->capture_default_str();
  cmd->add_option("--D", c.D, "Dissipative constant D (>= 0, reduced units)")
      ->capture_default_str();
  cmd->add_flag("--unclamped", c.unclamped,
                "Keep the attractive force at the end of a contact (default: clamp F at 0, a "
                "contact never pulls)");
}

struct OutArgs {
  std::string out = "-";
  bool force = false;
};

void addOutOptions(CLI::App* cmd, OutArgs& o) {
  cmd->add_option("-o,--out", o.out, "Output CSV ('-' = standard output)")->capture_default_str();
  cmd->add_flag("--force", o.force, "Overwrite an existing output file");
}

void checkPhi(double phi) {
  require(phi > 0.0 && phi < 0.74, "--phi must lie in (0, 0.74) (got " + formatReal(phi) + ").");
}

/// t = 0 followed by `points` log-spaced times from t_min to t_end.
std::vector<double> outputTimes(double t_min, double t_end, int points) {
  require(t_min > 0.0 && std::isfinite(t_min),
          "--t-min must be positive and finite (got " + formatReal(t_min) + ").");
  require(t_end > t_min && std::isfinite(t_end),
          "--t-end must be finite and larger than --t-min = " + formatReal(t_min) + " (got " +
              formatReal(t_end) + ").");
  require(points >= 2 && points <= 100000,
          "--points must lie in [2, 100000] (got " + std::to_string(points) + ").");
  std::vector<double> t{0.0};
  const double l0 = std::log10(t_min), l1 = std::log10(t_end);
  for (int k = 0; k < points; ++k) t.push_back(std::pow(10.0, l0 + (l1 - l0) * k / (points - 1.0)));
  t.back() = t_end;  // exactly the requested end
  return t;
}

void addContactProvenance(common::Provenance& prov, const mf::ContactParams& p) {
  prov.add("E", p.E);
  prov.add("D", p.D);
  prov.add("force_law", std::string(p.clamped ? "clamped: F = max(E xi^1.5 + D xi^0.5 xi', 0)"
                                              : "unclamped: F = E xi^1.5 + D xi^0.5 xi'"));
  prov.add("m_eff", mf::M_EFF);
  prov.add("units", std::string(UNITS));
}

// ---- restitution ----
struct RestitutionArgs {
  std::string v = "0.05,0.1,1,2";  // parsed by impactSpeeds(): an empty item is an error
  ContactArgs contact;
  OutArgs out;
};

/// --v: comma-separated impact speeds, each > 0 and finite; an empty or malformed item is an
/// error (CLI11's delimiter dropped the empty item of "1,,2").
std::vector<double> impactSpeeds(const std::string& text) {
  std::vector<double> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string item =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    double v = 0.0;
    require(common::parseReal(item, v) && v > 0.0 && std::isfinite(v),
            "--v takes comma-separated impact speeds > 0, e.g. --v 0.1,1 (got '" + text + "').");
    out.push_back(v);
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

void runRestitution(const RestitutionArgs& a, const CliContext& ctx) {
  const mf::ContactParams p = a.contact.params();
  const std::vector<double> speeds = impactSpeeds(a.v);
  common::refuseToOverwrite(a.out.out == "-" ? std::string() : a.out.out, a.out.force);
  const mf::Restitution R(p);

  // The second-order series is printed only where it applies (b < 0.1, i.e. 1 - e below ~0.11);
  // elsewhere the column holds nan.
  constexpr double SERIES_B_MAX = 0.1;
  common::Provenance prov(ctx.command_line);
  addContactProvenance(prov, p);
  prov.add("tolerance", R.options().tolerance);
  prov.add("columns", std::string("v: impact speed; e = -xi'(end)/v; contact_time: xi > 0 "
                                  "duration; release_time: clamped force "
                                  "reaches 0 (= contact_time unclamped); max_overlap in d; b = D "
                                  "m_eff^-0.4 E^-0.6 v^0.2 (e depends "
                                  "on b only); e_series = 1 - C1 b + C2 b^2 where b < ") +
                          formatReal(SERIES_B_MAX) +
                          ", else nan; elastic_contact_time = 3.218065 (m_eff^2/(E^2 v))^0.2");
  common::CsvWriter w(a.out.out, prov,
                      {"v", "e", "contact_time", "release_time", "max_overlap", "b", "e_series",
                       "elastic_contact_time"},
                      a.out.force);
  for (double v : speeds) {
    const mf::CollisionResult r = R.collide(v);
    if (r.max_overlap > 1.0) {  // the centres would pass each other: not a contact any more
      char why[200];
      std::snprintf(why, sizeof why,
                    "v = %.4g: max_overlap %.3g > 1 d, the spheres would pass through each "
                    "other; the Hertz law does not describe such an impact",
                    v, r.max_overlap);
      std::fprintf(stderr, "kinetic restitution: warning: %s\n", why);
      w.comment(std::string("warning: ") + why);
    }
    const double series =
        r.scaling_parameter < SERIES_B_MAX ? R.seriesRestitution(v) : std::nan("");
    w.row({v, r.restitution, r.contact_time, r.release_time, r.max_overlap, r.scaling_parameter,
           series, R.elasticContactTime(v)});
  }
  w.close();
}

// ---- haff ----
struct HaffArgs {
  double eps = 0.9;
  double phi = 0.076;
  double T0 = 1.0;
  double t_min = 1e-2;
  double t_end = 1000.0;
  int points = 50;
  OutArgs out;
};

void runHaff(const HaffArgs& a, const CliContext& ctx) {
  require(a.eps >= 0.0 && a.eps <= 1.0,
          "--eps must lie in [0, 1] (got " + formatReal(a.eps) + ").");
  checkPhi(a.phi);
  require(a.T0 > 0.0 && std::isfinite(a.T0),
          "--T0 must be positive and finite (got " + formatReal(a.T0) + ").");
  const auto times = outputTimes(a.t_min, a.t_end, a.points);
  common::refuseToOverwrite(a.out.out == "-" ? std::string() : a.out.out, a.out.force);
  const double inv_tau0 = mf::haffInverseTau0(a.eps, a.phi, a.T0);

  common::Provenance prov(ctx.command_line);
  prov.add("eps", a.eps);
  prov.add("phi", a.phi);
  prov.add("T0", a.T0);
  prov.add("omega0", mf::enskogCollisionFrequency(a.phi, a.T0));
  prov.add("tau0", inv_tau0 > 0.0 ? 1.0 / inv_tau0 : std::numeric_limits<double>::infinity());
  prov.add("law",
           std::string("T = T0 / (1 + t/tau0)^2, 1/tau0 = (1 - eps^2) omega0 / 6 (Haff 1983)"));
  prov.add("units", std::string(UNITS));
  prov.add("columns", std::string("t: time; T: granular temperature; slope = d ln T / d ln t"));
  common::CsvWriter w(a.out.out, prov, {"t", "T", "slope"}, a.out.force);
  for (double t : times) {
    const double slope = t > 0.0 ? -2.0 * t * inv_tau0 / (1.0 + t * inv_tau0) : 0.0;
    w.row({t, mf::haffTemperature(t, a.eps, a.phi, a.T0), slope});
  }
  w.close();
}

// ---- cooling ----
struct CoolingArgs {
  ContactArgs contact;
  double phi = 0.076;
  double t_min = 1e-2;
  double t_end = 1000.0;
  int points = 50;
  OutArgs out;
};

void runCooling(const CoolingArgs& a, const CliContext& ctx) {
  const mf::ContactParams p = a.contact.params();
  require(p.D > 0.0,
          "--D must be positive for viscoelastic cooling (got 0: the gas does not cool).");
  checkPhi(a.phi);
  const auto times = outputTimes(a.t_min, a.t_end, a.points);
  common::refuseToOverwrite(a.out.out == "-" ? std::string() : a.out.out, a.out.force);

  mf::CoolingOptions o;
  o.phi = a.phi;
  const auto r = mf::solveViscoelasticCooling(p, times, o);
  // Haff's law with the same initial cooling rate: 1 - eps_eff^2 = L(T0).
  const double loss0 = r.front().loss;
  const double eps_eff = std::sqrt(std::max(0.0, 1.0 - loss0));
  const double tau = mf::viscoelasticCoolingTau0(p, a.phi, o.T0);

  common::Provenance prov(ctx.command_line);
  addContactProvenance(prov, p);
  prov.add("phi", a.phi);
  prov.add("T0", o.T0);
  prov.add("omega0", mf::enskogCollisionFrequency(a.phi, o.T0));
  prov.add(
      "ode",
      std::string(
          "dT/dt = -(omega(T)/12) <g^2 (1 - e(g)^2)>, P(g) = g/(2T) exp(-g^2/(4T)), Maxwellian"));
  prov.add("rtol", o.rtol);
  prov.add("eps_same_initial_rate", eps_eff);
  prov.add("tau0_small_damping", tau);
  prov.add("columns", std::string("t; T: viscoelastic cooling ODE; slope = d ln T/d ln t; loss = "
                                  "<g^2(1-e^2)>/<g^2>; T_haff: Haff's "
                                  "law with eps_same_initial_rate; T_asymptote = T0 "
                                  "(t/tau0)^(-5/3), the exact late-time limit; "
                                  "T_small_damping = T0 (1 + t/tau0)^(-5/3), first order in the "
                                  "damping (not valid when loss is not "
                                  "small)"));
  common::CsvWriter w(a.out.out, prov,
                      {"t", "T", "slope", "loss", "T_haff", "T_asymptote", "T_small_damping"},
                      a.out.force);
  for (const auto& s : r) {
    w.row({s.t, s.T, s.slope, s.loss, mf::haffTemperature(s.t, eps_eff, a.phi, o.T0),
           s.t > 0.0 ? o.T0 * std::pow(s.t / tau, -5.0 / 3.0)
                     : std::numeric_limits<double>::infinity(),
           mf::viscoelasticCoolingTemperature(s.t, p, a.phi, o.T0)});
  }
  w.close();
}

// ---- enskog ----
struct EnskogArgs {
  double phi = 0.076;
  double T = 1.0;
  OutArgs out;
};

void runEnskog(const EnskogArgs& a, const CliContext& ctx) {
  checkPhi(a.phi);
  require(a.T >= 0.0 && std::isfinite(a.T),
          "--T must be non-negative and finite (got " + formatReal(a.T) + ").");
  common::refuseToOverwrite(a.out.out == "-" ? std::string() : a.out.out, a.out.force);
  common::Provenance prov(ctx.command_line);
  prov.add("phi", a.phi);
  prov.add("T", a.T);
  prov.add("units", std::string(UNITS));
  prov.add(
      "columns",
      std::string("n = 6 phi/pi (d^-3); g2 = (1 - phi/2)/(1 - phi)^3 (Carnahan-Starling); "
                  "omega = 4 sqrt(pi) n g2 sqrt(T/m): Enskog collision frequency per particle"));
  common::CsvWriter w(a.out.out, prov, {"phi", "T", "n", "g2", "omega"}, a.out.force);
  w.row({a.phi, a.T, mf::numberDensity(a.phi), mf::carnahanStarlingG2(a.phi),
         mf::enskogCollisionFrequency(a.phi, a.T)});
  w.close();
}

// ---- charging ----
struct ChargingArgs {
  double kappa = 0.83;
  double a = 5.0 / 3.0;
  OutArgs out;
};

void runCharging(const ChargingArgs& c, const CliContext& ctx) {
  require(c.kappa >= 0.0 && std::isfinite(c.kappa),
          "--kappa must be non-negative and finite (got " + formatReal(c.kappa) + ").");
  require(c.a > 0.0 && std::isfinite(c.a),
          "--cooling-exponent must be positive and finite (got " + formatReal(c.a) + ").");
  common::refuseToOverwrite(c.out.out == "-" ? std::string() : c.out.out, c.out.force);
  common::Provenance prov(ctx.command_line);
  prov.add("kappa", c.kappa);
  prov.add("cooling_exponent", c.a);
  prov.add("law",
           std::string("d<|q|>/dt ~ T^(1/2) T^kappa with T ~ t^-a: exponent = -a (1/2 + kappa) "
                       "(design.md section 2; -13/6 at kappa = 0.8, a = 5/3)"));
  common::CsvWriter w(c.out.out, prov, {"kappa", "cooling_exponent", "charging_rate_exponent"},
                      c.out.force);
  w.row({c.kappa, c.a, mf::chargingRateExponent(c.kappa, c.a)});
  w.close();
}

}  // namespace

void registerKineticCommand(CLI::App& app, const CliContext& ctx) {
  CLI::App* kin = app.add_subcommand(
      "kinetic", std::string("Kinetic-theory references: viscoelastic restitution e(v), Haff's "
                             "law, viscoelastic cooling, Enskog "
                             "collision frequency, charging-rate exponent. ") +
                     UNITS);
  kin->require_subcommand(1);

  auto ra = std::make_shared<RestitutionArgs>();
  CLI::App* rest = kin->add_subcommand(
      "restitution",
      "Restitution coefficient e(v) and contact time of two viscoelastic spheres (m_eff = 1/2) by "
      "integrating "
      "m_eff xi'' = -(E xi^{3/2} + D xi^{1/2} xi') from xi = 0, xi' = v until xi = 0 again.");
  rest->add_option("--v", ra->v,
                   "Impact speeds (normal relative speed, sqrt(T0/m), > 0), comma separated")
      ->capture_default_str();
  addContactOptions(rest, ra->contact);
  addOutOptions(rest, ra->out);
  rest->callback([ra, ctx]() { runRestitution(*ra, ctx); });

  auto ha = std::make_shared<HaffArgs>();
  CLI::App* haff = kin->add_subcommand("haff",
                                       "Haff's law T(t) = T0/(1 + t/tau0)^2, 1/tau0 = (1 - eps^2) "
                                       "omega0/6, for constant restitution eps.");
  haff->add_option("--eps", ha->eps, "Constant restitution coefficient, in [0, 1]")
      ->capture_default_str();
  haff->add_option("--phi", ha->phi, "Filling fraction, in (0, 0.74)")->capture_default_str();
  haff->add_option("--T0", ha->T0, "Initial temperature (units T0, > 0)")->capture_default_str();
  haff->add_option("--t-min", ha->t_min, "First log-spaced output time after t = 0 (> 0)")
      ->capture_default_str();
  haff->add_option("--t-end", ha->t_end, "Last output time (> t-min)")->capture_default_str();
  haff->add_option("--points", ha->points, "Number of log-spaced output times (>= 2)")
      ->capture_default_str();
  addOutOptions(haff, ha->out);
  haff->callback([ha, ctx]() { runHaff(*ha, ctx); });

  auto ca = std::make_shared<CoolingArgs>();
  CLI::App* cool = kin->add_subcommand(
      "cooling",
      "Homogeneous cooling with the viscoelastic e(g): dT/dt = -(omega(T)/12) <g^2 (1 - e(g)^2)> "
      "over a Maxwellian "
      "(T0 = 1), beside Haff's law with the same initial rate and the t^{-5/3} asymptote.");
  addContactOptions(cool, ca->contact);
  cool->add_option("--phi", ca->phi, "Filling fraction, in (0, 0.74)")->capture_default_str();
  cool->add_option("--t-min", ca->t_min, "First log-spaced output time after t = 0 (> 0)")
      ->capture_default_str();
  cool->add_option("--t-end", ca->t_end,
                   "Last output time (> t-min); the t^{-5/3} regime needs t >> 1e6")
      ->capture_default_str();
  cool->add_option("--points", ca->points, "Number of log-spaced output times (>= 2)")
      ->capture_default_str();
  addOutOptions(cool, ca->out);
  cool->callback([ca, ctx]() { runCooling(*ca, ctx); });

  auto ea = std::make_shared<EnskogArgs>();
  CLI::App* ensk = kin->add_subcommand("enskog",
                                       "Number density n, Carnahan-Starling g2 and Enskog "
                                       "collision frequency omega = 4 sqrt(pi) n g2 sqrt(T/m).");
  ensk->add_option("--phi", ea->phi, "Filling fraction, in (0, 0.74)")->capture_default_str();
  ensk->add_option("--T", ea->T, "Granular temperature (units T0, >= 0)")->capture_default_str();
  addOutOptions(ensk, ea->out);
  ensk->callback([ea, ctx]() { runEnskog(*ea, ctx); });

  auto cha = std::make_shared<ChargingArgs>();
  CLI::App* chg = kin->add_subcommand("charging",
                                      "Time exponent of the charging rate d<|q|>/dt ~ T^{1/2} "
                                      "T^kappa ~ t^{-a(1/2 + kappa)} for T ~ t^{-a}.");
  chg->add_option("--kappa", cha->kappa,
                  "Charging exponent kappa (>= 0; 0.83 for silica, Poppe et al. 2000)")
      ->capture_default_str();
  chg->add_option("--cooling-exponent", cha->a, "a in T ~ t^{-a} (> 0; 5/3 viscoelastic, 2 Haff)")
      ->capture_default_str();
  addOutOptions(chg, cha->out);
  chg->callback([cha, ctx]() { runCharging(*cha, ctx); });
}

}  // namespace granagg::cli
