#include "md/lammps/LammpsInput.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "common/Csv.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"
#include "md/potentials/SpringDashpot.h"

namespace granagg::md::lammps {

namespace {

using common::formatReal;

/// The density that gives a unit sphere unit mass (LAMMPS computes 4/3 pi R^3 density).
constexpr double UNIT_DENSITY = 6.0 / M_PI;

[[noreturn]] void cannot(const std::string& key, const std::string& value,
                         const std::string& why) {
  throw std::invalid_argument(key + " = " + value + " cannot run on LAMMPS: " + why);
}

/// Inner steps per outer step: coulomb.every when set above 1 with Coulomb forces (rRESPA),
/// else 1 ("auto" keeps every force at every step on LAMMPS, the path the same-physics
/// ensembles validate).
int respaLoop(const MdConfig& c) {
  return c.coulomb.K > 0.0 && c.coulomb.every > 1 ? c.coulomb.every : 1;
}

/// LAMMPS's one neighbour skin. Under rRESPA LAMMPS checks the list only at outer steps, where a
/// particle at the fastest impact speed moves k dt instead of dt between checks: the skin grows
/// by twice the extra distance, 2 v_max (k - 1) dt, which keeps the margin of the checked-every-
/// step list (md/neighbor/Skin.h).
double lammpsSkin(const MdConfig& c, double dt) {
  const int k = respaLoop(c);
  return c.neighbor.skinCap() + 2.0 * Engine::impactSpeedMax(c) * (k - 1) * dt;
}

}  // namespace

void checkLammpsCanRun(const MdConfig& c) {
  if (c.output.analyze)
    cannot("output.analyze", "true",
           "the in-situ analysis runs in granagg md; analyse the run's traj.h5 with granagg "
           "analyze");
  if (c.integrator.adaptive)
    cannot("integrator.dt", "\"adaptive\"",
           "the adaptive step is granagg md's; use \"auto\" or a number");
  if (c.coulomb.K > 0.0) {
    const CoulombConfig& cc = c.coulomb;
    if (cc.method != "pppm")
      cannot("coulomb.method", "\"" + cc.method + "\"",
             "granagg-lammps runs LAMMPS's PPPM; use coulomb.method = \"pppm\"");
    if (cc.every_max > 1)
      cannot("coulomb.every_max", std::to_string(cc.every_max),
             "LAMMPS has no Coulomb interval that follows the gas; use 1 or \"auto\"");
    if (cc.r_fast > 0.0)
      cannot("coulomb.r_fast", formatReal(cc.r_fast),
             cc.every > 1 ? "LAMMPS's rRESPA splits the Coulomb force at the real-space cutoff "
                            "(pair forces every step, the PPPM mesh every coulomb.every steps); "
                            "use \"auto\""
                          : "granagg-lammps has no near/far split of the Coulomb force (every "
                            "force at every step); use \"auto\"");
    if (cc.skin > 0.0) {
      const double skin = lammpsSkin(c, Engine::chooseTimeStep(c));
      if (cc.skin != skin)
        cannot("coulomb.skin", formatReal(cc.skin),
               "LAMMPS has one neighbour skin for all lists, " + formatReal(skin) +
                   (respaLoop(c) > 1 ? " (neighbor.skin grown for rRESPA)" : " (neighbor.skin)") +
                   "; use \"auto\" or that value");
    }
  }
}

std::string LammpsInput::text(const std::string& header) const {
  std::string t = header;
  if (!t.empty() && t.back() != '\n') t += '\n';
  for (const auto& c : commands) t += c + '\n';
  t += "run " + std::to_string(steps) + '\n';
  return t;
}

namespace {

/// translateConfig and translateRestart: the particles come from `file` (a data file, or with
/// `restart` a restart file, whose settings are then left out).
LammpsInput translate(const MdConfig& c, std::size_t N, double L, double sum_q2_design,
                      const std::string& file, bool restart, bool record_collisions) {
  checkLammpsCanRun(c);
  if (file.find_first_of(" \t\n\"'") != std::string::npos)
    throw std::invalid_argument("--out: the output folder's path must not contain blanks or "
                                "quotes (LAMMPS reads it as a word): " + file);
  LammpsInput in;
  auto& cmd = in.commands;
  const double dt = Engine::chooseTimeStep(c, &in.dt_reason);
  const double skin = lammpsSkin(c, dt);
  in.respa_loop = respaLoop(c);

  if (!restart) {
    cmd.push_back("units lj");
    cmd.push_back("atom_style hybrid sphere charge");
    cmd.push_back("boundary p p p");
  }
  cmd.push_back("newton on");
  cmd.push_back("comm_modify vel yes");
  cmd.push_back((restart ? "read_restart " : "read_data ") + file);
  cmd.push_back("set group all mass 1.0");

  // contact model
  std::string gran;
  if (c.contact.model == "hertz") {
    in.pair_style = "gran/hertz/history";
    gran = in.pair_style + " " + formatReal(2.0 * c.contact.E) + " 0.0 " +
           formatReal(4.0 * c.contact.D) + " 0.0 0.0 0";
  } else if (c.contact.model == "spring_dashpot") {
    const SpringDashpot::Params p =
        SpringDashpot::makeParams(c.contact.stiffness, c.contact.restitution, c.contact.clamp);
    in.pair_style = "gran/hooke/history";
    gran = in.pair_style + " " + formatReal(p.k) + " 0.0 " + formatReal(p.gamma / 0.5) +
           " 0.0 0.0 0";
  } else {
    cannot("contact.model", "\"" + c.contact.model + "\"", "no LAMMPS pair style for it");
  }
  if (c.contact.clamp) gran += " limit_damping";

  in.coulomb = c.coulomb.K > 0.0;
  if (in.coulomb) {
    const CoulombDesign d = designCoulomb(c.coulomb, N, L, skin, 1, 1, sum_q2_design);
    in.coulomb_setup = d.setup;
    cmd.push_back("pair_style hybrid/overlay " + gran + " coul/long " + formatReal(d.pppm.r_cut));
    cmd.push_back("pair_coeff * * " + in.pair_style);
    cmd.push_back("pair_coeff * * coul/long");
    cmd.push_back("dielectric " + formatReal(1.0 / c.coulomb.K));
    // LAMMPS's accuracy is an absolute force (relative to two unit charges at unit distance,
    // without the dielectric) and granagg's is relative to K: a K
    cmd.push_back("kspace_style pppm " + formatReal(c.coulomb.accuracy * c.coulomb.K));
    const std::string m = std::to_string(d.pppm.mesh);
    cmd.push_back("kspace_modify gewald " + formatReal(d.pppm.alpha) + " mesh " + m + " " + m +
                  " " + m + " order " + std::to_string(d.pppm.order));
    std::ostringstream s;
    s << "coulomb: PPPM as granagg designs it for coulomb.accuracy = " << c.coulomb.accuracy
      << ": alpha = " << d.pppm.alpha << ", r_cut = " << d.pppm.r_cut << ", mesh " << d.pppm.mesh
      << "^3, order " << d.pppm.order << " (estimated relative error " << d.setup.estimated_error
      << ")";
    if (in.respa_loop > 1)
      s << "; rRESPA: pair forces (contacts, real-space Coulomb r < r_cut) at every inner step "
        << dt << ", the PPPM mesh force every " << in.respa_loop << " steps (outer step "
        << in.respa_loop * dt << "); neighbour skin " << skin << " = neighbor.skin + 2 v_max ("
        << in.respa_loop << " - 1) dt (LAMMPS checks the list at outer steps only)";
    else
      s << "; every force at every step (coulomb.every = 1)";
    in.notes.push_back(s.str());
  } else {
    cmd.push_back("pair_style " + gran);
    cmd.push_back("pair_coeff * *");
  }

  cmd.push_back("neighbor " + formatReal(skin) + " bin");
  cmd.push_back("neigh_modify delay 0 every 1 check yes");
  cmd.push_back("fix integrate all nve/sphere");
  {
    const ChargingConfig& q = c.charging;
    std::string fix = std::string("fix ") + CHARGING_FIX_ID + " all granagg/charging pair " +
                      in.pair_style + " seed " + std::to_string(c.system.seed) + " Q " +
                      formatReal(q.Q) + " kappa " + formatReal(q.kappa) + " psi1 " +
                      formatReal(q.psi1_min) + " " + formatReal(q.psi1_max) + " psi2 " +
                      formatReal(q.psi2_fraction * q.kappa) + " exchange " +
                      (q.mode == "exchange" ? "yes" : "no") + " max_overlap " +
                      formatReal(c.run.max_overlap);
    if (record_collisions) fix += " record yes";
    if (in.respa_loop > 1) fix += " respa " + std::to_string(in.respa_loop);
    cmd.push_back(fix);
  }
  // LAMMPS's timestep is the outer step: under rRESPA k inner steps of dt
  in.dt = in.respa_loop * dt;
  if (in.respa_loop > 1) {
    cmd.push_back("run_style respa 2 " + std::to_string(in.respa_loop) + " pair 1 kspace 2");
    in.dt_reason += "; rRESPA outer step " + std::to_string(in.respa_loop) + " x " +
                    formatReal(dt) + " = " + formatReal(in.dt);
  }
  in.steps = static_cast<std::int64_t>(std::llround(c.run.t_end / in.dt));
  cmd.push_back("timestep " + formatReal(in.dt));
  cmd.push_back("thermo_style custom step time temp pe");
  cmd.push_back("thermo_modify norm no");
  cmd.push_back("thermo " + std::to_string(std::max(1, c.output.observable_interval)));

  return in;
}

}  // namespace

LammpsInput translateConfig(const MdConfig& c, const Frame& state, const std::string& data_file,
                            bool record_collisions) {
  // as the engine: sum q^2 of the initial state, at least N (a gas that starts neutral charges)
  double sum_q2 = 0.0;
  for (double q : state.charge) sum_q2 += q * q;
  return translate(c, state.size(), state.box, std::max(sum_q2, static_cast<double>(state.size())),
                   data_file, /*restart=*/false, record_collisions);
}

LammpsInput translateRestart(const MdConfig& c, std::size_t N, double box, double sum_q2_design,
                             const std::string& restart_file, bool record_collisions) {
  return translate(c, N, box, sum_q2_design, restart_file, /*restart=*/true, record_collisions);
}

std::string lammpsDataText(const Frame& s) {
  std::ostringstream t;
  const std::string L = formatReal(s.box);
  t << "granagg initial state (atom_style hybrid sphere charge; id = particle index + 1)\n\n"
    << s.size() << " atoms\n1 atom types\n\n"
    << "0 " << L << " xlo xhi\n0 " << L << " ylo yhi\n0 " << L << " zlo zhi\n\n"
    << "Masses\n\n1 1\n\n"
    << "Atoms # hybrid\n\n";
  const std::string density = formatReal(UNIT_DENSITY);
  const bool images = s.ix.size() == s.size();
  for (std::size_t i = 0; i < s.size(); ++i) {
    t << i + 1 << " 1 " << formatReal(s.x[i]) << ' ' << formatReal(s.y[i]) << ' '
      << formatReal(s.z[i]) << " 1 " << density << ' '
      << formatReal(s.charge.empty() ? 0.0 : s.charge[i]);
    if (images) t << ' ' << s.ix[i] << ' ' << s.iy[i] << ' ' << s.iz[i];
    t << '\n';
  }
  t << "\nVelocities\n\n";
  for (std::size_t i = 0; i < s.size(); ++i)
    t << i + 1 << ' ' << formatReal(s.vx[i]) << ' ' << formatReal(s.vy[i]) << ' '
      << formatReal(s.vz[i]) << " 0 0 0\n";
  return t.str();
}

}  // namespace granagg::md::lammps
