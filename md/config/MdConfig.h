#pragma once
/// \file MdConfig.h
/// The resolved configuration of an MD run: what `granagg md --config run.toml` reads
/// (md/config/ConfigParser.h), what the engine is built from, and what is stored in every output
/// (/parameters of the H5MD file, provenance of tables). Defaults are the paper's values
/// (Singh & Mazza 2018; docs/model.md sections 2-7). Reduced units: d = m = T0 = 1.
///
/// TOML layout (every key optional except where noted; unknown keys are errors):
///
///     [input]       version = 1
///     [system]      N, phi, seed, temperature, initial ("random" or a CSV, H5MD or LAMMPS data
///                   file path), initial_max_overlap ("auto" or a number)
///     [contact]     model ("hertz" | "spring_dashpot"), E, D, clamp, stiffness, restitution
///     [integrator]  dt ("auto", "adaptive" or a number), steps_per_contact, impact_speed_max
///                   ("auto" or a number)
///     [neighbor]    skin
///     [charging]    mode ("exchange" | "fixed"), initial ("neutral" | "monopolar" | "bipolar" |
///                   "file"), q0, Q, kappa, psi1_min, psi1_max, psi2_fraction
///     [coulomb]     K, method ("pppm" | "ewald"), accuracy, r_cut, mesh, order ("auto" or
///                   numbers), every, every_max, skin, r_fast
///     [run]         t_end, max_overlap
///     [output]      frames_per_decade, frame_interval, observable_interval, checkpoint_interval,
///                   checkpoint_wall_seconds, write_velocities, write_forces, trajectory,
///                   analyze
///     [analysis]    the options of `granagg analyze` for the analysis during the run
///                   (output.analyze), under their names with '_' (grid_spacing, tolerance, ...;
///                   docs/config.md). md keeps them as TOML text and does not read them: the
///                   in-situ analysis (study/insitu) checks them before the first step.
#include <cmath>
#include <cstdint>
#include <map>
#include <string>

#include "md/neighbor/Skin.h"

namespace granagg::md {

struct SystemConfig {
  int N = 1000;              ///< number of particles (>= 2)
  double phi = 0.076;        ///< filling fraction N pi / (6 L^3), in (0, 0.6)
  std::uint64_t seed = 1;    ///< seeds positions, velocities and charging
  double temperature = 1.0;  ///< initial granular temperature T_g(0) (= T0 = 1 in reduced units)
  std::string initial = "random";  ///< "random", or a CSV / H5MD file with positions, velocities
  /// Deepest overlap 1 - r an initial file may hold (contacts of a running gas are physical);
  /// 0 = "auto": run.max_overlap, the overlap no step of a run exceeds.
  double initial_max_overlap = 0.0;
  /// The tolerance in force: initial_max_overlap, or max_overlap for "auto".
  double initialMaxOverlap(double max_overlap) const {
    return initial_max_overlap > 0.0 ? initial_max_overlap : max_overlap;
  }
};

struct ContactConfig {
  std::string model = "hertz";  ///< "hertz" (viscoelastic Hertz) or "spring_dashpot"
  double E = 278.6;             ///< Hertz elastic constant, F_el = E xi^{3/2} (>= 0)
  double D = 27.7;              ///< Hertz dissipative constant, F_diss = D xi^{1/2} xi' (>= 0)
  bool clamp = true;            ///< clamp the contact force at zero (never attractive)
  double stiffness = 2.0e4;     ///< spring-dashpot k_n, F = k_n xi + gamma xi' (> 0)
  double restitution = 0.9;     ///< spring-dashpot constant restitution epsilon in (0, 1]
};

struct IntegratorConfig {
  double dt = 0.0;                  ///< time step; 0 means "auto" (from the contact time)
  /// integrator.dt = "adaptive" (dt then 0): the step follows the cooling gas (md/engine/Engine.h,
  /// "Adaptive time step"); it starts at the "auto" step
  bool adaptive = false;
  double steps_per_contact = 50.0;  ///< auto dt = contact time of the fastest impact / this
  /// fastest expected impact speed for auto dt; 0 means "auto": the normal relative speed exceeded
  /// by a fraction 1e-6 of collisions in a Maxwellian gas at the initial temperature,
  /// sqrt(4 T ln 1e6) (collision-weighted P(g) = g/(2T) exp(-g^2/(4T))).
  double impact_speed_max = 0.0;
};

struct NeighborConfig {
  /// Verlet skin of the contact list; lists rebuilt when a particle moved skin/2. 0 = "auto": 0.3,
  /// except where the list carries the fast Coulomb pairs, whose skin follows the gas between
  /// 0.05 and 0.3 (md/neighbor/Skin.h)
  double skin = 0.0;
  /// The skin a list built now uses at most: the number, or 0.3 for "auto".
  double skinCap() const { return skin > 0.0 ? skin : NEIGHBOR_SKIN_AUTO_MAX; }
};

/// Collisional charging (docs/model.md section 7): at the first step of a contact, |dq| =
/// Q [Psi1 m_eff xi'^2]^(kappa + Psi2) moves from one partner to the other (sign + or - with
/// probability 1/2), Psi1 ~ U[psi1_min, psi1_max], Psi2 ~ U[-psi2_fraction kappa, +psi2_fraction
/// kappa].
struct ChargingConfig {
  std::string mode =
      "exchange";  ///< "exchange" (the paper's model) or "fixed" (charges never change)
  /// initial charges: "neutral" (all 0), "monopolar" (all +q0), "bipolar" (+q0 or -q0 at random,
  /// zero net charge for even N), "file" (from system.initial)
  std::string initial = "neutral";
  double q0 = 1.0;  ///< charge magnitude of monopolar / bipolar initial states
  /// charge scale of the exchange rule; the default suits K = 0 (charges exert no force there),
  /// with Coulomb forces see recommendedChargeScale
  double Q = 1.0;
  double kappa = 0.83;    ///< exponent (Poppe et al. 2000, silica)
  double psi1_min = 0.1;  ///< Psi1 range: U[0.1, 3.1623], mean 1.63
  double psi1_max = 3.1623;
  double psi2_fraction =
      0.05;  ///< Psi2 ~ U[-0.05 kappa, +0.05 kappa] (mean 0; docs/model.md section 9)
};

/// The charge scale Q recommended at Coulomb constant K > 0: 0.05 at K = 5, the largest value of
/// the validation study's Q scan at which K = 5 runs (Q = 0.1 collapses: docs/validation.md).
/// The gas depends on K and Q only through K Q^2 (docs/validation.md), so Q = 0.05 sqrt(5 / K)
/// at other K.
inline double recommendedChargeScale(double K) { return 0.05 * std::sqrt(5.0 / K); }

/// Coulomb interaction K q_i q_k / r^2 with all periodic images (Ewald, tinfoil boundary).
struct CoulombConfig {
  double K = 0.0;  ///< Coulomb constant l_B / d (paper: 0, 0.25, 1, 5); 0 switches Coulomb off
  std::string method =
      "pppm";  ///< "pppm" (particle-mesh Ewald, production) or "ewald" (plain, reference)
  double accuracy = 1e-4;  ///< requested relative RMS force accuracy (docs/coulomb.md)
  double r_cut = 0.0;      ///< real-space cutoff; 0 = "auto"
  int mesh = 0;            ///< mesh points per side (pppm); 0 = "auto"
  int order = 0;           ///< charge-assignment order 2..7 (pppm); 0 = "auto"
  /// Multiple time stepping (Engine.h): the slow Coulomb force is evaluated every this many steps
  /// and applied as an impulse; 1 = every step (plain velocity Verlet with the total force);
  /// 0 = "auto": every 0.016 time units (Engine::coulombEvery; 8 steps at dt = 0.002)
  int every = 0;
  /// The slow interval follows the gas, from every up to this many steps (Engine.h, "multiple
  /// time stepping"); <= every: fixed; 0 = "auto": 4 x every (docs/benchmarks-coulomb.md)
  int every_max = 0;
  /// Verlet skin of the real-space (PPPM) list; 0 = "auto": with every > 1 it follows the gas
  /// between 0.2 and 0.8 (md/neighbor/Skin.h); with every = 1 neighbor.skin's cap
  double skin = 0.0;
  double r_fast =
      0.0;  ///< every > 1: Coulomb pair force within this is fast (every step); 0 = "auto" (2)
};

struct RunConfig {
  double t_end = 100.0;  ///< simulated time to reach
  /// stop (keeping the last checkpoint) if an overlap exceeds this. The paper's soft contacts
  /// overlap a lot: an elastic Hertz impact at speed v reaches xi_max = (5 m_eff v^2 / (4
  /// E))^{2/5}, 0.13 at v = 1.6 and 0.41 at v = 7.4 (the 1e-6 tail of impacts at T = 1).
  double max_overlap = 0.6;
};

struct OutputConfig {
  int frames_per_decade = 10;              ///< log-spaced frames in time (0: none)
  double frame_interval = 0.0;             ///< linear frame spacing in time (0: none)
  int observable_interval = 100;           ///< steps between observable samples
  long checkpoint_interval = 0;            ///< steps between checkpoints (0: only at the end)
  double checkpoint_wall_seconds = 600.0;  ///< wall-clock seconds between checkpoints (0: off)
  bool write_velocities = true;
  bool write_forces =
      false;  ///< per-particle total forces in every frame (/particles/all/force), for checks
  /// particle frames in traj.h5 at the frame times; false: observables and checkpoints only (the
  /// frame times still drive the in-situ analysis)
  bool trajectory = true;
  /// analyse every frame during the run ([analysis]) into OUT/analysis (granagg md --analyze)
  bool analyze = false;
};

struct MdConfig {
  int input_version = 1;
  SystemConfig system;
  ContactConfig contact;
  IntegratorConfig integrator;
  NeighborConfig neighbor;
  ChargingConfig charging;
  CoulombConfig coulomb;
  RunConfig run;
  OutputConfig output;
  /// [analysis]: key -> its value as TOML text (2.0, "cic", [10.0, 100.0]), in key order. Opaque
  /// to md: carried through toToml and flatten so that a restart and /parameters keep it.
  std::map<std::string, std::string> analysis;
  /// Where each key the user gave was set: "section.key" -> "run.toml:3:1" or "--set
  /// system.N=4" (the parser fills it; keys left at their defaults are absent). Not a key itself:
  /// toToml and flatten leave it out. A file-given initial state refuses a system.N or system.phi
  /// set here that contradicts the file, and replaces them where they are defaults.
  std::map<std::string, std::string> origin;
};

}  // namespace granagg::md
