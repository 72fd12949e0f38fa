/// \file FitBetaRun.cpp
/// The fit-beta sequence and its outputs (FitBetaRun.h).
#include "meanfield/fit/FitBetaRun.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "common/Csv.h"
#include "common/FolderLock.h"
#include "common/OutputPath.h"
#include "common/Strings.h"
#include "common/Version.h"

namespace granagg::meanfield {
namespace fs = std::filesystem;

namespace {

constexpr double NaN = std::numeric_limits<double>::quiet_NaN();

/// A number for fit_beta.json: NaN and inf as null (the notes say which).
nlohmann::ordered_json num(double x) {
  return std::isfinite(x) ? nlohmann::ordered_json(x) : nlohmann::ordered_json(nullptr);
}

/// "v [lo, hi]" to 4 digits; "v" alone without an interval; "n/a" without a value.
std::string interval(double v, double lo, double hi) {
  if (!std::isfinite(v)) return "n/a";
  if (!std::isfinite(lo) && !std::isfinite(hi)) return common::formatShort(v);
  return common::printfString("%.4g [%.4g, %.4g]", v, lo, hi);
}

/// Writes `path.partial` and renames it: no half-written JSON is left by a failure.
void writeJson(const std::string& path, const nlohmann::ordered_json& j) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream o(tmp);
    o << j.dump(2) << "\n";
    if (!o) throw std::runtime_error("cannot write '" + tmp + "'.");
  }
  fs::rename(tmp, path);
}

BetaFromZ noBeta() {
  BetaFromZ b;
  b.beta = b.beta_low = b.beta_high = NaN;
  return b;
}

}  // namespace

FitBetaResult runFitBeta(GrowthInput input, const FitBetaRequest& request) {
  validateBetaRange(request.beta_min, request.beta_max);
  if (!request.window.empty() && request.window.size() != 2)
    throw std::invalid_argument("--window needs two times T0 T1.");
  FitBetaResult r;
  r.request = request;
  const std::string dropped = dropUnusableRows(input);
  r.input = std::move(input);
  const GrowthInput& L = r.input;
  try {
    r.data = growthFromRuns(L.t, L.runs);
    validateGrowthData(r.data);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("INPUT " + L.source + " column " + L.column + ": " + e.what());
  }
  const int minPoints = request.min_points;
  if (r.data.t.size() < static_cast<std::size_t>(minPoints))
    throw std::invalid_argument("INPUT " + L.source + ": too few points (" +
                                std::to_string(r.data.t.size()) + " usable samples, at least " +
                                std::to_string(minPoints) + " needed" +
                                (dropped.empty() ? std::string() : "; " + dropped) + ").");

  // 1. z over the window.
  WindowOptions wo;
  wo.min_points = minPoints;
  r.window = request.window.empty()
                 ? automaticWindow(r.data, wo)
                 : explicitWindow(r.data, request.window[0], request.window[1], minPoints);
  r.z = fitGrowthExponent(r.data, r.window, r.bootstrap);
  const ZFit& zf = r.z;

  // 2. beta from z at the window's S range, and the mean field's z there for beta = 2 and 3.
  MeanFieldCurves curves;
  r.mf_ratio = curves.options().ratio;
  r.mf_rtol = curves.options().rtol;
  r.from_z = betaFromZ(curves, zf.z, zf.z_low, zf.z_high, zf.S0, zf.S1, request.beta_min,
                       request.beta_max);
  r.z_mf_beta2 = r.z_mf_beta3 = NaN;
  if (r.from_z.S1 > r.from_z.S0 * 1.0001) {
    r.z_mf_beta2 = curves.exponentBetween(r.from_z.S0, r.from_z.S1, 2.0);
    r.z_mf_beta3 = curves.exponentBetween(r.from_z.S0, r.from_z.S1, 3.0);
  }

  // 3. Full-curve fit.
  CurveFit& cf = r.curve;
  cf.beta = cf.beta_low = cf.beta_high = cf.S_c = cf.S_c_low = cf.S_c_high = NaN;
  cf.tau_c = cf.tau_c_low = cf.tau_c_high = cf.chi2_dof = NaN;
  if (request.curve_fit) {
    CurveFitOptions co;
    co.beta_min = request.beta_min;
    co.beta_max = request.beta_max;
    co.bootstrap = r.bootstrap;
    cf = fitCurve(curves, r.data, co);
    for (double t : r.data.t) {
      r.S_mf_beta2.push_back(cf.S_c * std::exp(curves.logS(t / cf.tau_c, 2.0)));
      r.S_mf_beta3.push_back(cf.S_c * std::exp(curves.logS(t / cf.tau_c, 3.0)));
    }
  }

  // 4. beta from z with the data's S mapped onto the mean field's by the fitted amplitude, S / S_c.
  r.from_z_scaled = noBeta();
  if (request.curve_fit && std::isfinite(cf.S_c) && cf.S_c > 0.0)
    r.from_z_scaled = betaFromZ(curves, zf.z, zf.z_low, zf.z_high, zf.S0 / cf.S_c, zf.S1 / cf.S_c,
                                request.beta_min, request.beta_max);

  // 5. beta from z by the asymptotic law z = 3 beta / (beta + 3): needs no S scale.
  r.asymptotic = betaAsymptotic(zf.z, zf.z_low, zf.z_high);
  return r;
}

FitBetaFiles fitBetaFiles(const std::string& folder) {
  const fs::path d(folder);
  return {(d / "fit_beta.csv").string(), (d / "fit_curve.csv").string(),
          (d / "fit_beta.json").string()};
}

void checkFitBetaOutputs(const std::string& folder, bool curve_fit, bool force) {
  const FitBetaFiles f = fitBetaFiles(folder);
  common::checkOutputFolder(folder, "--out");         // a file, read-only or not creatable
  common::FolderLock::checkAvailable(folder, force);  // another command writing there: refused
  common::refuseToOverwrite(f.csv, force);
  common::refuseToOverwrite(f.json, force);
  if (curve_fit) common::refuseToOverwrite(f.curve, force);
}

namespace {

/// The provenance shared by fit_beta.csv and fit_beta_curve.csv: the input, the window, the
/// methods and their notes.
common::Provenance fitBetaProvenance(const FitBetaResult& r, const std::string& command_line) {
  common::Provenance prov(command_line);
  prov.add("input", r.input.source);
  prov.add("column", r.input.column);
  prov.add("runs", static_cast<long long>(r.input.runs.size()));
  prov.add("samples", static_cast<long long>(r.data.t.size()));
  prov.add("window_rule", r.window.rule);
  prov.add("z_interval",
           r.z.interval_method +
               (r.z.replicates ? " (" + std::to_string(r.z.replicates) + " replicates)" : ""));
  prov.add("confidence", r.bootstrap.confidence);
  if (!r.z.note.empty()) prov.add("z_note", r.z.note);
  prov.add("bootstrap_seed", static_cast<long long>(r.bootstrap.seed));
  prov.add("beta_min", r.request.beta_min);
  prov.add("beta_max", r.request.beta_max);
  prov.add("mean_field",
           std::string("sectional solver, beta kernel, n_1(0) = 1, K0 = 1, grid ratio ") +
               common::formatReal(r.mf_ratio) + ", rtol " + common::formatReal(r.mf_rtol));
  prov.add(
      "beta_from_z",
      std::string("beta at which the mean-field least-squares exponent over the S range [S0, S1] "
                  "of the window (fitted power law at t0, t1) equals z"));
  if (!r.from_z.note.empty()) prov.add("beta_from_z_note", r.from_z.note);
  prov.add("beta_from_z_scaled",
           std::string("the same at the S range [S0, S1] / S_c (S_c from the curve fit)"));
  if (!r.from_z_scaled.note.empty()) prov.add("beta_from_z_scaled_note", r.from_z_scaled.note);
  prov.add("beta_asymptotic",
           std::string("3 z / (3 - z), the inverse of the large-S limit z = 3 beta / (beta + 3) "
                       "(no S scale needed; valid where z was measured in the scaling regime)"));
  if (!r.asymptotic.note.empty()) prov.add("beta_asymptotic_note", r.asymptotic.note);
  if (r.request.curve_fit) prov.add("curve_interval", r.curve.interval_method);
  if (!r.curve.note.empty()) prov.add("curve_fit_note", r.curve.note);
  for (std::size_t i = 0; i < r.input.notes.size(); ++i)
    prov.add("note." + std::to_string(i), r.input.notes[i]);
  return prov;
}

/// fit_beta.csv: one row, its columns named beside their values.
void writeFitBetaCsv(const std::string& path, const common::Provenance& prov,
                     const FitBetaResult& r, double beta_fit, bool force) {
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
          "beta_fit_determined: 0 when beta_fit lies at a bound of the search range (beta_fit "
          "is NaN then); NaN = not available"));
  const std::vector<std::pair<const char*, double>> columns = {
      {"z", r.z.z},
      {"z_low", r.z.z_low},
      {"z_high", r.z.z_high},
      {"t0", r.z.t0},
      {"t1", r.z.t1},
      {"n_points", static_cast<double>(r.z.points)},
      {"beta_from_z", r.from_z.beta},
      {"beta_from_z_low", r.from_z.beta_low},
      {"beta_from_z_high", r.from_z.beta_high},
      {"beta_fit", beta_fit},
      {"beta_fit_low", r.curve.beta_low},
      {"beta_fit_high", r.curve.beta_high},
      {"S_c", r.curve.S_c},
      {"S_c_low", r.curve.S_c_low},
      {"S_c_high", r.curve.S_c_high},
      {"tau_c", r.curve.tau_c},
      {"tau_c_low", r.curve.tau_c_low},
      {"tau_c_high", r.curve.tau_c_high},
      {"chi2_dof", r.curve.chi2_dof},
      {"S0", r.z.S0},
      {"S1", r.z.S1},
      {"n_runs", static_cast<double>(r.input.runs.size())},
      {"beta_from_z_scaled", r.from_z_scaled.beta},
      {"beta_from_z_scaled_low", r.from_z_scaled.beta_low},
      {"beta_from_z_scaled_high", r.from_z_scaled.beta_high},
      {"beta_asymptotic", r.asymptotic.beta},
      {"beta_asymptotic_low", r.asymptotic.beta_low},
      {"beta_asymptotic_high", r.asymptotic.beta_high},
      {"beta_fit_determined", !r.request.curve_fit ? NaN : (r.curve.at_bound ? 0.0 : 1.0)},
  };
  std::vector<std::string> names;
  std::vector<double> values;
  for (const auto& [name, value] : columns) {
    names.emplace_back(name);
    values.push_back(value);
  }
  common::CsvWriter w(path, sp, names, force);
  w.row(values);
  w.close();
}

/// fit_beta_curve.csv: the data beside the fitted mean field and the beta = 2, 3 curves.
void writeFitBetaCurve(const std::string& path, const common::Provenance& prov,
                       const FitBetaResult& r, bool beta_fit_known, bool force) {
  common::Provenance cp = prov;
  cp.add("columns",
         std::string(
             "t, S_md: the data (mean over runs); S_mf_fitted = S_c S_MF(t/tau_c; beta_fit) "
             "(NaN when beta_fit is not determined); "
             "S_mf_beta2, S_mf_beta3: the mean field for beta = 2 and 3 with the same S_c, tau_c"));
  common::CsvWriter w(path, cp, {"t", "S_md", "S_mf_fitted", "S_mf_beta2", "S_mf_beta3"}, force);
  for (std::size_t i = 0; i < r.data.t.size(); ++i)
    w.row({r.data.t[i], r.data.S[i], beta_fit_known ? r.curve.S_fitted[i] : NaN, r.S_mf_beta2[i],
           r.S_mf_beta3[i]});
  w.close();
}

/// fit_beta.json: every number of the result with the paper's values beside them (NaN and inf as
/// null; the notes say which).
nlohmann::ordered_json fitBetaJson(const FitBetaResult& r, const std::string& command_line,
                                   const common::PaperValues& paper, bool beta_fit_known,
                                   double beta_fit) {
  nlohmann::ordered_json j;
  j["version"] = common::versionString();
  j["command"] = command_line;
  j["input"] = r.input.source;
  j["column"] = r.input.column;
  j["n_runs"] = static_cast<long long>(r.input.runs.size());
  j["samples"] = static_cast<long long>(r.data.t.size());
  j["confidence"] = num(r.bootstrap.confidence);
  j["z"] = num(r.z.z);
  j["z_low"] = num(r.z.z_low);
  j["z_high"] = num(r.z.z_high);
  j["z_interval_method"] = r.z.interval_method;
  j["z_note"] = r.z.note;
  j["t0"] = num(r.z.t0);
  j["t1"] = num(r.z.t1);
  j["n_points"] = r.z.points;
  j["window_automatic"] = r.window.automatic;
  j["window_rule"] = r.window.rule;
  j["S0"] = num(r.z.S0);
  j["S1"] = num(r.z.S1);
  j["beta_from_z"] = num(r.from_z.beta);
  j["beta_from_z_low"] = num(r.from_z.beta_low);
  j["beta_from_z_high"] = num(r.from_z.beta_high);
  j["beta_from_z_note"] = r.from_z.note;
  j["beta_from_z_scaled"] = num(r.from_z_scaled.beta);
  j["beta_from_z_scaled_low"] = num(r.from_z_scaled.beta_low);
  j["beta_from_z_scaled_high"] = num(r.from_z_scaled.beta_high);
  j["beta_from_z_scaled_note"] = r.from_z_scaled.note;
  j["beta_asymptotic"] = num(r.asymptotic.beta);
  j["beta_asymptotic_low"] = num(r.asymptotic.beta_low);
  // +inf (z_high >= 3) is written as null like NaN; the note says which
  j["beta_asymptotic_high"] = num(r.asymptotic.beta_high);
  j["beta_asymptotic_note"] = r.asymptotic.note;
  j["z_mf_at_beta_min"] = num(r.from_z.z_at_beta_min);
  j["z_mf_at_beta_max"] = num(r.from_z.z_at_beta_max);
  j["z_mf_beta2_window"] = num(r.z_mf_beta2);
  j["z_mf_beta3_window"] = num(r.z_mf_beta3);
  j["curve_fit"] = r.request.curve_fit;
  j["beta_fit_determined"] = beta_fit_known;
  j["beta_fit"] = num(beta_fit);
  j["beta_fit_low"] = num(r.curve.beta_low);
  j["beta_fit_high"] = num(r.curve.beta_high);
  j["S_c"] = num(r.curve.S_c);
  j["S_c_low"] = num(r.curve.S_c_low);
  j["S_c_high"] = num(r.curve.S_c_high);
  j["tau_c"] = num(r.curve.tau_c);
  j["tau_c_low"] = num(r.curve.tau_c_low);
  j["tau_c_high"] = num(r.curve.tau_c_high);
  j["chi2_dof"] = num(r.curve.chi2_dof);
  j["curve_interval_method"] = r.curve.interval_method;
  j["curve_fit_note"] = r.curve.note;
  j["beta_min"] = num(r.request.beta_min);
  j["beta_max"] = num(r.request.beta_max);
  j["paper_z_neutral"] = num(paper.z_neutral);
  j["paper_z_neutral_err"] = num(paper.z_neutral_pm);
  j["paper_z_charged"] = num(paper.z_charged);
  j["paper_z_charged_err"] = num(paper.z_charged_pm);
  j["paper_z_mf_beta2"] = num(paper.z_meanfield_beta2);
  j["paper_z_mf_beta3"] = num(paper.z_meanfield_beta3);
  j["notes"] = r.input.notes;
  return j;
}

}  // namespace

void writeFitBeta(const FitBetaResult& r, const std::string& folder,
                  const std::string& command_line, const common::PaperValues& paper, bool force) {
  const FitBetaFiles f = fitBetaFiles(folder);
  // A beta at a bound of the search range is not a result: NaN in the CSVs, null in the JSON
  // (the bound is in curve_fit_note). S_c, tau_c stay: the best curve at that bound.
  const bool beta_fit_known = r.request.curve_fit && !r.curve.at_bound;
  const double beta_fit = beta_fit_known ? r.curve.beta : NaN;
  const common::FolderLock lock = common::FolderLock::acquire(folder, command_line, force);
  if (!r.request.curve_fit && force) fs::remove(f.curve);  // a stale curve would mislead
  const common::Provenance prov = fitBetaProvenance(r, command_line);
  writeFitBetaCsv(f.csv, prov, r, beta_fit, force);
  if (r.request.curve_fit) writeFitBetaCurve(f.curve, prov, r, beta_fit_known, force);
  writeJson(f.json, fitBetaJson(r, command_line, paper, beta_fit_known, beta_fit));
}

std::vector<std::string> fitBetaReport(const FitBetaResult& r, const common::PaperValues& paper) {
  std::vector<std::string> lines;
  lines.push_back(common::printfString(
      "%s column %s: %zu samples, %zu run%s", r.input.source.c_str(), r.input.column.c_str(),
      r.data.t.size(), r.input.runs.size(), r.input.runs.size() == 1 ? "" : "s"));
  for (const auto& n : r.input.notes)
    lines.push_back(common::printfString("  note: %s", n.c_str()));
  lines.push_back(common::printfString("window [%.4g, %.4g], %d samples (%s)", r.z.t0, r.z.t1,
                                       r.z.points, r.window.rule.c_str()));
  lines.push_back(common::printfString(
      "z = %s (95 %%, %s)   paper: %.2f +- %.2f neutral, %.2f +- %.3f charged",
      interval(r.z.z, r.z.z_low, r.z.z_high).c_str(), r.z.interval_method.c_str(), paper.z_neutral,
      paper.z_neutral_pm, paper.z_charged, paper.z_charged_pm));
  if (!r.z.note.empty()) lines.push_back(common::printfString("  note: %s", r.z.note.c_str()));
  lines.push_back(common::printfString(
      "beta from z = %s (full Smoluchowski z(beta) over S = %.4g..%.4g, where it gives z "
      "= %.4f at "
      "beta = 2, %.4f at beta = 3)   paper: mean field z = %.2f at beta = 2, %.2f at beta = 3",
      interval(r.from_z.beta, r.from_z.beta_low, r.from_z.beta_high).c_str(), r.from_z.S0,
      r.from_z.S1, r.z_mf_beta2, r.z_mf_beta3, paper.z_meanfield_beta2, paper.z_meanfield_beta3));
  if (!r.from_z.note.empty())
    lines.push_back(common::printfString("  note: %s", r.from_z.note.c_str()));
  lines.push_back(common::printfString(
      "beta from the asymptotic law z = 3 beta/(beta + 3) = %s (no S scale; valid where "
      "the local "
      "slope is flat)",
      interval(r.asymptotic.beta, r.asymptotic.beta_low, r.asymptotic.beta_high).c_str()));
  if (!r.asymptotic.note.empty())
    lines.push_back(common::printfString("  note: %s", r.asymptotic.note.c_str()));
  if (r.request.curve_fit) {
    lines.push_back(common::printfString(
        "beta from z at S / S_c = %.4g..%.4g (S_c from the curve fit) = %s", r.from_z_scaled.S0,
        r.from_z_scaled.S1,
        interval(r.from_z_scaled.beta, r.from_z_scaled.beta_low, r.from_z_scaled.beta_high)
            .c_str()));
    if (!r.from_z_scaled.note.empty())
      lines.push_back(common::printfString("  note: %s", r.from_z_scaled.note.c_str()));
    const std::string beta_fit =
        r.curve.at_bound ? "not determined (at the bound " + interval(r.curve.beta, NAN, NAN) +
                               " of the search range)"
                         : "= " + interval(r.curve.beta, r.curve.beta_low, r.curve.beta_high);
    lines.push_back(common::printfString(
        "beta from the curve fit %s, S_c = %s, tau_c = %s, chi2/dof = %.3g "
        "(%s)",
        beta_fit.c_str(), interval(r.curve.S_c, r.curve.S_c_low, r.curve.S_c_high).c_str(),
        interval(r.curve.tau_c, r.curve.tau_c_low, r.curve.tau_c_high).c_str(), r.curve.chi2_dof,
        r.curve.interval_method.c_str()));
    if (!r.curve.note.empty())
      lines.push_back(common::printfString("  note: %s", r.curve.note.c_str()));
  }
  return lines;
}

}  // namespace granagg::meanfield
