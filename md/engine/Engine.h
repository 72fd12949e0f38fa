#pragma once
/// \file Engine.h
/// The MD engine: N spheres of diameter 1 and mass 1 in a periodic cube, normal contact forces
/// (Hertz viscoelastic or spring-dashpot), velocity Verlet (docs/model.md sections 3-6).
///
/// One source for both backends: Engine::Impl (EngineImpl.h; defined in Engine.cpp,
/// EngineLists.cpp, EngineCheckpoint.cpp, EngineAbort.cpp, EngineCoulomb.cpp and
/// EngineTimeStep.cpp) holds the state in Thrust device vectors (structure of arrays) and loops
/// through Thrust algorithms whose functors call the HD physics of md/potentials/; its lists'
/// storage order and skins are tuned by a ListTuner (ListTuner.h). This header has no Thrust in
/// it (pimpl), so host-only code (CLI, I/O) can use it in a CUDA build too.
///
/// Storage: particles are kept sorted by cell for memory locality, re-sorted at every build of the
/// list built from cells (the contact list without Coulomb forces, the Coulomb list with them);
/// ParticleData::id maps slots back to particle ids, and frame(), forces() and error messages use
/// ids. Determinism: forces are gathered per particle over a neighbour row
/// sorted by particle id, so every sum runs in the same order whatever the thread count, the
/// storage order, the neighbour-list rebuild schedule, or a restart from a checkpoint: the same
/// build gives bit-identical trajectories.
///
/// Coulomb forces (coulomb.K > 0) are the slow force of an impulse multiple-time-step integrator
/// (r-RESPA; Tuckerman, Berne & Martyna, J. Chem. Phys. 97, 1990 (1992); Grubmueller et al., Mol.
/// Sim. 6, 121 (1991)): with k = coulomb.every, the slow Coulomb force F_C (mesh + the real space
/// beyond r_fast over a list of its own; plain Ewald: everything) is evaluated at every k-th step
/// and applied there as the impulse k dt F_C, split in velocity Verlet's two half kicks (plain
/// Ewald, the reference, has no split and is evaluated at every step whatever k). Contact
/// forces and the real space within r_fast (smoothly switched over [r_fast - 1, r_fast],
/// md/coulomb/RealSpace.h) act at every step, in one pass over the contact list.
/// This is time-reversible and symplectic like velocity Verlet itself, and its error is second
/// order in k dt for forces that vary slowly on that scale (the accuracy tests bound it; docs/
/// coulomb.md). k = 1 is plain velocity Verlet with the total force. Between evaluations the
/// integrator's velocities differ from the smooth trajectory's by (k/2 - j) dt F_C (j steps after
/// the evaluation); output uses the smooth ones (StateKind::Physical).
///
/// The slow interval can follow the gas (coulomb.every_max > k): at each evaluation the next
/// interval k' is chosen so that the fastest pair (relative speed at most 2 max|u|) moves no
/// further in it than a pair at integrator.impact_speed_max moves in k steps -- the displacement
/// per interval at which the fixed interval's accuracy was measured -- within [k, every_max]. A
/// cooling gas thus evaluates its slow part less and less often. The impulse at an evaluation is
/// then (k_before + k_after)/2 dt F_C: half closes the interval that ends, half opens the next
/// (Verlet-I with a varying outer step; both halves act at one instant, so the drift velocities
/// are exactly those of the split halves).
///
/// Adaptive time step (integrator.dt = "adaptive"; md::Simulation chooses when): the step may
/// change between run() calls. Velocity Verlet then closes the last step with dt_old / 2 and
/// opens the next with dt_new / 2. The slow Coulomb part keeps its schedule in time: its
/// interval bounds are the "auto" step's, in time units. A change is announced by the one before
/// (setTimeStep's next_change), no slow interval reaches past it, and so each change falls on an
/// evaluation (Impl::changeTimeStep): the impulse integrator with a varying outer step, as
/// above. The step and time of the last change are part of the state, so that
/// t = t_change + (step - step_change) dt carries no round-off accumulated over steps and a
/// checkpoint continues to the bit.
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "md/config/MdConfig.h"
#include "md/coulomb/CoulombDesign.h"
#include "md/engine/RunEngine.h"
#include "md/io/Checkpoint.h"
#include "md/io/Frame.h"

namespace granagg::md {

/// granagg's engine behind md::RunEngine (md/engine/RunEngine.h), on one process (OpenMP or
/// CUDA): writesFiles() and anyRank() keep their defaults.
class Engine : public RunEngine {
 public:
  /// Builds the engine from a validated configuration and an initial state (box L in initial.box).
  /// Throws std::invalid_argument for overlapping particles (naming the pair; a fresh initial state
  /// must have none -- pass allow_contacts = true to continue from a frame of a running gas, whose
  /// contacts are legitimate), wrong sizes, non-finite values, or a box too small for the neighbour
  /// cutoff.
  Engine(const MdConfig& config, const Frame& initial, bool allow_contacts = false);
  /// Continues a checkpoint (checkpoint()) bit for bit: the state, forces, collision counter,
  /// Coulomb parameters and multiple-time-step state it holds, under `config` (the run's own
  /// configuration, as stored with the checkpoint; run.t_end may differ). Throws
  /// std::invalid_argument if the checkpoint does not fit the configuration (its particles, its
  /// multiple-time-step state, or a time step other than the one it was written at).
  Engine(const MdConfig& config, const Checkpoint& checkpoint);
  ~Engine() override;
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  /// Advances `steps` velocity-Verlet steps. Throws RunAborted when a step fails its checks; the
  /// engine is then mid-step and must not be advanced further (a run restarts from its last
  /// checkpoint, as `granagg md` does).
  void run(std::int64_t steps) override;

  /// Host copy of the current state (wrapped positions, images, velocities, charges).
  Frame frame(StateKind kind = StateKind::Integrator) const override;
  /// Forces of the current state: the integrator's (a bit-for-bit restart needs them) or the
  /// physical ones (output).
  Forces forces(StateKind kind = StateKind::Integrator) const override;
  /// Everything the engine needs to continue bit for bit (Engine(config, checkpoint)): the
  /// integrator's state and forces, dt, the collision counter, the Coulomb parameters' design
  /// and the multiple-time-step state. The run's own fields (config_toml, seed, frame counters)
  /// are left for the caller (md/run/Simulation).
  Checkpoint checkpoint() const;
  /// checkpoint() with the run's fields of `run_fields` (config_toml, seed, frames_written),
  /// written atomically to checkpointPath(folder) = folder/checkpoint.h5
  /// (md::writeCheckpoint).
  void saveCheckpoint(const std::filesystem::path& folder, const RunFields& run_fields) override;
  Observables observables() const override;
  double dt() const override;
  std::int64_t step() const override;
  double time() const override;
  double box() const override;
  std::size_t size() const override;
  /// Number of neighbour-list builds so far (diagnostics).
  std::int64_t neighborBuilds() const override;
  /// Times the phases of every following step (md/engine/PhaseTimer.h; `granagg md --profile`).
  /// Changes no result; on the CUDA backend each phase then waits for the device.
  void enableProfile(bool on) override;
  /// Wall seconds per phase since profiling was enabled, in PhaseTimer's order (zeros if never).
  std::vector<std::pair<std::string, double>> phaseSeconds() const override;
  /// The Coulomb parameters in use, or null when coulomb.K = 0.
  const CoulombSetup* coulombSetup() const override;
  /// Steps from the last evaluation of the slow Coulomb part to the next (the interval in force;
  /// it changes only with coulomb.every_max); 0 without Coulomb.
  int slowInterval() const override;
  /// Evaluations of the slow Coulomb part so far in this process (0 without Coulomb).
  std::int64_t slowEvaluations() const override;
  /// Re-chooses the Coulomb parameters for sum_q2_design (a restart passes the stored value, so
  /// that it continues with the same parameters as the uninterrupted run). No-op without Coulomb.
  void useCoulombDesign(double sum_q2_design);
  /// OpenMP threads for the CPU backend (the OpenMP runtime reads OMP_NUM_THREADS only at start-up,
  /// so a command-line option must go through here); no-op on the CUDA backend.
  static void setThreads(int n);
  /// "OpenMP (2 threads)" or "CUDA (device name)": printed at start-up and stored in outputs.
  static std::string backendDescription();
  /// backendDescription().
  std::string description() const override;
  /// Steps between evaluations of the slow Coulomb part for a configuration and time step
  /// (coulomb.every, or "auto": every 0.016 time units; 1 for plain Ewald).
  static int coulombEvery(const MdConfig& config, double dt);
  /// The fastest impact the time step resolves (integrator.impact_speed_max, or "auto": exceeded
  /// by a fraction 1e-6 of collisions in a Maxwellian gas at the initial temperature).
  static double impactSpeedMax(const MdConfig& config);
  /// integrator.dt = "adaptive": the step that the gas as it is now needs (md/potentials/
  /// ImpactSpeed.h): the "auto" rule (steps_per_contact steps per contact of the fastest impact)
  /// at the larger of the tail speed of the current T_g and 1.25 times the fastest impact a listed
  /// pair can make, at most 10 "auto" steps; `reason` says which. Reads the state only.
  double adaptiveTimeStep(std::string* reason = nullptr) const override;
  /// Continues with step `dt` (between run() calls; Engine.h, "Adaptive time step") until the
  /// step `next_change`, where the next change will be (-1: not known; a change there is then
  /// not exact for the slow Coulomb part).
  void setTimeStep(double dt, std::int64_t next_change) override;
  bool adaptsTimeStep() const override { return true; }
  /// The time step chosen for a configuration (fixed, or auto from the contact time) and why.
  static double chooseTimeStep(const MdConfig& config, std::string* reason = nullptr);

 private:
  /// What else a bit-for-bit restart needs (checkpoint().engine): the multiple-time-step state
  /// (the Coulomb force of the last evaluation, its step and energy, the slow interval) and the
  /// resolved split.
  EngineState engineState() const;
  /// Restores a checkpointed state with its forces, collision counter and engineState() (same N):
  /// the second half of Engine(config, checkpoint).
  void restore(const Frame& state, const Forces& forces, std::int64_t collisions,
               const EngineState& engine_state);
  /// Skins of the current contact list and Coulomb (PPPM real-space) list, 0 for none; they
  /// follow the gas where neighbor.skin and coulomb.skin are "auto" (md/neighbor/Skin.h).
  /// For tests only, through their probe (tests/EngineProbe.h).
  double contactListSkin() const;
  double coulombListSkin() const;
  friend struct EngineProbe;

  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::md
