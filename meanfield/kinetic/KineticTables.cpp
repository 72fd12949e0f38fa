/// \file KineticTables.cpp
/// The tables of `granagg kinetic` (KineticTables.h).
#include "meanfield/kinetic/KineticTables.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "common/Strings.h"
#include "meanfield/kinetic/Charging.h"
#include "meanfield/kinetic/Cooling.h"

namespace granagg::meanfield {
using common::formatReal;

namespace {

const char* const UNITS =
    "Reduced units: diameter d = 1, mass m = 1, initial temperature T0 = 1; speeds in sqrt(T0/m), "
    "times in "
    "sqrt(m d^2/T0).";

void require(bool ok, const std::string& sentence) {
  if (!ok) throw std::invalid_argument(sentence);
}

ContactParams contactParams(double E, double D, bool unclamped) {
  require(E > 0.0 && std::isfinite(E),
          "--E must be positive and finite (got " + formatReal(E) + ").");
  require(D >= 0.0 && std::isfinite(D),
          "--D must be non-negative and finite (got " + formatReal(D) + ").");
  return ContactParams{E, D, !unclamped};
}

void checkPhi(double phi) {
  require(phi > 0.0 && phi < 0.74, "--phi must lie in (0, 0.74) (got " + formatReal(phi) + ").");
}

void addContactProvenance(common::Provenance& prov, const ContactParams& p) {
  prov.add("E", p.E);
  prov.add("D", p.D);
  prov.add("force_law", std::string(p.clamped ? "clamped: F = max(E xi^1.5 + D xi^0.5 xi', 0)"
                                              : "unclamped: F = E xi^1.5 + D xi^0.5 xi'"));
  prov.add("m_eff", M_EFF);
  prov.add("units", std::string(UNITS));
}

}  // namespace

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

std::vector<double> tableTimes(double t_min, double t_end, int points) {
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

namespace {

/// A table and where its comments go: comment i precedes row comment_rows[i] (rows.size(): after
/// the last row). The positions are the CSV's business only, hence not part of KineticTable.
struct PlacedTable {
  KineticTable table;
  std::vector<std::size_t> comment_rows;
};

/// The one writer of the five tables: the target's command line, then the table's parameters
/// in their order, its columns, and its rows with the comments at their places.
void writeKinetic(const KineticTable& t, const std::vector<std::size_t>& comment_rows,
                  const CsvTarget& target) {
  common::Provenance prov(target.command_line);
  for (const auto& [key, value] : t.provenance.parameters()) prov.add(key, value);
  common::CsvWriter w(target.path, prov, t.columns, target.force);
  // A comment without a place (none given, or past the end) goes after the last row.
  auto placeOf = [&](std::size_t c) {
    return std::min(c < comment_rows.size() ? comment_rows[c] : t.rows.size(), t.rows.size());
  };
  std::size_t c = 0;
  for (std::size_t i = 0; i <= t.rows.size(); ++i) {
    for (; c < t.comments.size() && placeOf(c) <= i; ++c) w.comment(t.comments[c]);
    if (i < t.rows.size()) w.row(t.rows[i]);
  }
  w.close();
}

PlacedTable restitutionTable(const RestitutionRequest& a) {
  const ContactParams p = contactParams(a.E, a.D, a.unclamped);
  const std::vector<double> speeds = impactSpeeds(a.speeds);
  const Restitution R(p);

  // The second-order series is printed only where it applies (b < 0.1, i.e. 1 - e below ~0.11);
  // elsewhere the column holds nan.
  constexpr double SERIES_B_MAX = 0.1;
  PlacedTable out;
  KineticTable& t = out.table;
  addContactProvenance(t.provenance, p);
  t.provenance.add("tolerance", R.options().tolerance);
  t.provenance.add("columns",
                   std::string("v: impact speed; e = -xi'(end)/v; contact_time: xi > 0 "
                               "duration; release_time: clamped force "
                               "reaches 0 (= contact_time unclamped); max_overlap in d; b = D "
                               "m_eff^-0.4 E^-0.6 v^0.2 (e depends "
                               "on b only); e_series = 1 - C1 b + C2 b^2 where b < ") +
                       formatReal(SERIES_B_MAX) +
                       ", else nan; elastic_contact_time = 3.218065 (m_eff^2/(E^2 v))^0.2");
  t.columns = {"v",           "e", "contact_time", "release_time",
               "max_overlap", "b", "e_series",     "elastic_contact_time"};
  for (double v : speeds) {
    const CollisionResult r = R.collide(v);
    if (r.max_overlap > 1.0) {  // the centres would pass each other: not a contact any more
      char why[200];
      std::snprintf(why, sizeof why,
                    "v = %.4g: max_overlap %.3g > 1 d, the spheres would pass through each "
                    "other; the Hertz law does not describe such an impact",
                    v, r.max_overlap);
      t.comments.push_back(std::string("warning: ") + why);
      out.comment_rows.push_back(t.rows.size());
    }
    const double series =
        r.scaling_parameter < SERIES_B_MAX ? R.seriesRestitution(v) : std::nan("");
    t.rows.push_back({v, r.restitution, r.contact_time, r.release_time, r.max_overlap,
                      r.scaling_parameter, series, R.elasticContactTime(v)});
  }
  return out;
}

}  // namespace

KineticTable kineticTable(const RestitutionRequest& a) { return restitutionTable(a).table; }

KineticTable kineticTable(const HaffRequest& a) {
  require(a.eps >= 0.0 && a.eps <= 1.0,
          "--eps must lie in [0, 1] (got " + formatReal(a.eps) + ").");
  checkPhi(a.phi);
  require(a.T0 > 0.0 && std::isfinite(a.T0),
          "--T0 must be positive and finite (got " + formatReal(a.T0) + ").");
  const auto times = tableTimes(a.t_min, a.t_end, a.points);
  const double inv_tau0 = haffInverseTau0(a.eps, a.phi, a.T0);

  KineticTable t;
  common::Provenance& prov = t.provenance;
  prov.add("eps", a.eps);
  prov.add("phi", a.phi);
  prov.add("T0", a.T0);
  prov.add("omega0", enskogCollisionFrequency(a.phi, a.T0));
  prov.add("tau0", inv_tau0 > 0.0 ? 1.0 / inv_tau0 : std::numeric_limits<double>::infinity());
  prov.add("law",
           std::string("T = T0 / (1 + t/tau0)^2, 1/tau0 = (1 - eps^2) omega0 / 6 (Haff 1983)"));
  prov.add("units", std::string(UNITS));
  prov.add("columns", std::string("t: time; T: granular temperature; slope = d ln T / d ln t"));
  t.columns = {"t", "T", "slope"};
  for (double time : times) {
    const double slope = time > 0.0 ? -2.0 * time * inv_tau0 / (1.0 + time * inv_tau0) : 0.0;
    t.rows.push_back({time, haffTemperature(time, a.eps, a.phi, a.T0), slope});
  }
  return t;
}

KineticTable kineticTable(const CoolingRequest& a) {
  const ContactParams p = contactParams(a.E, a.D, a.unclamped);
  require(p.D > 0.0,
          "--D must be positive for viscoelastic cooling (got 0: the gas does not cool).");
  checkPhi(a.phi);
  const auto times = tableTimes(a.t_min, a.t_end, a.points);

  CoolingOptions o;
  o.phi = a.phi;
  const auto r = solveViscoelasticCooling(p, times, o);
  // Haff's law with the same initial cooling rate: 1 - eps_eff^2 = L(T0).
  const double loss0 = r.front().loss;
  const double eps_eff = std::sqrt(std::max(0.0, 1.0 - loss0));
  const double tau = viscoelasticCoolingTau0(p, a.phi, o.T0);

  KineticTable t;
  common::Provenance& prov = t.provenance;
  addContactProvenance(prov, p);
  prov.add("phi", a.phi);
  prov.add("T0", o.T0);
  prov.add("omega0", enskogCollisionFrequency(a.phi, o.T0));
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
  t.columns = {"t", "T", "slope", "loss", "T_haff", "T_asymptote", "T_small_damping"};
  for (const auto& s : r) {
    t.rows.push_back({s.t, s.T, s.slope, s.loss, haffTemperature(s.t, eps_eff, a.phi, o.T0),
                      s.t > 0.0 ? o.T0 * std::pow(s.t / tau, -5.0 / 3.0)
                                : std::numeric_limits<double>::infinity(),
                      viscoelasticCoolingTemperature(s.t, p, a.phi, o.T0)});
  }
  return t;
}

KineticTable kineticTable(const EnskogRequest& a) {
  checkPhi(a.phi);
  require(a.T >= 0.0 && std::isfinite(a.T),
          "--T must be non-negative and finite (got " + formatReal(a.T) + ").");
  KineticTable t;
  common::Provenance& prov = t.provenance;
  prov.add("phi", a.phi);
  prov.add("T", a.T);
  prov.add("units", std::string(UNITS));
  prov.add(
      "columns",
      std::string("n = 6 phi/pi (d^-3); g2 = (1 - phi/2)/(1 - phi)^3 (Carnahan-Starling); "
                  "omega = 4 sqrt(pi) n g2 sqrt(T/m): Enskog collision frequency per particle"));
  t.columns = {"phi", "T", "n", "g2", "omega"};
  t.rows.push_back({a.phi, a.T, numberDensity(a.phi), carnahanStarlingG2(a.phi),
                    enskogCollisionFrequency(a.phi, a.T)});
  return t;
}

KineticTable kineticTable(const ChargingRequest& c) {
  require(c.kappa >= 0.0 && std::isfinite(c.kappa),
          "--kappa must be non-negative and finite (got " + formatReal(c.kappa) + ").");
  require(c.cooling_exponent > 0.0 && std::isfinite(c.cooling_exponent),
          "--cooling-exponent must be positive and finite (got " + formatReal(c.cooling_exponent) +
              ").");
  KineticTable t;
  common::Provenance& prov = t.provenance;
  prov.add("kappa", c.kappa);
  prov.add("cooling_exponent", c.cooling_exponent);
  prov.add("law",
           std::string("d<|q|>/dt ~ T^(1/2) T^kappa with T ~ t^-a: exponent = -a (1/2 + kappa) "
                       "(docs/model.md section 8; -13/6 at kappa = 0.8, a = 5/3)"));
  t.columns = {"kappa", "cooling_exponent", "charging_rate_exponent"};
  t.rows.push_back(
      {c.kappa, c.cooling_exponent, chargingRateExponent(c.kappa, c.cooling_exponent)});
  return t;
}

void writeTable(const RestitutionRequest& a, const CsvTarget& target) {
  const PlacedTable t = restitutionTable(a);
  target.checkWritable();
  for (const std::string& c : t.table.comments)
    std::fprintf(stderr, "kinetic restitution: %s\n", c.c_str());
  writeKinetic(t.table, t.comment_rows, target);
}

void writeTable(const HaffRequest& a, const CsvTarget& target) {
  const KineticTable t = kineticTable(a);
  target.checkWritable();
  writeKinetic(t, {}, target);
}

void writeTable(const CoolingRequest& a, const CsvTarget& target) {
  const KineticTable t = kineticTable(a);
  target.checkWritable();
  writeKinetic(t, {}, target);
}

void writeTable(const EnskogRequest& a, const CsvTarget& target) {
  const KineticTable t = kineticTable(a);
  target.checkWritable();
  writeKinetic(t, {}, target);
}

void writeTable(const ChargingRequest& a, const CsvTarget& target) {
  const KineticTable t = kineticTable(a);
  target.checkWritable();
  writeKinetic(t, {}, target);
}

}  // namespace granagg::meanfield
