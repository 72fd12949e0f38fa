/// `granagg analyze`: trajectory analysis of one run or an ensemble (analysis/, docs/analysis.md).
/// The settings and their checks are analysis/pipeline/AnalyzeSettings.h's; this file wires the
/// options.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "analysis/pipeline/AnalysisFolder.h"
#include "analysis/pipeline/AnalyzeSettings.h"
#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/ProgressLine.h"
#include "study/insitu/InSituAnalysis.h"

namespace granagg::cli {
namespace an = granagg::analysis;

namespace {

/// What analyze takes besides the analysis settings.
struct AnalyzeArgs {
  std::vector<std::string> runs;
  std::string out = "analysis-out";
  bool force = false, quiet = false, write_grid = false;
  int threads = 0;
  an::AnalyzeSettings s;
};

void runAnalyze(const AnalyzeArgs& a, const CliContext& ctx) {
  if (a.threads < 0) throw std::invalid_argument("--threads must be >= 1.");
#ifdef _OPENMP
  if (a.threads > 0) omp_set_num_threads(a.threads);
#endif
  const an::AnalysisOptions o = an::analysisOptions(a.s, a.write_grid);
  an::AnalysisFolderRequest request;
  request.runs = a.runs;
  request.out = a.out;
  request.force = a.force;
  request.write_grid = a.write_grid;
  request.command_line = ctx.command_line;
  // a run analysed while it ran that stored no frames: its in-situ tables
  request.stored_result = [](const std::string& run) { return insitu::storedResult(run); };
  common::ProgressLine progress("analyze", !a.quiet);  // in place, or a line a minute in a log
  const an::AnalysisFolder folder =
      an::analyseIntoFolder(request, o, [&](std::size_t run, std::size_t frame, std::size_t hint) {
        if (progress.due())
          progress.show("run " + std::to_string(run + 1) + "/" + std::to_string(a.runs.size()) +
                        ", frame " + std::to_string(frame) +
                        (hint ? "/" + std::to_string(hint) : std::string()));
      });
  progress.finish();
  for (const std::string& line : an::analysisWarnings(folder, o))  // even with -q
    std::fprintf(stderr, "analyze: warning: %s\n", line.c_str());
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
      "--grid-spacing", a->s.grid_spacing,
      "Grid clusters: target cell edge in d; cells per side floor(L/spacing) (default 2)");
  c->add_option("--grid-min-fill", a->s.grid_min_fill,
                "Grid clusters: occupied when the local filling fraction >= this (default 0.25)");
  c->add_option(
      "--grid-min-count", a->s.grid_min_count,
      "Grid clusters: occupied when count >= this (overrides --grid-min-fill; default 0 = off)");
  c->add_option(
      "--grid-assign", a->s.grid_assign,
      "Grid clusters: ngp (count centres per cell, default) or cic (cloud-in-cell smoothing)");
  c->add_flag("--no-grid", a->s.no_grid, "Skip grid clusters");
  c->add_option("--tolerance", a->s.tolerance,
                "Particle clusters: bonded when |r_ij| <= 1 + tolerance (default 0.05)");
  c->add_flag("--no-particle", a->s.no_particle, "Skip particle clusters and N_stick");
  c->add_flag("--no-structure-factor", a->s.no_structure,
              "Skip the structure factor S(k) (S_k.csv) and the density length l_density");
  c->add_option("--structure-kcut", a->s.structure_k_cut,
                "k_c in 1/d of the density length l = 2 pi / k_1, k_1 the first moment of S(k) "
                "over k <= k_c (default pi)");
  c->add_option("--slope-ratio", a->s.slope_ratio,
                "p of the local slope z(t) = ln[S(t)/S(t/p)]/ln p (default 2)");
  c->add_option("--fit-window", a->s.fit_window,
                "T_MIN T_MAX of the growth-exponent fit (default: the last decade)")
      ->expected(2);
  c->add_option("--charge-fit-window", a->s.charge_fit_window,
                "T_MIN T_MAX of the charging-rate fit (default 1 100)")
      ->expected(2);
  c->add_option("--mle-min-tail", a->s.mle_min_tail,
                "Fisher MLE: smallest tail (clusters >= xmin) considered (default 10)");
  c->add_option("--speed-max", a->s.speed_max, "Speed histogram range [0, max) in v~ (default 4)");
  c->add_option("--speed-bins", a->s.speed_bins, "Speed histogram bins (default 80)");
  c->add_option("--msd-origins", a->s.msd_origins,
                "t0 (from the first frame), all (FFT, evenly spaced frames), auto (default: all "
                "when possible)");
  c->add_option("--msd-max-memory", a->s.msd_max_memory_mib,
                "Memory budget of the all-origins MSD in MiB (default 1024)");
  c->add_option("--kappa", a->s.kappa,
                "Charging exponent kappa for the expected rate law (default: the file's "
                "charging.kappa, else 0.83)");
  c->add_option("--track", a->s.track,
                "N_stick: number of tracked particles (smallest ids; default 10)");
  c->add_flag("--allow-partial", a->s.allow_partial,
              "Analyse the frames before a truncated or malformed frame instead of failing");
  c->add_option(
      "--lammps-dt", a->s.lammps_dt,
      "LAMMPS dumps without ITEM: TIME: time = timestep * dt (default 0: time = timestep)");
  c->add_option("--bootstrap", a->s.bootstrap,
                "Bootstrap replicates over runs for the ensemble growth exponent (default 2000)");
  c->add_option("--seed", a->s.seed, "Seed of the bootstrap (default 20091)");
  c->add_option("--onset-factor", a->s.onset_factor,
                "Onset time t_c: S reaches this multiple of its early median (default 2)");
  c->add_option("--onset-baseline", a->s.onset_baseline,
                "Onset time t_c: the early median is over 0 < t <= this (default 10)");
  c->add_option("--fisher-bin-ratio", a->s.fisher_bin_ratio,
                "The paper's Fisher estimator: log bins [r^k, r^(k+1)) (default 2)");
  c->add_flag("--write-grid", a->write_grid,
              "Store every frame's occupancy grid and cluster labels in analysis.h5");
  c->add_option("--threads", a->threads, "OpenMP threads (default: all cores; OMP_NUM_THREADS)")
      ->check(CLI::Range(1, 4096));
  c->add_flag("-q,--quiet", a->quiet, "No progress line or summary");
  c->callback([a, ctx]() { runAnalyze(*a, ctx); });
}

}  // namespace granagg::cli
