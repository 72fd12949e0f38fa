#pragma once
/// \file Simulation.h
/// A restartable MD run: an engine plus its output folder (docs/ARCHITECTURE.md), the frame and
/// observable schedule and the checkpoints. `granagg md` is option wiring around this class; so are
/// `granagg-lammps` and any other driver (a test, a study). Modelled on OpenMM's Simulation: the
/// run owns the engine and its outputs, and reporters look at it between chunks of steps. The
/// engine is anything behind md::RunEngine (md/engine/RunEngine.h): granagg's md::Engine, which
/// start() and resume() build, or one the caller builds (LAMMPS across MPI ranks,
/// md/lammps/LammpsEngine.h).
///
/// Ranks. Under MPI every rank runs the same Simulation and makes the engine's collective calls in
/// the same order; only the rank where RunEngine::writesFiles() holds the folder lock, the
/// trajectory and the profile, and checks the trajectory between chunks. Checks that only the
/// writing rank can make (the folder) are agreed on through RunEngine::anyRank, so that every rank
/// throws the same kind of error; RunOptions::stop is OR-ed over the ranks.
///
/// Output folder:
///     traj.h5        H5MD trajectory: frames (log- and/or linearly spaced), observables every
///                    output.observable_interval steps and at the end, /parameters (provenance)
///     checkpoint.h5  the state to continue from bit for bit (md/io/Checkpoint.h), written every
///                    output.checkpoint_interval steps and/or output.checkpoint_wall_seconds, and
///                    at the end of run() (another engine writes its own checkpoint files:
///                    RunEngine::saveCheckpoint, checkpointPath)
///     profile.csv    with RunOptions::profile: wall seconds per phase of the loop
///     .granagg.lock  while start() or resume() writes the folder (common/FolderLock.h): a second
///                    command into the same folder is refused, naming this one
///
/// Determinism: a run of md::Engine resumed from any of its checkpoints writes the same frames,
/// observables and final state, to the bit, as the uninterrupted run (same build; any thread
/// count). Another engine's restart may be close without being exact (LAMMPS: docs/lammps.md).
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "md/config/MdConfig.h"
#include "md/engine/Engine.h"
#include "md/engine/RunEngine.h"
#include "md/run/Reporter.h"

namespace granagg::md {

/// How a run is started or resumed.
struct RunOptions {
  std::string command_line;  ///< provenance: stored in /parameters of a new trajectory
  /// start(): replace the files of a non-empty output folder; start() and resume(): clear a
  /// stale folder lock (a run that was killed). A folder held by a live process is never taken.
  bool overwrite = false;
  bool profile = false;      ///< time the loop by phase and write profile.csv (no result changes)
  /// When it points at a nonzero value (a signal handler sets it), run() stops after the chunk of
  /// steps in progress, writes a checkpoint and returns with RunSummary::stopped. Under MPI a
  /// signal caught by any rank stops every rank at the same chunk boundary.
  const volatile std::sig_atomic_t* stop = nullptr;
};

/// What run() did, for the log.
struct RunSummary {
  std::int64_t steps = 0;             ///< steps taken by this run() (not since t = 0)
  double loop_seconds = 0.0;          ///< wall time of the loop, output included
  std::int64_t neighbor_builds = 0;   ///< contact-list builds in this run()
  std::int64_t slow_evaluations = 0;  ///< evaluations of the slow Coulomb part in this run()
  bool stopped = false;  ///< ended early by RunOptions::stop (checkpoint written; resume() goes on)
  Observables observables;  ///< of the state run() ended in (the same on every rank)
};

/// Builds the engine that continues a checkpoint under the run's configuration (resume()).
using EngineFromCheckpoint = std::function<std::unique_ptr<RunEngine>(const MdConfig&)>;

class Simulation {
 public:
  /// A new run of `config` (validated here) into the folder `out`, from its initial state
  /// (system.initial: random, or a CSV / H5MD file, with charges from charging.initial). Creates
  /// and locks `out`; throws std::invalid_argument, before writing anything, for a bad
  /// configuration or initial state, for a non-empty `out` without RunOptions::overwrite and for
  /// an `out` that another process holds. Writes the trajectory's header and the frame and
  /// observables at t = 0; a failure there removes a folder it created.
  static Simulation start(const MdConfig& config, const std::filesystem::path& out,
                          const RunOptions& options);
  /// As above with an engine the caller built from `config` and its initial state (collectively,
  /// on every rank: LAMMPS). The folder is checked and locked on the writing rank; then
  /// RunEngine::begin(out) lets the engine write its own files, and the frame and observables at
  /// its first step are written.
  static Simulation start(const MdConfig& config, std::unique_ptr<RunEngine> engine,
                          const std::filesystem::path& out, const RunOptions& options);
  /// Continues the run in `out` from its checkpoint.h5, with the configuration stored there.
  /// `overrides` ("key=value", as --set) may only set run.t_end, to run further; the trajectory
  /// then records the continuation (/granagg/restarts, H5mdWriter::recordRestart). Throws
  /// std::invalid_argument, before writing anything, for another key, a bad value, a run.t_end
  /// before the checkpoint or a missing checkpoint, and std::runtime_error for an unreadable one.
  /// A run already at its run.t_end resumes with nothing to do (finished()) and touches nothing;
  /// any other locks the folder as start() does.
  static Simulation resume(const std::filesystem::path& out,
                           const std::vector<std::string>& overrides, const RunOptions& options);
  /// As above for a checkpoint of another engine, which the caller has read: `run_fields` holds
  /// the run's fields stored with it (config_toml, frames_written; `config_source` names it in
  /// messages) and `continue_engine` builds the engine from it under the run's configuration
  /// (collectively, on every rank). After the folder is locked, RunEngine::begin(out).
  static Simulation resume(const std::filesystem::path& out,
                           const std::vector<std::string>& overrides, const RunOptions& options,
                           const RunFields& run_fields, const std::string& config_source,
                           const EngineFromCheckpoint& continue_engine);

  Simulation(Simulation&&) noexcept;
  Simulation& operator=(Simulation&&) noexcept;
  ~Simulation();

  /// Adds a reporter (called in the order added).
  void addReporter(std::shared_ptr<Reporter> reporter);

  /// Runs to run.t_end: advances the engine in chunks, writes observables, frames and
  /// checkpoints on their schedule and a final checkpoint, and closes the trajectory. With
  /// RunOptions::stop set it ends early the same way, at the end of a chunk. Throws
  /// RunAborted when the engine stops (NaN, deep overlap); the message then says where the
  /// trajectory ends and which checkpoint is the last good state. Throws std::runtime_error when
  /// the trajectory was changed behind the run's back (removed, replaced or truncated between
  /// chunks, or unreadable after closing): such a run never ends as a success.
  RunSummary run();

  /// Writes checkpoint.h5 now (atomically; the trajectory is flushed first). Collective.
  void writeCheckpoint();

  const RunEngine& engine() const;
  const MdConfig& config() const;
  const std::filesystem::path& folder() const;
  std::filesystem::path trajectoryPath() const;
  std::filesystem::path checkpointPath() const;
  /// Why dt is what it is ("auto: elastic Hertz contact time ..." or "fixed").
  const std::string& dtReason() const;
  /// The step at which the run ends (run.t_end / dt, rounded); with an adaptive step, known
  /// only once the last epoch is planned (-1 before).
  std::int64_t lastStep() const;
  /// True if this Simulation continues a checkpoint.
  bool resumed() const;
  /// The stale folder lock that RunOptions::overwrite cleared ("" if none), for the log.
  const std::string& clearedStaleLock() const;
  /// What a resumed run repaired in traj.h5 ("" if nothing), for the log: the write that a
  /// killed run left unfinished, rolled back to its last complete frame (common/H5Journal.h).
  const std::string& trajectoryRepair() const;
  /// True if it was resumed at its run.t_end: run() has nothing to do and opens no file.
  bool finished() const;
  /// Frames in the trajectory so far.
  std::size_t framesWritten() const;
  /// The step of the last frame time the run reached (output.frames_per_decade,
  /// output.frame_interval and the last step), whether traj.h5 stored the frame
  /// (output.trajectory) or not; -1 before the first. A reporter sees a frame time when this
  /// equals engine().step().
  std::int64_t frameStep() const;
  /// The observables at the end of the last chunk of run() where some reporter needed them
  /// (Reporter::needsObservables; what reporters should read: the engine's observables() may
  /// evaluate the Coulomb energy afresh); zeros before the first. A reporter that said yes for
  /// the present step reads this step's.
  const Observables& lastObservables() const;

  /// Steps at which frames are written for `config` and `dt` up to `last`: t = 0, log-spaced
  /// (output.frames_per_decade from t = 0.01, or from dt if larger), linear
  /// (output.frame_interval) and `last`.
  static std::vector<std::int64_t> frameSteps(const MdConfig& config, double dt, std::int64_t last);

 private:
  struct Impl;
  explicit Simulation(std::unique_ptr<Impl> impl);
  /// start()'s first part: the configuration validated and its schedule checked, no engine yet.
  static std::unique_ptr<Impl> checkedRun(const MdConfig& config,
                                          const std::filesystem::path& out,
                                          const RunOptions& options);
  /// start()'s second half, once the engine is set up: lock, begin(), the header and t = 0.
  static Simulation startWriting(std::unique_ptr<Impl> d);
  /// resume()'s common part; `folder_checked`: FolderLock::checkAvailable was called already.
  static Simulation resumeWith(const std::filesystem::path& out,
                               const std::vector<std::string>& overrides, const RunOptions& options,
                               const RunFields& run_fields, const std::string& config_source,
                               const EngineFromCheckpoint& continue_engine, bool folder_checked);
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::md
