#pragma once
/// \file RunAnalyzer.h
/// One trajectory -> all observables of docs/model.md section 10 as tables, streaming the frames
/// (memory: one frame, the MSD reference positions, and the all-origins MSD buffer within its
/// budget); then the ensemble over runs. `granagg analyze` is a thin wrapper over these.
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "analysis/clusters/GridClusters.h"
#include "analysis/clusters/ParticleClusters.h"
#include "analysis/io/Frame.h"
#include "analysis/pipeline/Table.h"
#include "analysis/stats/StructureFactor.h"

namespace granagg::analysis {

/// Options of the analysis, with the defaults documented in docs/analysis.md.
struct AnalysisOptions {
  GridClustersParams grid;          ///< grid clusters: spacing 2 d, min_fill 0.25
  ParticleClustersParams particle;  ///< particle clusters: |r_ij| <= 1.05
  bool grid_clusters = true;        ///< compute grid clusters
  bool particle_clusters = true;    ///< compute particle clusters (and N_stick)
  /// S(k) per frame (table S_k) and the density field's length l (S_t's l_density column)
  bool structure_factor = true;
  StructureFactorOptions structure;  ///< its mesh and the cut-off k_c of l
  double slope_ratio = 2.0;         ///< p of the local slope z(t) = ln[S(t)/S(t/p)] / ln p
  double fit_t_min = 0.0;  ///< growth-exponent window; 0 and 0: the last decade [t_last/10, t_last]
  double fit_t_max = 0.0;
  std::size_t mle_min_tail = 10;  ///< smallest tail (clusters >= xmin) the Fisher MLE considers
  double speed_max = 4.0;         ///< speed histogram range [0, speed_max) in v~
  int speed_bins = 80;            ///< bins of width 0.05
  std::string msd_origins =
      "auto";  ///< "t0", "all" (FFT, must be possible) or "auto" (all when possible)
  std::size_t msd_max_bytes = std::size_t(1) << 30;  ///< memory budget of the all-origins MSD
  double kappa =
      std::numeric_limits<double>::quiet_NaN();  ///< NaN: the file's charging.kappa, else 0.83
  double charge_fit_t_min =
      1.0;  ///< window of the charging-rate fit (early build-up, after ~1 collision time)
  double charge_fit_t_max = 100.0;
  std::size_t track = 10;      ///< N_stick: contacts of the particles with the `track` smallest ids
  bool allow_partial = false;  ///< analyse the frames before a truncated/malformed one
  double lammps_dt = 0.0;      ///< LAMMPS timestep to convert steps to times (0: time = step)
  int bootstrap_replicates = 2000;  ///< ensemble growth exponent: bootstrap replicates over runs
  std::uint64_t bootstrap_seed = 20091;  ///< fixed seed: the same runs give the same interval
  double onset_factor = 2.0;      ///< onset time: S reaches this multiple of its early plateau ...
  double onset_t_base = 10.0;     ///< ... the median S over 0 < t <= this (GrowthMarkers.h)
  double fisher_bin_ratio = 2.0;  ///< the paper's Fisher estimator: logarithmic bins [r^k, r^{k+1})

  /// Throws std::invalid_argument naming the option when a value is out of range.
  void validate() const;
};

/// Everything computed for one run.
struct RunResult {
  std::string source;  ///< the path given
  std::string format;  ///< "h5md" or "lammps-dump"
  std::size_t frames = 0, particles = 0;
  double box = 0.0;      ///< box edge L of the first frame, in d
  bool partial = false;  ///< stopped at a bad frame (--allow-partial)
  std::string partial_reason;
  std::map<std::string, std::string> parameters;  ///< the file's /parameters
  double kappa = 0.0;                             ///< kappa used for the expected charging exponent
  std::string kappa_source;        ///< "option", "file (charging.kappa)" or "default"
  int grid_cells = 0;              ///< grid clusters: cells per side (last frame)
  double grid_cell_size = 0.0;     ///< cell edge h = L / n, in d
  double grid_min_count = 0.0;     ///< occupation threshold used (centres per cell)
  std::vector<std::string> notes;  ///< observables skipped and why
  std::vector<Table> tables;
  /// The table called `name`; throws std::out_of_range.
  const Table& table(const std::string& name) const;
  bool hasTable(const std::string& name) const;
};

/// Called after each frame's clusters (for --write-grid) and for progress.
struct RunCallbacks {
  std::function<void(const Frame&, const GridClusters&)> grid;
  std::function<void(std::size_t frame, std::size_t hint)> progress;
};

/// Analyses one trajectory (a traj.h5 file, a run folder holding one, or a LAMMPS dump).
/// Throws TrajectoryError for a bad frame unless options.allow_partial and at least one frame
/// was read; std::invalid_argument for a missing file or bad options.
RunResult analyzeRun(const std::string& path, const AnalysisOptions& options,
                     const RunCallbacks& callbacks = {});

/// Throws std::invalid_argument naming both runs when they do not simulate the same system (a
/// different particle count N or box edge L): an ensemble's statistics average runs of one system.
void checkSameSystem(const RunResult& a, const RunResult& b);

/// Ensemble tables over runs: every per-frame table averaged (mean, standard error; rows matched
/// by time), the ensemble growth and charging fits (bootstrap over runs when there are 2 or
/// more), the local slope of the mean S(t), and pooled Fisher fits of the summed N_s.
std::vector<Table> analyzeEnsemble(const std::vector<RunResult>& runs,
                                   const AnalysisOptions& options);

}  // namespace granagg::analysis
