/// `granagg fit-beta`: growth exponent z of a measured S(t), beta from z through the full
/// Smoluchowski z(beta), and a full-curve fit of S(t) against S_c S_MF(t / tau_c; beta)
/// (docs/fit-beta.md): the options, wired to meanfield/fit/FitBetaRun.h.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cli/CliContext.h"
#include "meanfield/fit/FitBetaRun.h"

namespace granagg::cli {
namespace mf = granagg::meanfield;

namespace {

struct FitBetaArgs {
  std::string input;
  std::string column;
  std::vector<double> window;
  double beta_min = 1.5;
  double beta_max = 6.0;
  bool no_curve_fit = false;
  std::string out = "fit-beta-out";
  bool force = false;
  bool quiet = false;
};

void runFitBeta(const FitBetaArgs& a, const CliContext& ctx) {
  mf::FitBetaRequest request;
  request.window = a.window;
  request.beta_min = a.beta_min;
  request.beta_max = a.beta_max;
  request.curve_fit = !a.no_curve_fit;
  mf::validateBetaRange(a.beta_min, a.beta_max);  // options first, then the input
  if (!a.window.empty() && a.window.size() != 2)
    throw std::invalid_argument("--window needs two times T0 T1.");
  mf::GrowthInput input = mf::readGrowthInput(a.input, a.column);
  mf::checkFitBetaOutputs(a.out, request.curve_fit, a.force);  // before the fits' seconds
  const mf::FitBetaResult r = mf::runFitBeta(std::move(input), request);
  const common::PaperValues& paper = paperValues();
  mf::writeFitBeta(r, a.out, ctx.command_line, paper, a.force);
  if (a.quiet) return;
  for (const std::string& line : mf::fitBetaReport(r, paper))
    std::fprintf(stderr, "fit-beta: %s\n", line.c_str());
  const mf::FitBetaFiles f = mf::fitBetaFiles(a.out);
  std::fprintf(stderr, "fit-beta: wrote %s, %s%s\n", f.csv.c_str(),
               a.no_curve_fit ? "" : (f.curve + ", ").c_str(), f.json.c_str());
}

}  // namespace

void registerFitBetaCommand(CLI::App& app, const CliContext& ctx) {
  auto args = std::make_shared<FitBetaArgs>();
  CLI::App* c = app.add_subcommand("fit-beta",
                                   "Fit the growth exponent z of a mean cluster size S(t) ~ t^z "
                                   "with a 95 % interval, the kernel exponent beta\n"
                                   "whose full Smoluchowski solution grows with the same z over "
                                   "the same S range, and a full-curve fit of\n"
                                   "S(t) against S_c S_MF(t/tau_c; beta). Writes fit_beta.csv, "
                                   "fit_curve.csv and fit_beta.json (docs/fit-beta.md).");
  c->add_option("INPUT", args->input,
                "A `granagg analyze` output folder (S_t.csv, per_run/S_t.csv), an analysis.h5, or "
                "a CSV with a t column "
                "and S column(s)")
      ->required();
  c->add_option(
      "--column", args->column,
      "S column (default: S_grid_mean, else S_grid (per_run tables), else S, else the only "
      "column besides t); a prefix "
      "(e.g. S_run) takes "
      "every matching column as one run");
  c->add_option("--window", args->window,
                "Fit window T0 T1 for z (default: automatic, the late plateau of the local slope)")
      ->expected(2);
  c->add_option("--beta-min", args->beta_min, "Smallest beta considered (>= 1)")
      ->capture_default_str();
  c->add_option("--beta-max", args->beta_max, "Largest beta considered (<= 20)")
      ->capture_default_str();
  c->add_flag("--no-curve-fit", args->no_curve_fit,
              "Skip the full-curve fit (z and beta from z only)");
  c->add_option("-o,--out", args->out, "Output folder")->capture_default_str();
  c->add_flag("--force", args->force, "Overwrite existing output files");
  c->add_flag("-q,--quiet", args->quiet, "No summary on the terminal");
  c->callback([args, ctx]() { runFitBeta(*args, ctx); });
}

}  // namespace granagg::cli
