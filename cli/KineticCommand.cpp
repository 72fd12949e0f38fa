/// `granagg kinetic`: kinetic-theory references (meanfield/kinetic/KineticTables.h writes the
/// tables): viscoelastic restitution, Haff's law, viscoelastic cooling, Enskog collision
/// frequency, charging-rate exponent. This file wires the options.
#include <memory>
#include <string>

#include "cli/CliContext.h"
#include "meanfield/kinetic/KineticTables.h"

namespace granagg::cli {
namespace mf = granagg::meanfield;

namespace {

const char* const UNITS =
    "Reduced units: diameter d = 1, mass m = 1, initial temperature T0 = 1; speeds in sqrt(T0/m), "
    "times in "
    "sqrt(m d^2/T0).";

template <class Table>
void addContactOptions(CLI::App* cmd, Table& c) {
  cmd->add_option("--E", c.E,
                  "Elastic constant E of F = E xi^{3/2} + D xi^{1/2} xi' (> 0, reduced units)")
      ->capture_default_str();
  cmd->add_option("--D", c.D, "Dissipative constant D (>= 0, reduced units)")
      ->capture_default_str();
  cmd->add_flag("--unclamped", c.unclamped,
                "Keep the attractive force at the end of a contact (default: clamp F at 0, a "
                "contact never pulls)");
}

template <class Table>
void addTimeOptions(CLI::App* cmd, Table& t, const std::string& t_end_help) {
  cmd->add_option("--t-min", t.t_min, "First log-spaced output time after t = 0 (> 0)")
      ->capture_default_str();
  cmd->add_option("--t-end", t.t_end, t_end_help)->capture_default_str();
  cmd->add_option("--points", t.points, "Number of log-spaced output times (>= 2)")
      ->capture_default_str();
}

/// Adds -o/--force to `cmd` and makes it write `Table` when it runs.
template <class Table>
void writesTable(CLI::App* cmd, const std::shared_ptr<Table>& table, const CliContext& ctx) {
  auto target = std::make_shared<common::CsvTarget>();
  target->command_line = ctx.command_line;
  cmd->add_option("-o,--out", target->path, "Output CSV ('-' = standard output)")
      ->capture_default_str();
  cmd->add_flag("--force", target->force, "Overwrite an existing output file");
  cmd->callback([table, target]() { mf::writeTable(*table, *target); });
}

}  // namespace

void registerKineticCommand(CLI::App& app, const CliContext& ctx) {
  CLI::App* kin = app.add_subcommand(
      "kinetic", std::string("Kinetic-theory references: viscoelastic restitution e(v), Haff's "
                             "law, viscoelastic cooling, Enskog "
                             "collision frequency, charging-rate exponent. ") +
                     UNITS);
  kin->require_subcommand(1);

  auto ra = std::make_shared<mf::RestitutionRequest>();
  CLI::App* rest = kin->add_subcommand(
      "restitution",
      "Restitution coefficient e(v) and contact time of two viscoelastic spheres (m_eff = 1/2) by "
      "integrating "
      "m_eff xi'' = -(E xi^{3/2} + D xi^{1/2} xi') from xi = 0, xi' = v until xi = 0 again.");
  rest->add_option("--v", ra->speeds,
                   "Impact speeds (normal relative speed, sqrt(T0/m), > 0), comma separated")
      ->capture_default_str();
  addContactOptions(rest, *ra);
  writesTable(rest, ra, ctx);

  auto ha = std::make_shared<mf::HaffRequest>();
  CLI::App* haff = kin->add_subcommand("haff",
                                       "Haff's law T(t) = T0/(1 + t/tau0)^2, 1/tau0 = (1 - eps^2) "
                                       "omega0/6, for constant restitution eps.");
  haff->add_option("--eps", ha->eps, "Constant restitution coefficient, in [0, 1]")
      ->capture_default_str();
  haff->add_option("--phi", ha->phi, "Filling fraction, in (0, 0.74)")->capture_default_str();
  haff->add_option("--T0", ha->T0, "Initial temperature (units T0, > 0)")->capture_default_str();
  addTimeOptions(haff, *ha, "Last output time (> t-min)");
  writesTable(haff, ha, ctx);

  auto ca = std::make_shared<mf::CoolingRequest>();
  CLI::App* cool = kin->add_subcommand(
      "cooling",
      "Homogeneous cooling with the viscoelastic e(g): dT/dt = -(omega(T)/12) <g^2 (1 - e(g)^2)> "
      "over a Maxwellian "
      "(T0 = 1), beside Haff's law with the same initial rate and the t^{-5/3} asymptote.");
  addContactOptions(cool, *ca);
  cool->add_option("--phi", ca->phi, "Filling fraction, in (0, 0.74)")->capture_default_str();
  addTimeOptions(cool, *ca, "Last output time (> t-min); the t^{-5/3} regime needs t >> 1e6");
  writesTable(cool, ca, ctx);

  auto ea = std::make_shared<mf::EnskogRequest>();
  CLI::App* ensk = kin->add_subcommand("enskog",
                                       "Number density n, Carnahan-Starling g2 and Enskog "
                                       "collision frequency omega = 4 sqrt(pi) n g2 sqrt(T/m).");
  ensk->add_option("--phi", ea->phi, "Filling fraction, in (0, 0.74)")->capture_default_str();
  ensk->add_option("--T", ea->T, "Granular temperature (units T0, >= 0)")->capture_default_str();
  writesTable(ensk, ea, ctx);

  auto cha = std::make_shared<mf::ChargingRequest>();
  CLI::App* chg = kin->add_subcommand("charging",
                                      "Time exponent of the charging rate d<|q|>/dt ~ T^{1/2} "
                                      "T^kappa ~ t^{-a(1/2 + kappa)} for T ~ t^{-a}.");
  chg->add_option("--kappa", cha->kappa,
                  "Charging exponent kappa (>= 0; 0.83 for silica, Poppe et al. 2000)")
      ->capture_default_str();
  chg->add_option("--cooling-exponent", cha->cooling_exponent,
                  "a in T ~ t^{-a} (> 0; 5/3 viscoelastic, 2 Haff)")
      ->capture_default_str();
  writesTable(chg, cha, ctx);
}

}  // namespace granagg::cli
