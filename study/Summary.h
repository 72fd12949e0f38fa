#pragma once
/// \file Summary.h
/// What a paired study found, in words a newcomer can act on (docs/pair.md, "Summary"): per
/// ensemble the growth of S(t), its onset and regime, the local slope, and one growth exponent z
/// or the reason there is none; then the validation study's result for the same K. PairStudy
/// writes it as DIR/summary.txt beside summary.json and prints it at the end of a study.
///
/// A growth exponent is reported only where it is one: S(t) in a scaling regime (a flat local
/// slope) and an interval that excludes zero. Everything else is said in words ("no power law
/// (local slope rising)", "not resolved with 3 runs"), so that no fitted number is read as a
/// result it is not. The numbers behind every line stay in summary.json.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "study/PairStudy.h"

namespace granagg::study {

/// The local slope z(t) = d ln S / d ln t over the last half decade of a run,
/// [t_last / sqrt(10), t_last]: the stretch on which the growth regime is judged
/// (classifyGrowth, docs/analysis.md).
struct SlopeTrend {
  std::size_t n = 0;               ///< finite local slopes in the stretch
  double t0 = NAN, t1 = NAN;       ///< first and last time with a finite local slope
  double first = NAN, last = NAN;  ///< the local slope at t0 and t1
  double min = NAN, max = NAN;
  /// "flat" (max - min within the tolerance of the mean), "rising" or "falling" (the
  /// least-squares change of z over the stretch is at least half of max - min, up or down),
  /// "varying" (neither), or "" with fewer than 3 local slopes.
  std::string direction;
};

/// The trend of z(t) (samples in increasing t; NaN slopes skipped) over the last half decade
/// before the last time with a finite S. flat_tolerance: relative spread (max - min) / |mean|
/// that counts as flat (StudyServices::flat_slope_tolerance).
SlopeTrend slopeTrend(const std::vector<double>& t, const std::vector<double>& S,
                      const std::vector<double>& z, double flat_tolerance);

/// One ensemble's numbers as the study's steps wrote them (NaN where a table is missing).
struct EnsembleResult {
  double K = 0;
  /// analyze (fits.csv): z of S_grid over its window (default: the last decade), 95 % interval
  double z = NAN, z_low = NAN, z_high = NAN, fit_t_min = NAN, fit_t_max = NAN, runs = NAN;
  /// fit-beta (fit_beta.json): z over its window [w0, w1] (where the local slope is flat)
  double fz = NAN, fz_low = NAN, fz_high = NAN, w0 = NAN, w1 = NAN;
  double bz = NAN, bz_low = NAN, bz_high = NAN;  ///< beta from z at the data's S
  double ba = NAN, ba_low = NAN, ba_high = NAN;  ///< beta from the asymptotic law 3 z / (3 - z)
  double bf = NAN, bf_low = NAN, bf_high = NAN;  ///< full-curve beta: NaN when not determined
  double bf_min = NAN, bf_max = NAN;             ///< its search range
  /// false when the full-curve fit gave no beta: null, flagged, or at a bound of its range
  bool bf_determined = false;
  double S_c = NAN, tau_c = NAN;
  double onset = NAN, onset_err = NAN;  ///< onset time t_c of S_grid (analyze's fits.csv)
  double t_last = NAN;                  ///< last time with a finite S_grid (S_t.csv)
  GrowthSummary regime;                 ///< of the ensemble-mean S_grid (S_t.csv)
  SlopeTrend slope;                     ///< its local slope over the last half decade
  bool has_fit = false;                 ///< fit_beta.json was read
  std::string notes;                    ///< fit-beta's notes on beta (clamped, no beta, at a bound)
};

/// Reads DIR/analysis/K<K>/{fits,S_t}.csv and DIR/fit/K<K>/fit_beta.json. A full-curve beta
/// written as a number at a bound of its search range (within 1e-4 of it, fit-beta's own rule)
/// counts as not determined, as does a null one.
EnsembleResult readEnsemble(const std::filesystem::path& out, double K, const StudyServices& s);

/// The one growth exponent a summary states for an ensemble.
struct ReportedZ {
  /// "power law" (value, interval, window given), "not resolved" (interval includes 0),
  /// "no power law" (S grows, the local slope is not flat), "no growth" (S has not doubled),
  /// "unknown" (no S(t) table)
  std::string status;
  double value = NAN, low = NAN, high = NAN, t0 = NAN, t1 = NAN;
  std::string source;  ///< "fit-beta" (its window, where the local slope is flat) or "analyze"
  std::string text;    ///< the line as printed, e.g. "no power law (local slope rising)"
};

/// From the regime, the local slope and the two fits: fit-beta's z where it has one (its
/// window is where the local slope is flat), else analyze's. `runs`: the ensemble's runs.
ReportedZ reportedZ(const EnsembleResult& r, int runs);

/// The validation study's headline row for a K (data/validation/verdict.csv, quantity 1;
/// docs/validation.md).
struct ValidationRow {
  bool found = false;
  double N = NAN, runs = NAN, t_end = NAN, z = NAN, z_low = NAN, z_high = NAN, t0 = NAN, t1 = NAN;
  double onset = NAN, growth_factor = NAN, zloc_min = NAN, zloc_max = NAN;
  bool power_law = false;  ///< its local slope over the last half decade is flat
};

/// The row for K from the first data folder that has verdict.csv (found = false if none).
ValidationRow readValidation(double K, const StudyServices& s);

/// Everything the summary text says about one ensemble.
struct EnsembleFindings {
  EnsembleResult r;
  int runs = 0;
  long long N = 0;
  double t_end = NAN, charging_Q = NAN;
  std::string fit_status;  ///< "done", or why fit-beta gave nothing
  ValidationRow validation;
  double paper_z = NAN, paper_z_pm = NAN;
};

/// The mean field's local slope at the paper's S for one beta.
struct MeanFieldFinding {
  double beta = NAN, S = NAN, z_local = NAN, paper_z = NAN;
};

struct StudyFindings {
  std::string name;
  std::filesystem::path out;
  std::vector<EnsembleFindings> ensembles;
  std::vector<MeanFieldFinding> meanfield;
  std::uintmax_t bytes = 0;  ///< size of the results folder (0: not stated)
};

/// The verdict, one sentence each (no bullet): per ensemble what it showed, the mean field, and
/// the validation study's conclusion for the same K.
std::vector<std::string> verdictLines(const StudyFindings& f);
/// A few plain lines per ensemble: heading, growth and regime, local slope, z, beta, the
/// validation study's row, the paper's value.
std::vector<std::string> ensembleLines(const EnsembleFindings& e);
/// The whole summary.txt: the verdict first, then the ensembles, where the numbers are, and the
/// folder's size with the command that deletes it. Lines wrapped at 100 columns.
std::string summaryText(const StudyFindings& f);

/// Bytes in the regular files under `dir` (links not followed; unreadable entries skipped).
std::uintmax_t folderBytes(const std::filesystem::path& dir);

}  // namespace granagg::study
