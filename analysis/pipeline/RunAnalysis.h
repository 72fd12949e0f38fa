#pragma once
/// \file RunAnalysis.h
/// The analysis of one run, one frame at a time: what `granagg analyze` does with the frames of a
/// trajectory (analyzeRun reads them and hands them here) and what an MD run does with its own
/// frames while it runs (in-situ analysis, study/insitu/InSituAnalysis.h). Both run this code, so
/// that the in-situ tables are the offline ones, value for value.
///
///     RunAnalysis a(options, "RUN", "in-situ", parameters);
///     for (each frame f) a.add(f);         // the per-frame observables
///     RunResult r = a.finish();            // the fits and the tables in the order of the output
///
/// Between frames the whole state (the tables so far, the MSD origin and all-origins buffer, the
/// last frame's charge-speed scatter) can be written to an HDF5 file and read back (saveState,
/// restoreState), so that a run continued from a checkpoint ends with the tables of the run that
/// was never stopped.
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "analysis/io/Frame.h"
#include "analysis/pipeline/RunAnalyzer.h"

namespace granagg::analysis {

class RunAnalysis {
 public:
  /// `source` and `format` name the run in the result (a path; "h5md", "lammps-dump" or
  /// "in-situ"); `parameters` are its /parameters (kappa is read from charging.kappa there).
  /// Throws std::invalid_argument for bad options.
  RunAnalysis(const AnalysisOptions& options, std::string source, std::string format,
              std::map<std::string, std::string> parameters, RunCallbacks callbacks = {});
  RunAnalysis(RunAnalysis&&) noexcept;
  RunAnalysis& operator=(RunAnalysis&&) noexcept;
  ~RunAnalysis();

  /// Analyses one frame. Throws TrajectoryError (naming `source` and the frame) when its particle
  /// count differs from the first frame's or its time does not increase; the state is then as
  /// before the call.
  void add(const Frame& frame);
  /// Frames analysed so far.
  std::size_t frames() const;
  /// Time and step of the last frame analysed (NaN and -1 before the first).
  double lastTime() const;
  std::int64_t lastStep() const;

  /// Marks the result partial (a reader stopped at a bad frame, --allow-partial).
  void setPartial(const std::string& reason);
  /// The fits (growth exponents, onset, charging rate) and every table, in the order of the
  /// output. Throws std::invalid_argument when no frame was added. Call once.
  RunResult finish();

  /// Writes the state after the frames so far into a new HDF5 file `path` (replaced if it
  /// exists), with `tag` (the MD step it belongs to) as an attribute. Throws std::runtime_error
  /// when it cannot be written.
  void saveState(const std::string& path, std::int64_t tag) const;
  /// The tag of a state file; throws std::runtime_error for a file that is not one.
  static std::int64_t stateTag(const std::string& path);
  /// Replaces this analysis's state by the one in `path` (saved with the same options and
  /// source). Throws std::runtime_error for a file that is not a state, or one saved with other
  /// tables or columns; this analysis must then not be used further.
  void restoreState(const std::string& path);

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::analysis
