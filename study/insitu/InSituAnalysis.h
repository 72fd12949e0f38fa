#pragma once
/// \file InSituAnalysis.h
/// The analysis of a run while it runs (`granagg md --analyze`, output.analyze): at every frame
/// time of the run's schedule the engine's state goes, without a copy to disk, into the same
/// analysis/pipeline/RunAnalysis that `granagg analyze` runs over a trajectory; at the end the
/// fits and tables go into RUN/analysis, the files `granagg analyze RUN --out RUN/analysis` would
/// write. OpenMM's reporters and HOOMD-blue's analyzers are the model: the composition lives
/// above md/ and analysis/, which never include each other (docs/ARCHITECTURE.md).
///
/// Restart. Before every checkpoint the analysis state goes into RUN/analysis-state.h5, tagged
/// with the checkpoint's step; the one before is kept as RUN/analysis-state.prev.h5, so that a
/// kill between the state and the checkpoint still leaves a state that matches the checkpoint.
/// A continued run restores the state of its checkpoint's step; where none matches and traj.h5
/// holds the frames (output.trajectory), it rebuilds the state from them and says so.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "analysis/io/Frame.h"
#include "analysis/pipeline/RunAnalysis.h"
#include "md/config/MdConfig.h"
#include "md/io/Frame.h"
#include "md/run/Reporter.h"
#include "md/run/Simulation.h"

namespace granagg::insitu {

/// The keys of [analysis] (the options of `granagg analyze` that shape the analysis, with '_').
const std::vector<std::string>& analysisKeys();

/// The analysis options of `config`'s [analysis] table. Throws md::ConfigError (exit 2) naming
/// the key, where it was set and its allowed range, for an unknown key or a bad value: before
/// the run's first step.
analysis::AnalysisOptions analysisOptions(const md::MdConfig& config);

/// md's host state as a trajectory frame, the way traj.h5 stores it and `granagg analyze` reads
/// it back (md/io/H5mdWriter.cpp, common/H5mdReader.cpp): positions wrapped into [0, L) with the
/// crossings in the image counts, velocities, charges (zeros for a neutral gas), ids 0..N-1.
analysis::Frame trajectoryFrame(const md::Frame& frame, std::size_t index);

/// The result of a finished run that was analysed during the run and stored no frames
/// (output.trajectory = false): its analysis state at the last checkpoint, finished, for
/// `granagg analyze` and ensembles. Nothing (std::nullopt) for any other path: a trajectory, a
/// folder with frames, a run without output.analyze. Throws std::invalid_argument for such a run
/// whose state does not match its checkpoint.
std::optional<analysis::RunResult> storedResult(const std::string& run);

/// The reporter. Construct it after Simulation::start or resume and before run(); add it with
/// Simulation::addReporter. A new run analyses its frame at t = 0 at once.
class InSituAnalysis : public md::Reporter {
 public:
  /// `log` receives the one-line notes (a rebuilt state). Throws md::ConfigError for bad
  /// [analysis] options and std::runtime_error when a continued run has no state to continue.
  InSituAnalysis(const md::Simulation& sim, std::string command_line,
                 std::function<void(const std::string&)> log = {});
  ~InSituAnalysis() override;

  std::int64_t nextStep(const md::Simulation& sim) const override;
  /// Never: the analysis reads the frame, not the observables.
  bool needsObservables(const md::Simulation&) const override { return false; }
  void report(const md::Simulation& sim) override;
  void beforeCheckpoint(const md::Simulation& sim, std::int64_t step) override;

  /// After run() reached run.t_end: the fits and RUN/analysis (replacing the one of a shorter
  /// run that this one continued). Returns the folder.
  std::filesystem::path writeResults(const md::Simulation& sim);
  /// Frames analysed so far.
  std::size_t frames() const;

  static std::filesystem::path resultFolder(const std::filesystem::path& run) {
    return run / "analysis";
  }
  static std::filesystem::path stateFile(const std::filesystem::path& run) {
    return run / "analysis-state.h5";
  }
  static std::filesystem::path previousStateFile(const std::filesystem::path& run) {
    return run / "analysis-state.prev.h5";
  }
  /// Removes the analysis files of an earlier run in `run` (a run started over with --force).
  static void removeOutputs(const std::filesystem::path& run);

 private:
  void addCurrentFrame(const md::Simulation& sim);
  void resumeState(const md::Simulation& sim);

  analysis::AnalysisOptions m_options;
  std::string m_command_line;
  std::function<void(const std::string&)> m_log;
  std::unique_ptr<analysis::RunAnalysis> m_analysis;
  std::int64_t m_state_step = -1;  // the step of the last state saved or restored
};

}  // namespace granagg::insitu
