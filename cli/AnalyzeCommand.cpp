/// `granagg analyze`: trajectory analysis of one run or an ensemble (analysis/, docs/analysis.md).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "analysis/pipeline/AnalysisFolder.h"
#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/ProgressLine.h"

namespace granagg::cli {
namespace an = granagg::analysis;
namespace fs = std::filesystem;

namespace {

struct AnalyzeArgs {
  std::vector<std::string> runs;
  std::string out = "analysis-out";
  bool force = false, quiet = false, write_grid = false, allow_partial = false;
  bool no_grid = false, no_particle = false;
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
  int threads = 0;
};

an::AnalysisOptions toOptions(const AnalyzeArgs& a) {
  // the options by their names (the libraries' own checks name their parameters instead)
  if (!(a.grid_spacing > 0.0) || !std::isfinite(a.grid_spacing))
    throw std::invalid_argument("--grid-spacing must be > 0 and finite (got " +
                                common::formatReal(a.grid_spacing) + ")");
  if (!(a.grid_min_fill > 0.0 && a.grid_min_fill <= 1.0))
    throw std::invalid_argument("--grid-min-fill must lie in (0, 1] (got " +
                                common::formatReal(a.grid_min_fill) + ")");
  if (a.grid_min_count < 0)
    throw std::invalid_argument("--grid-min-count must be >= 0 (got " +
                                std::to_string(a.grid_min_count) + ")");
  if (!(a.tolerance >= 0.0) || !std::isfinite(a.tolerance))
    throw std::invalid_argument("--tolerance must be >= 0 and finite (got " +
                                common::formatReal(a.tolerance) + ")");
  an::AnalysisOptions o;
  o.grid.spacing = a.grid_spacing;
  o.grid.min_fill = a.grid_min_fill;
  o.grid.min_count = a.grid_min_count;
  if (a.grid_assign == "ngp")
    o.grid.assignment = an::GridAssignment::Nearest;
  else if (a.grid_assign == "cic")
    o.grid.assignment = an::GridAssignment::CloudInCell;
  else
    throw std::invalid_argument("--grid-assign must be ngp or cic (got '" + a.grid_assign + "').");
  o.grid_clusters = !a.no_grid;
  o.particle_clusters = !a.no_particle;
  if (a.no_grid && a.no_particle)
    throw std::invalid_argument(
        "--no-grid and --no-particle together leave no cluster definition.");
  if (a.write_grid && a.no_grid)
    throw std::invalid_argument("--write-grid needs grid clusters (drop --no-grid).");
  o.particle.tolerance = a.tolerance;
  o.slope_ratio = a.slope_ratio;
  if (!a.fit_window.empty()) {
    if (a.fit_window.size() != 2)
      throw std::invalid_argument("--fit-window takes two times T_MIN T_MAX.");
    o.fit_t_min = a.fit_window[0];
    o.fit_t_max = a.fit_window[1];
    if (!(o.fit_t_max > o.fit_t_min) || !(o.fit_t_min >= 0))
      throw std::invalid_argument("--fit-window must be two times 0 <= T_MIN < T_MAX (got " +
                                  common::formatReal(o.fit_t_min) + " " +
                                  common::formatReal(o.fit_t_max) + ").");
  }
  if (!a.charge_fit_window.empty()) {
    if (a.charge_fit_window.size() != 2)
      throw std::invalid_argument("--charge-fit-window takes two times T_MIN T_MAX.");
    o.charge_fit_t_min = a.charge_fit_window[0];
    o.charge_fit_t_max = a.charge_fit_window[1];
  }
  o.mle_min_tail = a.mle_min_tail;
  o.speed_max = a.speed_max;
  o.speed_bins = a.speed_bins;
  o.msd_origins = a.msd_origins;
  if (!(a.msd_max_memory_mib >= 0) || !std::isfinite(a.msd_max_memory_mib))
    throw std::invalid_argument("--msd-max-memory must be >= 0 MiB.");
  o.msd_max_bytes = static_cast<std::size_t>(a.msd_max_memory_mib * 1024.0 * 1024.0);
  o.kappa = a.kappa;
  o.track = a.track;
  o.allow_partial = a.allow_partial;
  o.lammps_dt = a.lammps_dt;
  o.bootstrap_replicates = a.bootstrap;
  if (a.seed < 0) throw std::invalid_argument("--seed must be >= 0.");
  o.bootstrap_seed = static_cast<std::uint64_t>(a.seed);
  o.onset_factor = a.onset_factor;
  o.onset_t_base = a.onset_baseline;
  o.fisher_bin_ratio = a.fisher_bin_ratio;
  o.validate();
  return o;
}

void runAnalyze(const AnalyzeArgs& a, const CliContext& ctx) {
  if (a.threads < 0) throw std::invalid_argument("--threads must be >= 1.");
#ifdef _OPENMP
  if (a.threads > 0) omp_set_num_threads(a.threads);
#endif
  const an::AnalysisOptions o = toOptions(a);
  an::AnalysisFolderRequest request;
  request.runs = a.runs;
  request.out = a.out;
  request.force = a.force;
  request.write_grid = a.write_grid;
  request.command_line = ctx.command_line;
  common::ProgressLine progress("analyze", !a.quiet);  // in place, or a line a minute in a log
  const an::AnalysisFolder folder =
      an::analyseIntoFolder(request, o, [&](std::size_t run, std::size_t frame, std::size_t hint) {
        if (progress.due())
          progress.show("run " + std::to_string(run + 1) + "/" + std::to_string(a.runs.size()) +
                        ", frame " + std::to_string(frame) +
                        (hint ? "/" + std::to_string(hint) : std::string()));
      });
  progress.finish();
  if (a.quiet) return;
  for (const std::string& line : an::analysisReport(folder))
    std::fprintf(stderr, "analyze: %s\n", line.c_str());
  std::fprintf(stderr, "analyze: wrote %s (CSV tables, per_run/, analysis.h5)\n", a.out.c_str());
}

}  // namespace

void registerAnalyzeCommand(CLI::App& app, const CliContext& ctx) {
  auto a = std::make_shared<AnalyzeArgs>();
  CLI::App* c = app.add_subcommand("analyze",
                                   "Analyse trajectories (H5MD files, run folders holding traj.h5, "
                                   "or LAMMPS text dumps): grid and particle\n"
                                   "clusters, N_s(s), S(t), Fisher and growth exponents, MSD, "
                                   "speed distribution, a2, T_g, charges, N_stick.\n"
                                   "Several RUNs make an ensemble (mean and standard error). "
                                   "Tables and defaults: docs/analysis.md.");
  c->add_option("runs", a->runs, "Trajectories: traj.h5, run folders, or LAMMPS dumps")->required();
  c->add_option("-o,--out", a->out,
                "Output folder (default analysis-out); must not exist or be empty unless --force");
  c->add_flag("--force", a->force, "Overwrite files in an existing output folder");
  c->add_option(
      "--grid-spacing", a->grid_spacing,
      "Grid clusters: target cell edge in d; cells per side floor(L/spacing) (default 2)");
  c->add_option("--grid-min-fill", a->grid_min_fill,
                "Grid clusters: occupied when the local filling fraction >= this (default 0.25)");
  c->add_option(
      "--grid-min-count", a->grid_min_count,
      "Grid clusters: occupied when count >= this (overrides --grid-min-fill; default 0 = off)");
  c->add_option(
      "--grid-assign", a->grid_assign,
      "Grid clusters: ngp (count centres per cell, default) or cic (cloud-in-cell smoothing)");
  c->add_flag("--no-grid", a->no_grid, "Skip grid clusters");
  c->add_option("--tolerance", a->tolerance,
                "Particle clusters: bonded when |r_ij| <= 1 + tolerance (default 0.05)");
  c->add_flag("--no-particle", a->no_particle, "Skip particle clusters and N_stick");
  c->add_option("--slope-ratio", a->slope_ratio,
                "p of the local slope z(t) = ln[S(t)/S(t/p)]/ln p (default 2)");
  c->add_option("--fit-window", a->fit_window,
                "T_MIN T_MAX of the growth-exponent fit (default: the last decade)")
      ->expected(2);
  c->add_option("--charge-fit-window", a->charge_fit_window,
                "T_MIN T_MAX of the charging-rate fit (default 1 100)")
      ->expected(2);
  c->add_option("--mle-min-tail", a->mle_min_tail,
                "Fisher MLE: smallest tail (clusters >= xmin) considered (default 10)");
  c->add_option("--speed-max", a->speed_max, "Speed histogram range [0, max) in v~ (default 4)");
  c->add_option("--speed-bins", a->speed_bins, "Speed histogram bins (default 80)");
  c->add_option("--msd-origins", a->msd_origins,
                "t0 (from the first frame), all (FFT, evenly spaced frames), auto (default: all "
                "when possible)");
  c->add_option("--msd-max-memory", a->msd_max_memory_mib,
                "Memory budget of the all-origins MSD in MiB (default 1024)");
  c->add_option("--kappa", a->kappa,
                "Charging exponent kappa for the expected rate law (default: the file's "
                "charging.kappa, else 0.83)");
  c->add_option("--track", a->track,
                "N_stick: number of tracked particles (smallest ids; default 10)");
  c->add_flag("--allow-partial", a->allow_partial,
              "Analyse the frames before a truncated or malformed frame instead of failing");
  c->add_option(
      "--lammps-dt", a->lammps_dt,
      "LAMMPS dumps without ITEM: TIME: time = timestep * dt (default 0: time = timestep)");
  c->add_option("--bootstrap", a->bootstrap,
                "Bootstrap replicates over runs for the ensemble growth exponent (default 2000)");
  c->add_option("--seed", a->seed, "Seed of the bootstrap (default 20091)");
  c->add_option("--onset-factor", a->onset_factor,
                "Onset time t_c: S reaches this multiple of its early median (default 2)");
  c->add_option("--onset-baseline", a->onset_baseline,
                "Onset time t_c: the early median is over 0 < t <= this (default 10)");
  c->add_option("--fisher-bin-ratio", a->fisher_bin_ratio,
                "The paper's Fisher estimator: log bins [r^k, r^(k+1)) (default 2)");
  c->add_flag("--write-grid", a->write_grid,
              "Store every frame's occupancy grid and cluster labels in analysis.h5");
  c->add_option("--threads", a->threads, "OpenMP threads (default: all cores; OMP_NUM_THREADS)")
      ->check(CLI::Range(1, 4096));
  c->add_flag("-q,--quiet", a->quiet, "No progress line or summary");
  c->callback([a, ctx]() { runAnalyze(*a, ctx); });
}

}  // namespace granagg::cli
