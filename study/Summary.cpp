/// \file Summary.cpp
/// What a study found: summary.json (nlohmann-json) and the summary on the terminal, from the
/// tables its steps wrote (PairStudy.h).
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/Csv.h"
#include "common/Version.h"
#include "study/PairStudy.h"
#include "study/Process.h"

namespace granagg::study {
namespace fs = std::filesystem;
using common::formatReal;
using nlohmann::ordered_json;

namespace {

/// Per-K numbers for the summary (NaN where a table is missing).
struct EnsembleResult {
  double K = 0;
  double z = NAN, z_low = NAN, z_high = NAN, fit_t_min = NAN, fit_t_max = NAN, runs = NAN;
  double fz = NAN, fz_low = NAN, fz_high = NAN, bz = NAN, bz_low = NAN, bz_high = NAN;
  double bf = NAN, bf_low = NAN, bf_high = NAN, S_c = NAN, tau_c = NAN, w0 = NAN, w1 = NAN;
  double ba = NAN, ba_low = NAN, ba_high = NAN;  ///< beta from the asymptotic law 3 z / (3 - z)
  bool bf_determined = true;                     ///< false when the curve fit ended at a bound
  double onset = NAN, onset_err = NAN;           ///< onset time of S_grid (analyze's fits.csv)
  GrowthSummary regime;                          ///< of the ensemble-mean S_grid (S_t.csv)
  bool has_fit = false;
  std::string notes;  ///< fit-beta's notes on beta (clamped, no beta, at a bound)
};

/// A number of a JSON object; NaN when absent or null (fit-beta writes NaN and inf as null).
double number(const nlohmann::json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : NAN;
}

/// A number for summary.json: NaN and inf as null.
ordered_json num(double x) { return std::isfinite(x) ? ordered_json(x) : ordered_json(nullptr); }

ordered_json interval(double v, double lo, double hi) {
  return {{"value", num(v)}, {"low", num(lo)}, {"high", num(hi)}};
}

/// The validation study's result for this K (data/validation/verdict.csv, written by
/// scripts/validation_report.py, described in docs/validation.md): one sentence, or "" when the
/// study has no row for K.
std::string validationLine(double K, const StudyServices& s) {
  for (const auto& d : s.data_dirs) {
    const fs::path p = fs::path(d) / "validation" / "verdict.csv";
    if (!fs::exists(p)) continue;
    try {
      const common::CsvTable t = common::readCsv(p.string());
      for (const auto& row : t.rows) {
        if (std::abs(row[t.column("K")] - K) > 1e-12 || row[t.column("quantity_id")] != 1.0)
          continue;
        char buf[600];
        std::snprintf(buf, sizeof buf,
                      "validation study (docs/validation.md; N = %.0f, %.0f runs to t = %.0f): z = "
                      "%.2f [%.2f, %.2f] over "
                      "t = %.0f..%.0f, onset t_c = %.0f, growth x%.0f; local slope %.2f..%.2f over "
                      "the last half "
                      "decade%s",
                      row[t.column("N")], row[t.column("runs")], row[t.column("t_end")],
                      row[t.column("value")], row[t.column("low")], row[t.column("high")],
                      row[t.column("t0")], row[t.column("t1")], row[t.column("onset")],
                      row[t.column("growth_factor")], row[t.column("zloc_min")],
                      row[t.column("zloc_max")],
                      row[t.column("zloc_max")] - row[t.column("zloc_min")] >
                              s.flat_slope_tolerance * 0.5 *
                                  (row[t.column("zloc_max")] + row[t.column("zloc_min")])
                          ? ": not a power law"
                          : "");
        return buf;
      }
    } catch (const std::exception&) {
    }
  }
  return "";
}

EnsembleResult readEnsemble(const fs::path& out, double K, const StudyServices& s) {
  EnsembleResult r;
  r.K = K;
  const fs::path fits = out / "analysis" / kName(K) / "fits.csv";
  if (fs::exists(fits)) {
    try {
      const common::CsvTable t = common::readCsv(fits.string());
      if (!t.rows.empty()) {
        const auto& row = t.rows.front();
        r.z = row[t.column("z_grid")];
        r.z_low = row[t.column("z_grid_low")];
        r.z_high = row[t.column("z_grid_high")];
        r.fit_t_min = row[t.column("fit_t_min")];
        r.fit_t_max = row[t.column("fit_t_max")];
        r.runs = row[t.column("runs")];
        if (t.hasColumn("onset_time_grid")) {
          r.onset = row[t.column("onset_time_grid")];
          r.onset_err = row[t.column("onset_time_grid_err")];
        }
      }
    } catch (const std::exception&) {
    }
  }
  const fs::path st = out / "analysis" / kName(K) / "S_t.csv";
  r.regime.regime = "unknown";
  if (fs::exists(st)) {
    try {
      const common::CsvTable t = common::readCsv(st.string());
      std::vector<double> tt, S, z;
      for (const auto& row : t.rows) {
        tt.push_back(row[t.column("t")]);
        S.push_back(row[t.column("S_grid_mean")]);
        z.push_back(row[t.column(t.hasColumn("z_local_grid_of_mean") ? "z_local_grid_of_mean"
                                                                     : "z_local_grid")]);
      }
      r.regime = s.classify_growth(tt, S, z);
    } catch (const std::exception&) {
    }
  }
  const fs::path fj = out / "fit" / kName(K) / "fit_beta.json";
  if (fs::exists(fj)) {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(readText(fj));
    } catch (const std::exception&) {
      return r;  // (a cut file: reported as no fit)
    }
    r.has_fit = true;
    r.fz = number(j, "z");
    r.fz_low = number(j, "z_low");
    r.fz_high = number(j, "z_high");
    r.bz = number(j, "beta_from_z");
    r.bz_low = number(j, "beta_from_z_low");
    r.bz_high = number(j, "beta_from_z_high");
    r.bf = number(j, "beta_fit");
    r.bf_low = number(j, "beta_fit_low");
    r.bf_high = number(j, "beta_fit_high");
    r.ba = number(j, "beta_asymptotic");
    r.ba_low = number(j, "beta_asymptotic_low");
    r.ba_high = number(j, "beta_asymptotic_high");
    r.bf_determined = j.value("beta_fit_determined", true);
    r.S_c = number(j, "S_c");
    r.tau_c = number(j, "tau_c");
    r.w0 = number(j, "t0");
    r.w1 = number(j, "t1");
    if (!std::isfinite(r.w0) && j.contains("window") && j["window"].is_array() &&
        j["window"].size() == 2 && j["window"][0].is_number() && j["window"][1].is_number()) {
      r.w0 = j["window"][0].get<double>();  // (an older fit_beta.json: "window": [t0, t1])
      r.w1 = j["window"][1].get<double>();
    }
    for (const char* key : {"beta_from_z_note", "beta_asymptotic_note", "curve_fit_note"}) {
      const auto n = j.find(key);
      if (n != j.end() && n->is_string() && !n->get<std::string>().empty())
        r.notes += (r.notes.empty() ? "" : " ") + n->get<std::string>();
    }
  }
  return r;
}

/// Local slope z of a mean-field S(t) table where S first reaches `S_target` (NaN if never).
double localSlopeAt(const fs::path& csv, double S_target) {
  if (!fs::exists(csv)) return NAN;
  try {
    const common::CsvTable t = common::readCsv(csv.string());
    const std::size_t cs = t.column("S"), cz = t.column("z_local");
    for (const auto& row : t.rows)
      if (row[cs] >= S_target) return row[cz];
  } catch (const std::exception&) {
  }
  return NAN;
}

}  // namespace

void PairStudy::writeSummary() {
  const common::PaperValues& paper = m_s.paper;
  ordered_json s{{"granagg", common::versionString()},
                 {"study", m_c.name},
                 {"config", (m_out / "config" / "pair.toml").string()},
                 {"source_config", m_c.source},
                 {"out", m_out.string()},
                 {"command", m_s.command_line},
                 {"written", nowUtc()},
                 {"cores", m_cores},
                 {"backend", m_s.backend}};
  s["paper"] = {{"reference", paper.reference},
                {"z_neutral", num(paper.z_neutral)},
                {"z_neutral_pm", num(paper.z_neutral_pm)},
                {"z_charged", num(paper.z_charged)},
                {"z_charged_pm", num(paper.z_charged_pm)},
                {"z_meanfield_beta2", num(paper.z_meanfield_beta2)},
                {"z_meanfield_beta3", num(paper.z_meanfield_beta3)}};
  ordered_json ensembles = ordered_json::array();
  for (double K : m_c.K) {
    const EnsembleResult r = readEnsemble(m_out, K, m_s);
    const MdPlan& plan = m_md.at(kName(K));
    const std::string fit_status = r.has_fit                    ? "done"
                                   : m_fit_note.count(kName(K)) ? m_fit_note.at(kName(K))
                                   : m_status.count("fit")      ? m_status.at("fit")
                                                                : "not run";
    ordered_json e{
        {"K", K},
        {"name", kName(K)},
        {"runs", m_c.runs},
        {"N", plan.N},
        {"phi", plan.phi},
        {"t_end", plan.t_end},
        {"charging_Q", plan.charging_Q},
        {"z_analyze", interval(r.z, r.z_low, r.z_high)},
        {"z_analyze_window", {num(r.fit_t_min), num(r.fit_t_max)}},
        {"z_analyze_method", std::string("grid clusters, least squares of ln S on ln t, 95% ") +
                                 (m_c.runs > 1 ? "bootstrap over runs" : "Student t")},
        {"fit_beta", fit_status},
        {"z", interval(r.fz, r.fz_low, r.fz_high)},
        {"fit_window", {num(r.w0), num(r.w1)}},
        {"beta_from_z", interval(r.bz, r.bz_low, r.bz_high)},
        {"beta_asymptotic", interval(r.ba, r.ba_low, r.ba_high)},
        {"beta_asymptotic_applicable", r.regime.regime == "scaling"},
        {"beta_fit", interval(r.bf, r.bf_low, r.bf_high)},
        {"beta_fit_determined", r.bf_determined},
        {"S_c", num(r.S_c)},
        {"tau_c", num(r.tau_c)},
        {"fit_notes", r.notes},
        {"growth_factor", num(r.regime.growth_factor)},
        {"onset_time", num(r.onset)},
        {"onset_time_se", num(r.onset_err)},
        {"regime", r.regime.regime},
        {"regime_reason", r.regime.reason},
        {"validation", validationLine(K, m_s)},
        {"paper_z", num(K == 0 ? paper.z_neutral : paper.z_charged)},
        {"paper_z_pm", num(K == 0 ? paper.z_neutral_pm : paper.z_charged_pm)}};
    if (K != 0) e["paper_note"] = "the paper's charged value (K = 5)";
    ensembles.push_back(e);
  }
  s["ensembles"] = ensembles;
  common::CsvTable zb;
  bool has_zb = false;
  if (fs::exists(m_out / "meanfield" / "zbeta.csv")) {
    try {
      zb = common::readCsv((m_out / "meanfield" / "zbeta.csv").string());
      has_zb = true;
    } catch (const std::exception&) {
    }
  }
  ordered_json meanfield = ordered_json::array();
  for (double b : m_c.betas) {
    double zinf = NAN;
    if (has_zb)
      for (const auto& row : zb.rows)
        if (std::abs(row[zb.column("beta")] - b) < 1e-9) zinf = row[zb.column("z_asymptotic")];
    const fs::path csv = m_out / "meanfield" / ("S_beta" + formatReal(b) + ".csv");
    meanfield.push_back({{"beta", b},
                         {"z_scaling", 3 * b / (b + 3)},
                         {"z_asymptotic", num(zinf)},
                         {"z_local_S250", num(localSlopeAt(csv, paper.S_beta2))},
                         {"z_local_S1650", num(localSlopeAt(csv, paper.S_beta3))},
                         {"paper_z", b == 2   ? num(paper.z_meanfield_beta2)
                                     : b == 3 ? num(paper.z_meanfield_beta3)
                                              : ordered_json(nullptr)}});
  }
  s["meanfield"] = meanfield;
  s["steps"] = ordered_json(m_status);
  ordered_json timings = ordered_json::object();
  for (const auto& [k, v] : m_timing) timings[k] = std::round(v * 100) / 100;
  timings["total"] = std::round(seconds() * 100) / 100;
  s["timings_s"] = timings;
  ordered_json commands = ordered_json::array({m_s.command_line});
  std::istringstream cmds(readText(m_out / "commands.txt"));
  for (std::string line; std::getline(cmds, line);)
    if (!line.empty()) commands.push_back(line);
  s["commands"] = commands;
  writeText(m_out / "summary.json", s.dump(2) + "\n");
}

namespace {

std::string fmt(double v, int prec = 3) {
  if (!std::isfinite(v)) return "n/a";
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

}  // namespace

void PairStudy::printSummary() {
  if (m_a.quiet) return;
  const common::PaperValues& paper = m_s.paper;
  std::fprintf(stderr, "pair: ---- summary (%s) ----\n", (m_out / "summary.json").c_str());
  for (double K : m_c.K) {
    const EnsembleResult r = readEnsemble(m_out, K, m_s);
    std::fprintf(stderr, "pair: K = %-5s z = %s [%s, %s] (analyze, grid, t in [%s, %s])",
                 formatReal(K).c_str(), fmt(r.z).c_str(), fmt(r.z_low).c_str(),
                 fmt(r.z_high).c_str(), fmt(r.fit_t_min, 3).c_str(), fmt(r.fit_t_max, 3).c_str());
    std::fprintf(stderr, "   paper: %s +- %s%s\n",
                 formatReal(K == 0 ? paper.z_neutral : paper.z_charged).c_str(),
                 formatReal(K == 0 ? paper.z_neutral_pm : paper.z_charged_pm).c_str(),
                 K == 0 ? "" : " (K = 5)");
    std::fprintf(stderr, "pair:           regime: %s (%s)\n", r.regime.regime.c_str(),
                 r.regime.reason.c_str());
    const std::string v = validationLine(K, m_s);
    if (!v.empty()) std::fprintf(stderr, "pair:           %s\n", v.c_str());
    if (r.has_fit)
      std::fprintf(
          stderr,
          "pair:           fit-beta: z = %s [%s, %s], beta from z at the data's S %s, asymptotic "
          "beta %s, "
          "full-curve beta = %s\n",
          fmt(r.fz).c_str(), fmt(r.fz_low).c_str(), fmt(r.fz_high).c_str(),
          (std::isfinite(r.bz)
               ? "= " + fmt(r.bz, 2) + " [" + fmt(r.bz_low, 2) + ", " + fmt(r.bz_high, 2) + "]"
               : std::string("n/a (z outside the mean field's range there)"))
              .c_str(),
          (r.regime.regime == "scaling"
               ? "= " + fmt(r.ba, 2) + " [" + fmt(r.ba_low, 2) + ", " + fmt(r.ba_high, 2) + "]"
               : "not applicable (no scaling regime; 3z/(3-z) would give " + fmt(r.ba, 2) + ")")
              .c_str(),
          r.bf_determined
              ? (fmt(r.bf, 2) + " [" + fmt(r.bf_low, 2) + ", " + fmt(r.bf_high, 2) + "]").c_str()
              : "not determined (at the bound of its range)");
    if (r.has_fit && !r.notes.empty())
      std::fprintf(stderr, "pair:           fit-beta note: %.200s%s\n", r.notes.c_str(),
                   r.notes.size() > 200 ? "..." : "");
    if (!r.has_fit)
      std::fprintf(stderr, "pair:           fit-beta: %s\n",
                   m_fit_note.count(kName(K)) ? m_fit_note.at(kName(K)).c_str()
                   : m_status.count("fit")    ? m_status.at("fit").c_str()
                                              : "not run");
  }
  for (double b : m_c.betas) {
    const fs::path csv = m_out / "meanfield" / ("S_beta" + formatReal(b) + ".csv");
    const double S_paper = b == 2 ? paper.S_beta2 : paper.S_beta3;
    const std::string paper_z = b == 2   ? "   paper: " + formatReal(paper.z_meanfield_beta2)
                                : b == 3 ? "   paper: " + formatReal(paper.z_meanfield_beta3)
                                         : "";
    std::fprintf(stderr,
                 "pair: mean field beta = %s: z(S ~ %g) = %s, asymptotic 3 beta/(beta+3) = %s%s\n",
                 formatReal(b).c_str(), S_paper, fmt(localSlopeAt(csv, S_paper)).c_str(),
                 fmt(3 * b / (b + 3)).c_str(), paper_z.c_str());
  }
  std::fprintf(stderr, "pair: wrote %s (summary.json%s) in %.0f s\n", m_out.c_str(),
               fs::exists(m_out / "report.html") ? ", report.html, figures/" : "", seconds());
}

}  // namespace granagg::study
