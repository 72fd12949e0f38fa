#pragma once
/// \file OutputReporters.h
/// The outputs of a run as reporters (md/run/Reporter.h), which md::Simulation owns and calls
/// before the user's: the trajectory (traj.h5: frames and observables on their schedule) and the
/// checkpoints (every output.checkpoint_interval steps, every output.checkpoint_wall_seconds
/// and at the end). OpenMM's split is the model: the engine (md::RunEngine) is the Context, and
/// every file a run writes comes from a reporter that looks at it between chunks of steps.
///
/// Ranks. Every rank holds both reporters and makes the same collective engine calls in the same
/// order (a frame is gathered on every rank); only the rank where RunEngine::writesFiles() holds
/// the H5MD writer and checks the file.
#include <sys/stat.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "md/config/MdConfig.h"
#include "md/engine/RunEngine.h"
#include "md/io/H5mdWriter.h"
#include "md/run/Reporter.h"

namespace granagg::md {

/// /parameters of a new trajectory: every configuration key, then what the run chose (version,
/// command, backend, the engine's parameters, dt and its reason, the Coulomb set-up).
std::vector<std::pair<std::string, std::string>> trajectoryParameters(
    const MdConfig& cfg, const RunEngine& engine, const std::string& command_line,
    const std::string& dt_reason);

/// traj.h5: the observables (with the step dt in force) every output.observable_interval steps
/// and at the run's last step, the frames at `frame_steps` (Simulation::frameSteps; with an
/// adaptive step, addFrameStep). With output.trajectory = false the frame steps still come and
/// go (frameStep(): for the in-situ analysis) but no frame is stored. Between chunks it checks that the file
/// is still the one it writes; after closing, that it reads back whole. A trajectory changed
/// behind the run's back (removed, replaced, truncated by another program; other granagg commands
/// are kept out by the folder lock) stops the run with std::runtime_error: a run never reports
/// success for a file it cannot vouch for.
class TrajectoryReporter : public Reporter {
 public:
  /// `next_frame`: the index into `frame_steps` of the next frame to write; `frames_written`:
  /// the frames the file already holds. No file is opened yet (create() or reopen()).
  TrajectoryReporter(RunEngine& engine, const MdConfig& cfg, std::filesystem::path file,
                     std::vector<std::int64_t> frame_steps, std::size_t next_frame,
                     std::size_t frames_written, std::int64_t last_step);

  /// A new file with /parameters, the configuration, and the observables and the frame at the
  /// engine's step (collective). `observables` are the engine's at that step.
  void create(const std::vector<std::pair<std::string, std::string>>& parameters,
              const std::string& config_toml, bool overwrite, const Observables& observables);
  /// Opens the file of a resumed run at the engine's step and records who continued it, from
  /// where, to where (/granagg/restarts).
  void reopen(double t_end, const std::string& command_line, const std::string& version);

  /// An adaptive step (Simulation): the frames and the last step become known epoch by epoch.
  /// `step` is after every frame step so far.
  void addFrameStep(std::int64_t step);
  void setLastStep(std::int64_t step) { m_last_step = step; }

  std::int64_t nextStep(const Simulation& sim) const override;
  /// At the observable steps (output.observable_interval) and the last step.
  bool needsObservables(const Simulation& sim) const override;
  /// Checks the file, then writes the observables and the frame that fall on this step.
  void report(const Simulation& sim) override;

  /// Checks the file (between chunks; the writing rank only).
  void check();
  void flush();
  /// Closes the file and, unless `verify` is false (a run that aborted), reads it back.
  void close(bool verify = true);

  /// Recorded by the checkpoint reporter: the message for a damaged file names it.
  void checkpointWritten(std::filesystem::path file, std::int64_t step);

  const std::filesystem::path& file() const { return m_file; }
  /// What reopen() repaired in the file ("" if nothing; H5mdWriter::repairNote).
  const std::string& repairNote() const { return m_repair_note; }
  std::size_t framesWritten() const;
  /// The step of the last frame time reached (stored or not); -1 before the first.
  std::int64_t frameStep() const { return m_frame_step; }

 private:
  [[noreturn]] void damaged(const std::string& what) const;
  void watch();
  void writeFrame();

  RunEngine& m_engine;
  const MdConfig& m_cfg;
  std::filesystem::path m_file;
  std::vector<std::int64_t> m_frame_steps;
  std::size_t m_next_frame;
  std::size_t m_frames_written;  // counted on every rank
  std::int64_t m_last_step;
  std::int64_t m_frame_step = -1;
  std::unique_ptr<H5mdWriter> m_writer;  // on the writing rank
  std::string m_repair_note;
  struct stat m_stat {};                 // the file as this run last left it
  std::filesystem::path m_checkpoint_file;
  std::int64_t m_checkpoint_step = -1;   // -1: none written by this process or found
};

/// Checkpoints every output.checkpoint_interval steps and whenever output.checkpoint_wall_seconds
/// have passed since the last (the ranks agree on the clock through RunEngine::anyRank), through
/// RunEngine::saveCheckpoint with the run's fields. The trajectory is flushed first, so that a
/// checkpoint never names frames the file does not hold.
class CheckpointReporter : public Reporter {
 public:
  /// `trajectory`: the run's trajectory (its counters go into the checkpoint). `last_step`: the
  /// step of the checkpoint the run continues (-1 for a new run).
  CheckpointReporter(RunEngine& engine, const MdConfig& cfg, std::filesystem::path folder,
                     TrajectoryReporter& trajectory, std::int64_t last_step);
  /// Called before every checkpoint with its step (Simulation: Reporter::beforeCheckpoint of
  /// every reporter), so that what is saved beside the checkpoint is saved first.
  void setBeforeSave(std::function<void(std::int64_t)> before) { m_before = std::move(before); }

  std::int64_t nextStep(const Simulation& sim) const override;
  /// Never: a checkpoint holds the state, not the observables.
  bool needsObservables(const Simulation&) const override { return false; }
  void report(const Simulation& sim) override;

  /// Writes a checkpoint now (collective).
  void save();
  /// The step of the last checkpoint written or continued, -1 for none.
  std::int64_t lastStep() const { return m_last_step; }

 private:
  using Clock = std::chrono::steady_clock;
  RunEngine& m_engine;
  const MdConfig& m_cfg;
  std::filesystem::path m_folder;
  TrajectoryReporter& m_trajectory;
  std::int64_t m_last_step;
  Clock::time_point m_last_time = Clock::now();
  std::function<void(std::int64_t)> m_before;
};

/// profile.csv: one row, seconds per phase of the loop (`other` = the loop's time in no phase:
/// observables, output, checkpoints; column names are the phase names in snake case), then the
/// list builds and slow Coulomb evaluations; the provenance holds box, dt, the end time and the
/// Coulomb set-up, so that benchmark scripts need not read the log.
void writeProfile(const RunEngine& engine, const std::filesystem::path& path,
                  const std::string& command_line, std::int64_t steps, double loop_seconds,
                  std::int64_t neighbor_builds, std::int64_t slow_evaluations);

}  // namespace granagg::md
