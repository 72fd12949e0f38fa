/// `granagg fit-beta`: growth exponent z of a measured S(t), beta from z through the full
/// Smoluchowski z(beta), and a full-curve fit of S(t) against S_c S_MF(t / tau_c; beta)
/// (meanfield/fit/BetaFit.h, docs/fit-beta.md).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Version.h"
#include "meanfield/fit/BetaFit.h"
#include "meanfield/fit/GrowthInput.h"

namespace granagg::cli {
namespace mf = granagg::meanfield;
namespace fs = std::filesystem;

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

// ---- fit_beta.json: nlohmann-json, keys in the order written, NaN and inf -> null

class Json {
 public:
  void num(const std::string& k, double v) {
    m_j[k] = std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
  }
  void integer(const std::string& k, long long v) { m_j[k] = v; }
  void boolean(const std::string& k, bool v) { m_j[k] = v; }
  void str(const std::string& k, const std::string& v) { m_j[k] = v; }
  void strings(const std::string& k, const std::vector<std::string>& v) { m_j[k] = v; }
  std::string text() const { return m_j.dump(2) + "\n"; }

 private:
  nlohmann::ordered_json m_j = nlohmann::ordered_json::object();
};

std::string interval(double v, double lo, double hi) {
  char buf[160];
  if (!std::isfinite(v)) return "n/a";
  if (!std::isfinite(lo) && !std::isfinite(hi))
    std::snprintf(buf, sizeof buf, "%.4g", v);  // (no interval)
  else
    std::snprintf(buf, sizeof buf, "%.4g [%.4g, %.4g]", v, lo, hi);
  return buf;
}

void runFitBeta(const FitBetaArgs& a, const CliContext& ctx) {
  const common::PaperValues& paper = paperValues();  // printed beside ours
  mf::validateBetaRange(a.beta_min, a.beta_max);
  if (!a.window.empty() && a.window.size() != 2)
    throw std::invalid_argument("--window needs two times T0 T1.");
  mf::GrowthInput L = mf::readGrowthInput(a.input, a.column);
  mf::dropUnusableRows(L);
  mf::GrowthData data;
  try {
    data = mf::growthFromRuns(L.t, L.runs);
    mf::validateGrowthData(data);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("INPUT " + L.source + " column " + L.column + ": " + e.what());
  }
  const int minPoints = 5;
  if (data.t.size() < static_cast<std::size_t>(minPoints))
    throw std::invalid_argument("INPUT " + L.source + ": too few points (" +
                                std::to_string(data.t.size()) + " samples with t > 0, at least " +
                                std::to_string(minPoints) + " needed).");

  const fs::path outDir(a.out);
  const std::string csvPath = (outDir / "fit_beta.csv").string(),
                    curvePath = (outDir / "fit_curve.csv").string(),
                    jsonPath = (outDir / "fit_beta.json").string();
  common::refuseToOverwrite(csvPath, a.force);
  common::refuseToOverwrite(jsonPath, a.force);
  if (!a.no_curve_fit) common::refuseToOverwrite(curvePath, a.force);

  // 1. z over the window.
  mf::WindowOptions wo;
  wo.min_points = minPoints;
  const mf::SlopeWindow window =
      a.window.empty() ? mf::automaticWindow(data, wo)
                       : mf::explicitWindow(data, a.window[0], a.window[1], minPoints);
  mf::BootstrapOptions bo;
  const mf::ZFit zf = mf::fitGrowthExponent(data, window, bo);

  // 2. beta from z at the window's S range, and the mean field's z there for beta = 2 and 3.
  mf::MeanFieldCurves curves;
  const mf::BetaFromZ bz =
      mf::betaFromZ(curves, zf.z, zf.z_low, zf.z_high, zf.S0, zf.S1, a.beta_min, a.beta_max);
  double zmf2 = std::nan(""), zmf3 = std::nan("");
  if (bz.S1 > bz.S0 * 1.0001) {
    zmf2 = curves.exponentBetween(bz.S0, bz.S1, 2.0);
    zmf3 = curves.exponentBetween(bz.S0, bz.S1, 3.0);
  }

  // 3. Full-curve fit.
  mf::CurveFit cf;
  const double nan = std::nan("");
  cf.beta = cf.beta_low = cf.beta_high = cf.S_c = cf.S_c_low = cf.S_c_high = nan;
  cf.tau_c = cf.tau_c_low = cf.tau_c_high = cf.chi2_dof = nan;
  if (!a.no_curve_fit) {
    mf::CurveFitOptions co;
    co.beta_min = a.beta_min;
    co.beta_max = a.beta_max;
    co.bootstrap = bo;
    cf = mf::fitCurve(curves, data, co);
  }

  // 4. beta from z with the data's S mapped onto the mean field's by the fitted amplitude, S / S_c.
  mf::BetaFromZ bzs;
  bzs.beta = bzs.beta_low = bzs.beta_high = nan;
  if (!a.no_curve_fit && std::isfinite(cf.S_c) && cf.S_c > 0.0)
    bzs = mf::betaFromZ(curves, zf.z, zf.z_low, zf.z_high, zf.S0 / cf.S_c, zf.S1 / cf.S_c,
                        a.beta_min, a.beta_max);

  // 5. beta from z by the asymptotic law z = 3 beta / (beta + 3): needs no S scale.
  const mf::BetaFromZ ba = mf::betaAsymptotic(zf.z, zf.z_low, zf.z_high);

  // Outputs.
  fs::create_directories(outDir);
  if (a.no_curve_fit && a.force)
    fs::remove(curvePath);  // a stale curve from an earlier run would mislead
  common::Provenance prov(ctx.command_line);
  prov.add("input", L.source);
  prov.add("column", L.column);
  prov.add("runs", static_cast<long long>(L.runs.size()));
  prov.add("samples", static_cast<long long>(data.t.size()));
  prov.add("window_rule", window.rule);
  prov.add("z_interval",
           zf.interval_method +
               (zf.replicates ? " (" + std::to_string(zf.replicates) + " replicates)" : ""));
  prov.add("confidence", bo.confidence);
  prov.add("bootstrap_seed", static_cast<long long>(bo.seed));
  prov.add("beta_min", a.beta_min);
  prov.add("beta_max", a.beta_max);
  prov.add("mean_field",
           std::string("sectional solver, beta kernel, n_1(0) = 1, K0 = 1, grid ratio ") +
               common::formatReal(curves.options().ratio) + ", rtol " +
               common::formatReal(curves.options().rtol));
  prov.add(
      "beta_from_z",
      std::string("beta at which the mean-field least-squares exponent over the S range [S0, S1] "
                  "of the window (fitted power law at t0, t1) equals z"));
  if (!bz.note.empty()) prov.add("beta_from_z_note", bz.note);
  prov.add("beta_from_z_scaled",
           std::string("the same at the S range [S0, S1] / S_c (S_c from the curve fit)"));
  if (!bzs.note.empty()) prov.add("beta_from_z_scaled_note", bzs.note);
  prov.add("beta_asymptotic",
           std::string("3 z / (3 - z), the inverse of the large-S limit z = 3 beta / (beta + 3) "
                       "(no S scale needed; valid where z was measured in the scaling regime)"));
  if (!ba.note.empty()) prov.add("beta_asymptotic_note", ba.note);
  if (!a.no_curve_fit) prov.add("curve_interval", cf.interval_method);
  if (!cf.note.empty()) prov.add("curve_fit_note", cf.note);
  for (std::size_t i = 0; i < L.notes.size(); ++i)
    prov.add("note." + std::to_string(i), L.notes[i]);
  common::Provenance sp = prov;
  sp.add(
      "columns",
      std::string(
          "z, z_low, z_high: exponent of S ~ t^z over [t0, t1] (n_points samples) with its 95 % "
          "interval; beta_from_z*: inversion of the full-Smoluchowski z(beta) at the window's S "
          "range [S0, S1]; beta_fit, S_c, tau_c (+ _low/_high): fit of ln S(t) to "
          "ln[S_c S_MF(t/tau_c; beta)]; chi2_dof: residual variance of ln S; S0, S1: fitted S at "
          "t0, t1; n_runs: runs in the input; beta_from_z_scaled*: as beta_from_z at [S0, S1] / "
          "S_c; "
          "beta_asymptotic*: 3 z / (3 - z) (the large-S law inverted) at z, z_low, z_high; "
          "beta_fit_determined: 0 when beta_fit lies at a bound of the search range; NaN = not "
          "available"));
  {
    common::CsvWriter w(csvPath, sp,
                        {"z",
                         "z_low",
                         "z_high",
                         "t0",
                         "t1",
                         "n_points",
                         "beta_from_z",
                         "beta_from_z_low",
                         "beta_from_z_high",
                         "beta_fit",
                         "beta_fit_low",
                         "beta_fit_high",
                         "S_c",
                         "S_c_low",
                         "S_c_high",
                         "tau_c",
                         "tau_c_low",
                         "tau_c_high",
                         "chi2_dof",
                         "S0",
                         "S1",
                         "n_runs",
                         "beta_from_z_scaled",
                         "beta_from_z_scaled_low",
                         "beta_from_z_scaled_high",
                         "beta_asymptotic",
                         "beta_asymptotic_low",
                         "beta_asymptotic_high",
                         "beta_fit_determined"},
                        a.force);
    w.row({zf.z,
           zf.z_low,
           zf.z_high,
           zf.t0,
           zf.t1,
           static_cast<double>(zf.points),
           bz.beta,
           bz.beta_low,
           bz.beta_high,
           cf.beta,
           cf.beta_low,
           cf.beta_high,
           cf.S_c,
           cf.S_c_low,
           cf.S_c_high,
           cf.tau_c,
           cf.tau_c_low,
           cf.tau_c_high,
           cf.chi2_dof,
           zf.S0,
           zf.S1,
           static_cast<double>(L.runs.size()),
           bzs.beta,
           bzs.beta_low,
           bzs.beta_high,
           ba.beta,
           ba.beta_low,
           ba.beta_high,
           a.no_curve_fit ? nan : (cf.at_bound ? 0.0 : 1.0)});
    w.close();
  }
  if (!a.no_curve_fit) {
    common::Provenance cp = prov;
    cp.add(
        "columns",
        std::string(
            "t, S_md: the data (mean over runs); S_mf_fitted = S_c S_MF(t/tau_c; beta_fit); "
            "S_mf_beta2, S_mf_beta3: the mean field for beta = 2 and 3 with the same S_c, tau_c"));
    common::CsvWriter w(curvePath, cp, {"t", "S_md", "S_mf_fitted", "S_mf_beta2", "S_mf_beta3"},
                        a.force);
    for (std::size_t i = 0; i < data.t.size(); ++i) {
      const double tm = data.t[i] / cf.tau_c;
      w.row({data.t[i], data.S[i], cf.S_fitted[i], cf.S_c * std::exp(curves.logS(tm, 2.0)),
             cf.S_c * std::exp(curves.logS(tm, 3.0))});
    }
    w.close();
  }
  {
    Json j;
    j.str("version", common::versionString());
    j.str("command", ctx.command_line);
    j.str("input", L.source);
    j.str("column", L.column);
    j.integer("n_runs", static_cast<long long>(L.runs.size()));
    j.integer("samples", static_cast<long long>(data.t.size()));
    j.num("confidence", bo.confidence);
    j.num("z", zf.z);
    j.num("z_low", zf.z_low);
    j.num("z_high", zf.z_high);
    j.str("z_interval_method", zf.interval_method);
    j.num("t0", zf.t0);
    j.num("t1", zf.t1);
    j.integer("n_points", zf.points);
    j.boolean("window_automatic", window.automatic);
    j.str("window_rule", window.rule);
    j.num("S0", zf.S0);
    j.num("S1", zf.S1);
    j.num("beta_from_z", bz.beta);
    j.num("beta_from_z_low", bz.beta_low);
    j.num("beta_from_z_high", bz.beta_high);
    j.str("beta_from_z_note", bz.note);
    j.num("beta_from_z_scaled", bzs.beta);
    j.num("beta_from_z_scaled_low", bzs.beta_low);
    j.num("beta_from_z_scaled_high", bzs.beta_high);
    j.str("beta_from_z_scaled_note", bzs.note);
    j.num("beta_asymptotic", ba.beta);
    j.num("beta_asymptotic_low", ba.beta_low);
    // +inf (z_high >= 3) is written as null like NaN; the note says which
    j.num("beta_asymptotic_high", ba.beta_high);
    j.str("beta_asymptotic_note", ba.note);
    j.num("z_mf_at_beta_min", bz.z_at_beta_min);
    j.num("z_mf_at_beta_max", bz.z_at_beta_max);
    j.num("z_mf_beta2_window", zmf2);
    j.num("z_mf_beta3_window", zmf3);
    j.boolean("curve_fit", !a.no_curve_fit);
    j.boolean("beta_fit_determined", !a.no_curve_fit && !cf.at_bound);
    j.num("beta_fit", cf.beta);
    j.num("beta_fit_low", cf.beta_low);
    j.num("beta_fit_high", cf.beta_high);
    j.num("S_c", cf.S_c);
    j.num("S_c_low", cf.S_c_low);
    j.num("S_c_high", cf.S_c_high);
    j.num("tau_c", cf.tau_c);
    j.num("tau_c_low", cf.tau_c_low);
    j.num("tau_c_high", cf.tau_c_high);
    j.num("chi2_dof", cf.chi2_dof);
    j.str("curve_interval_method", cf.interval_method);
    j.str("curve_fit_note", cf.note);
    j.num("beta_min", a.beta_min);
    j.num("beta_max", a.beta_max);
    j.num("paper_z_neutral", paper.z_neutral);
    j.num("paper_z_neutral_err", paper.z_neutral_pm);
    j.num("paper_z_charged", paper.z_charged);
    j.num("paper_z_charged_err", paper.z_charged_pm);
    j.num("paper_z_mf_beta2", paper.z_meanfield_beta2);
    j.num("paper_z_mf_beta3", paper.z_meanfield_beta3);
    j.strings("notes", L.notes);
    std::ofstream o(jsonPath);
    o << j.text();
    if (!o) throw std::runtime_error("cannot write '" + jsonPath + "'.");
  }

  if (a.quiet) return;
  std::fprintf(stderr, "fit-beta: %s column %s: %zu samples, %zu run%s\n", L.source.c_str(),
               L.column.c_str(), data.t.size(), L.runs.size(), L.runs.size() == 1 ? "" : "s");
  for (const auto& n : L.notes) std::fprintf(stderr, "fit-beta:   note: %s\n", n.c_str());
  std::fprintf(stderr, "fit-beta: window [%.4g, %.4g], %d samples (%s)\n", zf.t0, zf.t1, zf.points,
               window.rule.c_str());
  std::fprintf(stderr,
               "fit-beta: z = %s (95 %%, %s)   paper: %.2f +- %.2f neutral, %.2f +- %.3f charged\n",
               interval(zf.z, zf.z_low, zf.z_high).c_str(), zf.interval_method.c_str(),
               paper.z_neutral, paper.z_neutral_pm, paper.z_charged, paper.z_charged_pm);
  std::fprintf(
      stderr,
      "fit-beta: beta from z = %s (full Smoluchowski z(beta) over S = %.4g..%.4g, where it gives z "
      "= %.4f at "
      "beta = 2, %.4f at beta = 3)   paper: mean field z = %.2f at beta = 2, %.2f at beta = 3\n",
      interval(bz.beta, bz.beta_low, bz.beta_high).c_str(), bz.S0, bz.S1, zmf2, zmf3,
      paper.z_meanfield_beta2, paper.z_meanfield_beta3);
  if (!bz.note.empty()) std::fprintf(stderr, "fit-beta:   note: %s\n", bz.note.c_str());
  std::fprintf(
      stderr,
      "fit-beta: beta from the asymptotic law z = 3 beta/(beta + 3) = %s (no S scale; valid where "
      "the local "
      "slope is flat)\n",
      interval(ba.beta, ba.beta_low, ba.beta_high).c_str());
  if (!ba.note.empty()) std::fprintf(stderr, "fit-beta:   note: %s\n", ba.note.c_str());
  if (!a.no_curve_fit) {
    std::fprintf(stderr,
                 "fit-beta: beta from z at S / S_c = %.4g..%.4g (S_c from the curve fit) = %s\n",
                 bzs.S0, bzs.S1, interval(bzs.beta, bzs.beta_low, bzs.beta_high).c_str());
    if (!bzs.note.empty()) std::fprintf(stderr, "fit-beta:   note: %s\n", bzs.note.c_str());
    const std::string beta_fit = cf.at_bound
                                     ? "not determined (at the bound " +
                                           interval(cf.beta, NAN, NAN) + " of the search range)"
                                     : "= " + interval(cf.beta, cf.beta_low, cf.beta_high);
    std::fprintf(stderr,
                 "fit-beta: beta from the curve fit %s, S_c = %s, tau_c = %s, chi2/dof = %.3g "
                 "(%s)\n",
                 beta_fit.c_str(), interval(cf.S_c, cf.S_c_low, cf.S_c_high).c_str(),
                 interval(cf.tau_c, cf.tau_c_low, cf.tau_c_high).c_str(), cf.chi2_dof,
                 cf.interval_method.c_str());
    if (!cf.note.empty()) std::fprintf(stderr, "fit-beta:   note: %s\n", cf.note.c_str());
  }
  std::fprintf(stderr, "fit-beta: wrote %s, %s%s\n", csvPath.c_str(),
               a.no_curve_fit ? "" : (curvePath + ", ").c_str(), jsonPath.c_str());
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
