#pragma once
/// \file RunEngine.h
/// What a run needs of an engine (docs/ARCHITECTURE.md): the interface through which
/// md::Simulation (md/run/Simulation.h) drives granagg's own md::Engine or LAMMPS
/// (md::lammps::LammpsEngine, md/lammps/LammpsEngine.h). OpenMM's split is the model: the
/// engine is the Context (state, forces, time stepping), the Simulation with its reporters owns
/// the schedule and the outputs (trajectory, observables, checkpoints, progress).
///
/// Ranks. An engine may be distributed over MPI ranks; this header has no MPI in it (granagg_md
/// stays free of MPI) and only says what every rank must do. Every rank runs the same
/// Simulation; the collective calls -- run(), frame(), forces(), observables(),
/// saveCheckpoint(), anyRank() and begin() -- are made on every rank in the same order.
/// writesFiles() is true on the one rank that writes the output folder (rank 0; always true
/// without MPI): there frame() and forces() hold every particle, elsewhere they are empty.
/// Everything else (step, time, dt, box, size, the diagnostics) is the same on every rank.
///
/// Cost. Simulation calls these between chunks of steps; an engine's hot loops are inside
/// run(), so the virtual calls cost nothing measurable.
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "md/coulomb/CoulombDesign.h"
#include "md/io/Checkpoint.h"
#include "md/io/Frame.h"

namespace granagg::md {

/// Observables at one step (docs/model.md section 10, "Per frame"). Energies are totals (not per
/// particle).
struct Observables {
  std::int64_t step = 0;
  double time = 0.0;
  double temperature = 0.0;        ///< T_g = (1/3N) sum (v - <v>)^2
  double kinetic_energy = 0.0;     ///< (1/2) sum v^2
  double elastic_energy = 0.0;     ///< sum over contacts of the elastic energy
  double momentum[3] = {0, 0, 0};  ///< sum v
  double momentum_abs_sum = 0.0;   ///< sum |v| (scale for momentum conservation)
  double contacts_per_particle = 0.0;
  std::int64_t collisions = 0;  ///< new contacts since the start of the run
  double mean_overlap = 0.0;    ///< over pairs in contact (0 if none)
  double max_overlap = 0.0;
  double total_charge = 0.0;     ///< sum q (conserved by the exchange rule)
  double mean_abs_charge = 0.0;  ///< (1/N) sum |q|, the paper's q-bar
  double max_abs_charge = 0.0;
  double coulomb_energy =
      0.0;  ///< Ewald total (real + mesh/reciprocal + self + background); 0 without Coulomb
};

/// Which velocities and forces a host copy holds. They differ only with Coulomb forces on a
/// multiple-time-step schedule (coulomb.every = k > 1; see md::Engine), and there only between
/// Coulomb evaluations.
enum class StateKind {
  /// The integrator's state: what a checkpoint stores. Velocities v(t) = u + (dt/2) f(t); forces
  /// f(t) = contact + w Coulomb with the impulse weight w (k at an evaluation step, 0 between).
  Integrator,
  /// For output and observables: the velocities of the smooth trajectory that the impulses
  /// approximate, v - (k/2 - j) dt F_C at j = 1..k-1 steps after an evaluation, and forces
  /// contact + F_C (F_C from the last evaluation).
  Physical,
};

/// Thrown when a run must stop (NaN, overlap beyond the bound); the message names the step and the
/// particles (and, for a Coulomb collapse, the criterion). The last checkpoint is the good state.
class RunAborted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class RunEngine {
 public:
  virtual ~RunEngine() = default;

  /// Advances `steps` time steps (collective). May throw RunAborted.
  virtual void run(std::int64_t steps) = 0;
  virtual std::int64_t step() const = 0;
  virtual double time() const = 0;
  virtual double dt() const = 0;
  /// Why dt is what it is, where the engine says more than Engine::chooseTimeStep (empty: that).
  virtual std::string dtReason() const { return {}; }
  /// integrator.dt = "adaptive" (md::Engine): whether this engine can change its step between
  /// chunks; the step the gas needs now (`reason` says why); and the change itself (between
  /// run() calls), in force until the step `next_change` where the next change will be.
  /// md::Simulation refuses the setting for an engine that cannot.
  virtual bool adaptsTimeStep() const { return false; }
  virtual double adaptiveTimeStep(std::string* /*reason*/ = nullptr) const { return dt(); }
  virtual void setTimeStep(double /*dt*/, std::int64_t /*next_change*/) {
    throw std::logic_error("this engine cannot change its time step");
  }
  /// The edge L of the periodic cube.
  virtual double box() const = 0;
  /// The number of particles N (on every rank).
  virtual std::size_t size() const = 0;

  /// The state in particle-id order: wrapped positions with image counts, velocities, charges
  /// (collective; every particle on the writing rank, none elsewhere).
  virtual Frame frame(StateKind kind = StateKind::Integrator) const = 0;
  /// The forces, in id order (collective; empty where !writesFiles()).
  virtual Forces forces(StateKind kind = StateKind::Integrator) const = 0;
  /// The observables of the current state (collective; the same on every rank).
  virtual Observables observables() const = 0;
  /// The Coulomb parameters in use, or null without Coulomb forces.
  virtual const CoulombSetup* coulombSetup() const { return nullptr; }

  /// Diagnostics for the log and profile.csv (md/run/RunLog.h); neutral where an engine has none.
  virtual std::int64_t neighborBuilds() const { return 0; }
  virtual std::int64_t slowEvaluations() const { return 0; }
  virtual int slowInterval() const { return 0; }
  virtual void enableProfile(bool) {}
  virtual std::vector<std::pair<std::string, double>> phaseSeconds() const { return {}; }

  /// The backend line ("OpenMP (2 threads)", "LAMMPS 29 Sep 2021 on 4 MPI ranks"): printed at
  /// start-up and stored in /parameters as `backend`.
  virtual std::string description() const = 0;
  /// What else a new trajectory's /parameters records about the engine (after `backend`).
  virtual std::vector<std::pair<std::string, std::string>> parameters() const { return {}; }

  /// True on the rank that writes the output folder (rank 0 under MPI).
  virtual bool writesFiles() const { return true; }
  /// `local` OR-ed over the ranks (collective), so that every rank takes the same branch (a stop
  /// signal caught by one rank stops all at the same chunk boundary). Without MPI: `local`.
  virtual bool anyRank(bool local) const { return local; }

  /// Called once on every rank when the writing rank holds the output folder `folder` (checked
  /// and locked), before the first frame or step: an engine that writes files of its own into
  /// the folder (LAMMPS's input and log) starts them here. Collective.
  virtual void begin(const std::filesystem::path& /*folder*/) {}

  /// The file whose presence marks a checkpoint in `folder` (the one `--restart` reads).
  virtual std::filesystem::path checkpointPath(const std::filesystem::path& folder) const {
    return folder / "checkpoint.h5";
  }
  /// Writes the checkpoint of the current state into `folder`, atomically, with the run's own
  /// fields (`run_fields`: config_toml, seed, frames_written). Collective; the files are
  /// written by the writing rank. Not const: LAMMPS's write_restart migrates atoms between
  /// ranks (the state's values do not change).
  virtual void saveCheckpoint(const std::filesystem::path& folder,
                              const RunFields& run_fields) = 0;
};

}  // namespace granagg::md
