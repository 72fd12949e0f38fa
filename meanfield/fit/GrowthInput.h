#pragma once
/// \file GrowthInput.h
/// S(t) for the beta fit, read from what `granagg analyze` writes (docs/fit-beta.md, "Input"): an
/// analyze output folder (S_t.csv and per_run/S_t.csv), its analysis.h5 (/ensemble/S_t and
/// /runs/<k>/S_t), or any CSV with a t column and S column(s): one series, run columns sharing a
/// prefix, or a long table with a leading `run` column. Files are the contract with analysis/
/// (docs/ARCHITECTURE.md): nothing of analysis/ is included.
#include <string>
#include <vector>

namespace granagg::meanfield {

/// S(t) as read: times, one or several runs (or one series), what was read and notes.
struct GrowthInput {
  std::string source;  ///< the file (and group) read, quoted for messages
  std::string column;  ///< the S column used
  std::vector<double> t;
  std::vector<std::vector<double>> runs;  ///< one entry: a single series
  std::vector<std::string> notes;         ///< what was done to the data, for the report
};

/// Reads S(t) from `input` (folder, analysis.h5 or CSV; told by content). `column` "" takes the
/// default: S_grid_mean, else S_grid, else S, else the only column besides t (and run); a name
/// that matches no column but prefixes several takes them as runs. For an ensemble mean column
/// (*_mean) with per-run tables of 2 or more runs, the runs are read (times matched to 9 digits)
/// so that intervals can be formed over them. Throws std::invalid_argument naming INPUT and the
/// column for a missing file, a missing column or an ambiguous choice.
GrowthInput readGrowthInput(const std::string& input, const std::string& column);

/// Drops the rows with t = 0 (fits are in log t) and the rows where S is NaN in the series or in
/// any run (`granagg analyze` writes NaN where a frame has no cluster), with a note for each that
/// names the runs and times; throws std::invalid_argument for a negative or non-finite t.
/// Infinite or non-positive S stays, for validateGrowthData to reject. Returns the notes added
/// ("; "-joined, "" when nothing was dropped): why rows are missing, for a too-few-rows error.
std::string dropUnusableRows(GrowthInput& input);

}  // namespace granagg::meanfield
