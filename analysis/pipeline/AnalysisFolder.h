#pragma once
/// \file AnalysisFolder.h
/// What `granagg analyze` writes (docs/analysis.md): one or several runs analysed as an ensemble
/// into a folder of CSV tables (ensemble tables at the top, per-run tables stacked in per_run/)
/// and analysis.h5, every file with the same provenance. A failure leaves nothing that would
/// block the rerun.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/pipeline/RunAnalyzer.h"
#include "common/Csv.h"

namespace granagg::analysis {

struct AnalysisFolderRequest {
  std::vector<std::string> runs;  ///< traj.h5 files, run folders or LAMMPS dumps
  std::string out;                ///< the folder
  bool force = false;             ///< overwrite files in an existing non-empty folder
  bool write_grid = false;        ///< stream every frame's grid occupancy into analysis.h5
  std::string command_line;       ///< for the provenance
  /// A run's result computed elsewhere (the in-situ analysis of a run that stored no frames:
  /// study/insitu's storedResult), or none: then its trajectory is analysed.
  std::function<std::optional<RunResult>(const std::string&)> stored_result;
};

struct AnalysisFolder {
  std::vector<RunResult> runs;
  std::vector<Table> ensemble;
};

/// Refuses (std::invalid_argument) a --out that is a file, or a non-empty folder without force;
/// a run given twice (an ensemble needs independent runs) or one that does not exist.
void checkAnalysisFolderRequest(const AnalysisFolderRequest& request);

/// Analyses the runs and writes the folder. `progress(run, frame, frame_count_hint)` is called
/// for every frame read. Runs of different systems (checkSameSystem) are refused before the rest
/// are analysed.
AnalysisFolder analyseIntoFolder(
    const AnalysisFolderRequest& request, const AnalysisOptions& options,
    const std::function<void(std::size_t, std::size_t, std::size_t)>& progress = {});

/// One run analysed elsewhere (during the run: study/insitu) written as `granagg analyze` writes
/// it: the same files, tables and columns in the folder `out`, which must not exist. It is
/// written as `out`.partial and renamed, so that a failure leaves no folder behind.
AnalysisFolder writeRunAnalysis(const std::string& out, RunResult result,
                                const AnalysisOptions& options, const std::string& command_line);

/// The provenance of every table: the command line, each run's source and grid, and every
/// option's value.
common::Provenance analysisProvenance(const std::string& command_line,
                                      const AnalysisOptions& options,
                                      const std::vector<RunResult>& runs);

/// The summary for the terminal, one line each (without a prefix).
std::vector<std::string> analysisReport(const AnalysisFolder& folder);

/// What a reader of the tables must be told even when the summary is not wanted, one line each
/// (without a prefix): a growth-exponent window holding too few frames for a fit (z is NaN), and
/// a trajectory that ends before the run.t_end in its /parameters (an unfinished run).
std::vector<std::string> analysisWarnings(const AnalysisFolder& folder,
                                          const AnalysisOptions& options);

}  // namespace granagg::analysis
