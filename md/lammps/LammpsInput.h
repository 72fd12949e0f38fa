#pragma once
/// \file LammpsInput.h
/// granagg's run configuration (md/config/MdConfig.h) as a LAMMPS input: what granagg-lammps
/// feeds to LAMMPS, logs, and stores as OUT/lammps.in. No LAMMPS or MPI here: a pure translation,
/// testable without either.
///
/// The model, key by key (docs/lammps.md has the table):
/// - Particles: unit spheres of unit mass, `atom_style hybrid sphere charge`, ids = granagg's
///   particle index + 1, read from a data file written from the initial state (as `granagg md`
///   builds it: md::prepareInitialState), then `set group all mass 1.0`
///   (the density 6/pi gives 1 only up to rounding). Periodic cube [0, L)^3 from the state.
/// - contact.model = "hertz": `pair_style gran/hertz/history kn 0 gamma_n 0 0 0 [limit_damping]`
///   with kn = 2E, gamma_n = 4D. LAMMPS's normal force is sqrt(xi R_i R_j/(R_i + R_j)) [kn xi +
///   m_eff gamma_n xi'] (src/GRANULAR/pair_gran_hertz_history.cpp), which for R = 1/2 and m = 1
///   (m_eff = 1/2) is (kn/2) xi^{3/2} + (gamma_n/4) xi^{1/2} xi' = E xi^{3/2} + D xi^{1/2} xi'.
///   "spring_dashpot": `gran/hooke/history` with kn = k_n, gamma_n = gamma_n / m_eff. No
///   tangential force (kt = gamma_t = xmu = 0, dampflag 0). contact.clamp = `limit_damping`.
/// - coulomb.K > 0: `pair_style hybrid/overlay` with `coul/long r_cut`, `dielectric 1/K` (so that
///   LAMMPS's q_i q_j / (dielectric r^2) is K q_i q_j / r^2 with granagg's charges unchanged),
///   `kspace_style pppm` with the splitting parameter, mesh and order that granagg's own design
///   chooses for coulomb.accuracy (md/coulomb/CoulombDesign.h; the same ik-differentiated PPPM
///   and error estimate as LAMMPS's), for sum q^2 = max(initial sum q^2, N) as the engine does:
///   LAMMPS cannot estimate them itself for a gas that starts neutral.
/// - Charging, collision count, run.max_overlap: `fix granagg/charging` (FixCharging.h).
/// - Integration: `fix nve/sphere`, `timestep` = Engine::chooseTimeStep, `comm_modify vel yes`,
///   `newton on`, neighbour skin neighbor.skin (auto: 0.3), checked every step.
/// - coulomb.every = k > 1 (Coulomb forces): `run_style respa 2 k pair 1 kspace 2`, LAMMPS's
///   impulse multiple time stepping split at r_cut: contacts and real-space Coulomb every step
///   dt, the PPPM mesh every k steps; `timestep` is the outer step k dt, the fix is told
///   `respa k`, and the skin grows to cover k steps between list checks (docs/lammps.md).
///   "auto" stays at every force at every step (run_style verlet).
///
/// What LAMMPS cannot honour is an error naming the key (checkLammpsCanRun); "auto" values that
/// select a granagg-only method resolve to what LAMMPS does, and the notes say so.
#include <cstdint>
#include <string>
#include <vector>

#include "md/config/MdConfig.h"
#include "md/coulomb/CoulombDesign.h"
#include "md/io/Frame.h"

namespace granagg::md::lammps {

/// The ID of the charging fix in the generated input.
inline constexpr const char* CHARGING_FIX_ID = "granagg";

/// A configuration translated for LAMMPS.
struct LammpsInput {
  std::vector<std::string> commands;  ///< everything before the run, in order
  double dt = 0.0;           ///< LAMMPS's timestep: the outer step respa_loop x granagg's dt
  int respa_loop = 1;        ///< inner steps per outer step (run_style respa; 1: verlet)
  std::string dt_reason;     ///< as Engine::chooseTimeStep says
  std::int64_t steps = 0;    ///< llround(run.t_end / dt), as granagg md (outer steps)
  std::string pair_style;    ///< the granular pair style (FixCharging's `pair`)
  bool coulomb = false;      ///< coulomb.K > 0
  CoulombSetup coulomb_setup;  ///< coulomb: what granagg's design chose
  /// How keys were resolved for LAMMPS (log lines).
  std::vector<std::string> notes;

  /// The complete input: `header` (comment lines), the commands, `run steps`.
  std::string text(const std::string& header) const;
};

/// Throws std::invalid_argument naming the first key whose value LAMMPS cannot honour (a
/// method only granagg has, set explicitly): coulomb.every_max > 1, coulomb.r_fast,
/// coulomb.skin other than LAMMPS's neighbour skin, coulomb.method = "ewald".
void checkLammpsCanRun(const MdConfig& config);

/// The input for `config` from `state` (as md::prepareInitialState gives it), stored as the data
/// file `data_file`. record_collisions: the fix keeps every collision (FixCharging `record yes`).
/// Throws std::invalid_argument like checkLammpsCanRun (which it calls).
LammpsInput translateConfig(const MdConfig& config, const Frame& state,
                            const std::string& data_file, bool record_collisions = false);

/// The input that continues a run of `config` from the LAMMPS restart file `restart_file`: the
/// commands of translateConfig for that run, with `read_restart` for `read_data` and without
/// what the restart file sets (units, atom_style, boundary). The run had N particles in a box of
/// edge `box`, and its Coulomb parameters were designed for `sum_q2_design`
/// (CoulombSetup::sum_q2_design; unused without Coulomb), so that they come out the same.
LammpsInput translateRestart(const MdConfig& config, std::size_t N, double box,
                             double sum_q2_design, const std::string& restart_file,
                             bool record_collisions);

/// The LAMMPS data file of `state` (atom_style hybrid sphere charge): box [0, L)^3, atom i has
/// id i + 1, type 1, diameter 1, density 6/pi, charge, image flags; velocities (angular 0).
/// Reals with round-trip precision. md::readInitialState reads it back exactly.
std::string lammpsDataText(const Frame& state);

}  // namespace granagg::md::lammps
