#pragma once
/// \file AnalyzeSettings.h
/// `granagg analyze`'s analysis options as given on the command line (docs/analysis.md), and
/// their translation into AnalysisOptions. Bad values throw std::invalid_argument with one
/// sentence naming the option (the command-line spelling, e.g. "--grid-spacing").
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "analysis/pipeline/RunAnalyzer.h"

namespace granagg::analysis {

/// The options of `granagg analyze` that shape the analysis, with their command-line defaults.
struct AnalyzeSettings {
  bool allow_partial = false;
  bool no_grid = false, no_particle = false;
  bool no_structure = false;        ///< --no-structure-factor
  double structure_k_cut = 3.14159265358979323846;  ///< --structure-kcut (k_c of l, 1/d)
  double grid_spacing = 2.0, grid_min_fill = 0.25;
  int grid_min_count = 0;
  std::string grid_assign = "ngp";
  double tolerance = 0.05;
  double slope_ratio = 2.0;
  std::vector<double> fit_window, charge_fit_window;
  std::size_t mle_min_tail = 10;
  double speed_max = 4.0;
  int speed_bins = 80;
  std::string msd_origins = "auto";
  double msd_max_memory_mib = 1024;
  double kappa = std::numeric_limits<double>::quiet_NaN();
  std::size_t track = 10;
  double lammps_dt = 0.0;
  int bootstrap = 2000;
  long long seed = 20091;
  double onset_factor = 2.0;
  double onset_baseline = 10.0;
  double fisher_bin_ratio = 2.0;
};

/// Checks the settings and builds the options (AnalysisOptions::validate included).
/// `write_grid` (grid occupancies into analysis.h5) needs grid clusters.
AnalysisOptions analysisOptions(const AnalyzeSettings& settings, bool write_grid);

}  // namespace granagg::analysis
