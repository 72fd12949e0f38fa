/// \file Summary.cpp
/// What a study found: summary.json (nlohmann-json), summary.txt and the summary on the terminal,
/// from the tables its steps wrote (PairStudy.h, Summary.h).
#include "study/Summary.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <sstream>

#include "common/Csv.h"
#include "common/Strings.h"
#include "common/Version.h"
#include "study/PairStudy.h"
#include "study/Process.h"

namespace granagg::study {
namespace fs = std::filesystem;
using common::formatReal;
using nlohmann::ordered_json;

namespace {

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

/// printf into a std::string.
template <typename... Args>
std::string strf(const char* format, Args... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, format, args...);
  return buf;
}

/// A number for text: 3 significant digits below 100 (1.35, 57.3), whole above (513, 1234);
/// "n/a" when not finite.
std::string g3(double v) {
  if (!std::isfinite(v)) return "n/a";
  return std::abs(v) >= 100 ? strf("%.0f", v) : strf("%.3g", v);
}
/// A count for text (N = 50016, 20 runs).
std::string whole(double v) { return std::isfinite(v) ? strf("%.0f", v) : "n/a"; }
/// A number for text with fixed decimals, "n/a" when not finite.
std::string fx(double v, int decimals = 2) {
  return std::isfinite(v) ? strf("%.*f", decimals, v) : "n/a";
}
/// A time for text: 4 significant digits (t = 1000, 31.62, 0.5016), whole from 1e4 on.
std::string tt(double v) {
  if (!std::isfinite(v)) return "n/a";
  return std::abs(v) >= 1e4 ? strf("%.0f", v) : strf("%.4g", v);
}

/// analyze's fits.csv: z of S_grid over its window and the onset time.
void readFits(const fs::path& fits, EnsembleResult& r) {
  if (!fs::exists(fits)) return;
  try {
    const common::CsvTable t = common::readCsv(fits.string());
    if (t.rows.empty()) return;
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
  } catch (const std::exception&) {
  }
}

/// analyze's S_t.csv: the regime of the ensemble-mean S_grid and its local slope.
void readGrowth(const fs::path& st, const StudyServices& s, EnsembleResult& r) {
  r.regime.regime = "unknown";
  if (!fs::exists(st)) return;
  try {
    const common::CsvTable t = common::readCsv(st.string());
    std::vector<double> time, S, z;
    const std::size_t cz =
        t.column(t.hasColumn("z_local_grid_of_mean") ? "z_local_grid_of_mean" : "z_local_grid");
    for (const auto& row : t.rows) {
      time.push_back(row[t.column("t")]);
      S.push_back(row[t.column("S_grid_mean")]);
      z.push_back(row[cz]);
    }
    for (std::size_t k = time.size(); k-- > 0;)
      if (std::isfinite(S[k]) && S[k] > 0 && time[k] > 0) {
        r.t_last = time[k];
        break;
      }
    r.regime = s.classify_growth(time, S, z);
    r.slope = slopeTrend(time, S, z, s.flat_slope_tolerance);
  } catch (const std::exception&) {
  }
}

/// fit-beta's fit_beta.json (false when absent or cut).
bool readFitBeta(const fs::path& fj, EnsembleResult& r) {
  if (!fs::exists(fj)) return false;
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(readText(fj));
  } catch (const std::exception&) {
    return false;  // (a cut file: reported as no fit)
  }
  r.fz = number(j, "z");
  r.fz_low = number(j, "z_low");
  r.fz_high = number(j, "z_high");
  r.bz = number(j, "beta_from_z");
  r.bz_low = number(j, "beta_from_z_low");
  r.bz_high = number(j, "beta_from_z_high");
  r.ba = number(j, "beta_asymptotic");
  r.ba_low = number(j, "beta_asymptotic_low");
  r.ba_high = number(j, "beta_asymptotic_high");
  r.bf = number(j, "beta_fit");
  r.bf_low = number(j, "beta_fit_low");
  r.bf_high = number(j, "beta_fit_high");
  r.bf_min = number(j, "beta_min");
  r.bf_max = number(j, "beta_max");
  // fit-beta's own rule (meanfield/fit/BetaFit.cpp): a beta within 1e-4 of the range of a bound
  // is not determined by the data. Files that wrote such a beta as a number are read the same.
  const double edge = 1e-4 * (r.bf_max - r.bf_min);
  const bool at_bound = std::isfinite(edge) && (r.bf <= r.bf_min + edge || r.bf >= r.bf_max - edge);
  const auto flag = j.find("beta_fit_determined");
  const bool flagged_no = flag != j.end() && flag->is_boolean() && !flag->get<bool>();
  r.bf_determined = std::isfinite(r.bf) && !at_bound && !flagged_no;
  if (!r.bf_determined) r.bf = r.bf_low = r.bf_high = NAN;
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
  return true;
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

/// "neutral gas" or "charged gas".
std::string gasName(double K) { return K == 0 ? "neutral gas" : "charged gas"; }

/// The local slope's trend in words: "rising", ..., or why there is none.
std::string trendWords(const SlopeTrend& s) {
  return s.direction.empty() ? "fewer than 3 local slopes in the last half decade"
                             : "local slope " + s.direction;
}

/// `text` broken at spaces into lines of at most `width` columns (a longer word stays whole);
/// continuation lines are indented by the first line's leading spaces plus `hang`.
std::string wrap(const std::string& text, std::size_t width = 100, std::size_t hang = 2) {
  const std::size_t lead = std::min(text.find_first_not_of(' '), text.size());
  const std::string indent(lead + hang, ' ');
  std::string out, line(lead, ' ');
  bool fresh = true;  // no word on `line` yet
  std::istringstream words(text);
  for (std::string w; words >> w;) {
    if (!fresh && line.size() + 1 + w.size() > width) {
      out += line + "\n";
      line = indent;
      fresh = true;
    }
    line += (fresh ? "" : " ") + w;
    fresh = false;
  }
  return out + line + "\n";
}

/// The validation study's row for an ensemble, in words.
std::string validationText(const ValidationRow& v, double K) {
  if (!v.found)
    return "validation study: no ensemble at K = " + formatReal(K) + " (docs/validation.md)";
  return "validation study (docs/validation.md): " + whole(v.runs) + " runs of N = " + whole(v.N) +
         " to t = " + tt(v.t_end) + ": S_grid x" + g3(v.growth_factor) +
         ", onset t_c = " + g3(v.onset) + ", local slope " + fx(v.zloc_min) + ".." +
         fx(v.zloc_max) + " over the last half decade: " +
         (v.power_law ? "a power law, z = " + fx(v.z) + " [" + fx(v.z_low) + ", " + fx(v.z_high) +
                            "] over t = " + tt(v.t0) + ".." + tt(v.t1)
                      : std::string("no power law"));
}

}  // namespace

SlopeTrend slopeTrend(const std::vector<double>& t, const std::vector<double>& S,
                      const std::vector<double>& z, double flat_tolerance) {
  SlopeTrend s;
  double t_last = NAN;
  for (std::size_t k = std::min({t.size(), S.size(), z.size()}); k-- > 0;)
    if (std::isfinite(S[k]) && S[k] > 0 && t[k] > 0) {
      t_last = t[k];
      break;
    }
  if (!std::isfinite(t_last)) return s;
  std::vector<double> x, y;  // ln t, z over [t_last / sqrt(10), t_last]
  for (std::size_t k = 0; k < std::min(t.size(), z.size()); ++k)
    if (t[k] > 0 && t[k] >= t_last / std::sqrt(10.0) && t[k] <= t_last && std::isfinite(z[k])) {
      if (x.empty()) s.t0 = t[k], s.first = z[k];
      s.t1 = t[k];
      s.last = z[k];
      x.push_back(std::log(t[k]));
      y.push_back(z[k]);
    }
  s.n = x.size();
  if (s.n == 0) return s;
  s.min = *std::min_element(y.begin(), y.end());
  s.max = *std::max_element(y.begin(), y.end());
  if (s.n < 3) return s;
  double mx = 0, my = 0;
  for (std::size_t k = 0; k < s.n; ++k) mx += x[k] / s.n, my += y[k] / s.n;
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < s.n; ++k)
    sxy += (x[k] - mx) * (y[k] - my), sxx += (x[k] - mx) * (x[k] - mx);
  const double spread = s.max - s.min;
  // least-squares change of z across the stretch (robust to one noisy end point)
  const double change = sxx > 0 ? sxy / sxx * (x.back() - x.front()) : 0.0;
  if (spread <= flat_tolerance * std::abs(my))
    s.direction = "flat";
  else if (change >= 0.5 * spread)
    s.direction = "rising";
  else if (change <= -0.5 * spread)
    s.direction = "falling";
  else
    s.direction = "varying";
  return s;
}

EnsembleResult readEnsemble(const fs::path& out, double K, const StudyServices& s) {
  EnsembleResult r;
  r.K = K;
  readFits(out / "analysis" / kName(K) / "fits.csv", r);
  readGrowth(out / "analysis" / kName(K) / "S_t.csv", s, r);
  r.has_fit = readFitBeta(out / "fit" / kName(K) / "fit_beta.json", r);
  return r;
}

ReportedZ reportedZ(const EnsembleResult& r, int runs) {
  ReportedZ z;
  const std::string& regime = r.regime.regime;
  if (regime == "none") {
    z.status = "no growth";
    z.text = "none (S has not doubled by t = " + tt(r.t_last) + ": no aggregation to measure)";
    return z;
  }
  if (regime == "onset") {
    z.status = "no power law";
    z.text = "no power law (" + trendWords(r.slope) + ")";
    return z;
  }
  if (regime != "scaling") {
    z.status = "unknown";
    z.text = "n/a (no S(t) table: the analysis did not run or failed)";
    return z;
  }
  if (std::isfinite(r.fz)) {
    z.source = "fit-beta";
    z.value = r.fz, z.low = r.fz_low, z.high = r.fz_high, z.t0 = r.w0, z.t1 = r.w1;
  } else {
    z.source = "analyze";
    z.value = r.z, z.low = r.z_low, z.high = r.z_high, z.t0 = r.fit_t_min, z.t1 = r.fit_t_max;
  }
  const std::string window = "over t = " + tt(z.t0) + ".." + tt(z.t1);
  // A growth exponent whose interval reaches 0 (or has none) is not measured by these runs.
  if (!(z.low > 0) || !std::isfinite(z.value)) {
    z.status = "not resolved";
    z.text = "not resolved with " + std::to_string(runs) + " run" + (runs == 1 ? "" : "s") +
             " (the 95 % interval " + window + " includes 0)";
    return z;
  }
  z.status = "power law";
  z.text = "z = " + fx(z.value) + " [" + fx(z.low) + ", " + fx(z.high) + "] " + window +
           " (95 % interval over " + std::to_string(runs) + " run" + (runs == 1 ? "" : "s") +
           (z.source == "fit-beta" ? "; fit-beta's window, where the local slope is flat)"
                                   : "; analyze's window)");
  return z;
}

ValidationRow readValidation(double K, const StudyServices& s) {
  ValidationRow v;
  for (const auto& d : s.data_dirs) {
    const fs::path p = fs::path(d) / "validation" / "verdict.csv";
    if (!fs::exists(p)) continue;
    try {
      const common::CsvTable t = common::readCsv(p.string());
      for (const auto& row : t.rows) {
        if (std::abs(row[t.column("K")] - K) > 1e-12 || row[t.column("quantity_id")] != 1.0)
          continue;
        const auto at = [&](const char* c) { return row[t.column(c)]; };
        v.found = true;
        v.N = at("N"), v.runs = at("runs"), v.t_end = at("t_end");
        v.z = at("value"), v.z_low = at("low"), v.z_high = at("high");
        v.t0 = at("t0"), v.t1 = at("t1"), v.onset = at("onset");
        v.growth_factor = at("growth_factor");
        v.zloc_min = at("zloc_min"), v.zloc_max = at("zloc_max");
        v.power_law =
            v.zloc_max - v.zloc_min <= s.flat_slope_tolerance * 0.5 * (v.zloc_max + v.zloc_min);
        return v;
      }
      return v;
    } catch (const std::exception&) {
    }
  }
  return v;
}

std::vector<std::string> ensembleLines(const EnsembleFindings& e) {
  const EnsembleResult& r = e.r;
  std::vector<std::string> l;
  l.push_back("K = " + formatReal(r.K) + ", " + gasName(r.K) +
              (r.K != 0 && std::isfinite(e.charging_Q) ? " (Q = " + g3(e.charging_Q) + ")" : "") +
              ": " + std::to_string(e.runs) + " run" + (e.runs == 1 ? "" : "s") +
              " of N = " + std::to_string(e.N) + " to t = " + tt(e.t_end));
  const std::string onset =
      std::isfinite(r.onset)
          ? "onset t_c = " + g3(r.onset) +
                (std::isfinite(r.onset_err) ? " +- " + g3(r.onset_err) : std::string())
          : "no onset (S_grid never reached twice its early value)";
  static const std::map<std::string, std::string> regime_words{
      {"none", "none (S has not doubled: no aggregation yet)"},
      {"onset", "onset (S grows, its local slope still changes: not yet a power law)"},
      {"scaling", "scaling (the local slope is flat: a power law)"},
      {"unknown", "unknown (no S(t) table)"}};
  const auto w = regime_words.find(r.regime.regime);
  l.push_back("  growth: S_grid x" + g3(r.regime.growth_factor) + " by t = " + tt(r.t_last) + "; " +
              onset + "; regime: " + (w != regime_words.end() ? w->second : r.regime.regime));
  const SlopeTrend& s = r.slope;
  if (s.n == 0)
    l.push_back("  local slope: none over the last half decade");
  else
    l.push_back("  local slope: " + fx(s.first) + " at t = " + tt(s.t0) + " -> " + fx(s.last) +
                " at t = " + tt(s.t1) + " (range " + fx(s.min) + ".." + fx(s.max) +
                " over the last half decade)" + (s.direction.empty() ? "" : ": " + s.direction));
  const ReportedZ z = reportedZ(r, e.runs);
  l.push_back("  z: " + z.text);
  if (z.status != "power law") {
    l.push_back("  beta: none (no growth exponent to map onto the mean field)");
  } else {
    std::string b = "  beta: ";
    b += std::isfinite(r.ba)
             ? fx(r.ba) + " [" + fx(r.ba_low) + ", " + fx(r.ba_high) +
                   "] from z by the asymptotic law z = 3 beta / (beta + 3)"
             : "n/a from z (" + (r.notes.empty() ? "fit-beta gave none" : r.notes) + ")";
    b += r.bf_determined
             ? "; full-curve fit " + fx(r.bf) + " [" + fx(r.bf_low) + ", " + fx(r.bf_high) + "]"
             : "; full-curve fit: not determined (at a bound of its search range)";
    l.push_back(b);
  }
  if (e.fit_status != "done" && (z.status == "power law" || e.fit_status.rfind("failed", 0) == 0))
    l.push_back("  fit-beta: " + e.fit_status);
  l.push_back("  " + validationText(e.validation, r.K));
  l.push_back("  paper: " + formatReal(e.paper_z) + " +- " + formatReal(e.paper_z_pm) +
              (r.K == 0 ? " (neutral)" : " (charged, K = 5; the paper finds z independent of K)"));
  return l;
}

std::vector<std::string> verdictLines(const StudyFindings& f) {
  std::vector<std::string> l;
  double onset_neutral = NAN;
  for (const auto& e : f.ensembles)
    if (e.r.K == 0) onset_neutral = e.r.onset;
  for (const auto& e : f.ensembles) {
    const EnsembleResult& r = e.r;
    const ReportedZ z = reportedZ(r, e.runs);
    std::string s = "The " + gasName(r.K) + " (K = " + formatReal(r.K) + ") ";
    if (z.status == "unknown") {
      l.push_back(s + "has no results: its analysis is missing (see pair.log).");
      continue;
    }
    if (z.status == "no growth") {
      l.push_back(s + "does not aggregate within its runs: S_grid x" + g3(r.regime.growth_factor) +
                  " by t = " + tt(r.t_last) + " (less than 2). Too short for a growth exponent.");
      continue;
    }
    s += "aggregates";
    if (std::isfinite(r.onset)) {
      s += " from t_c = " + g3(r.onset);
      if (r.K != 0 && onset_neutral > r.onset)
        s += ", " + g3(onset_neutral / r.onset) + " times earlier than the neutral gas";
    }
    s += " (S_grid x" + g3(r.regime.growth_factor) + " by t = " + tt(r.t_last) + ")";
    if (z.status == "no power law")
      s += ", but S(t) is not a power law yet (" + trendWords(r.slope) +
           (std::isfinite(r.slope.first) && std::isfinite(r.slope.last)
                ? " from " + fx(r.slope.first) + " to " + fx(r.slope.last)
                : std::string()) +
           "): these runs give no growth exponent z and no beta.";
    else if (z.status == "not resolved")
      s += " as a power law, but its exponent z is " + z.text + ".";
    else
      s += " as a power law: " + z.text.substr(0, z.text.find(" (95 %")) + "; paper " +
           formatReal(e.paper_z) + " +- " + formatReal(e.paper_z_pm) + ".";
    l.push_back(s);
  }
  std::string mf, mf_paper;
  bool mf_agrees = !f.meanfield.empty();
  for (const auto& m : f.meanfield) {
    mf += (mf.empty() ? "" : ", ") + fx(m.z_local, 3) + " at S ~ " + g3(m.S) +
          " (beta = " + formatReal(m.beta) + ")";
    if (std::isfinite(m.paper_z)) {
      mf_paper += (mf_paper.empty() ? "" : " and ") + formatReal(m.paper_z);
      mf_agrees &= std::abs(m.z_local - m.paper_z) <= 0.005;  // the paper's 2 decimals
    }
  }
  if (!mf.empty())
    l.push_back("The mean field (Smoluchowski equation, beta kernel) has local slopes " + mf +
                (mf_paper.empty()
                     ? "."
                     : (mf_agrees ? ": the paper's " : "; the paper: ") + mf_paper + "."));
  // The validation study's conclusion, from its rows for the K of this study.
  std::string rows, paper_z;
  bool any = false, all_no_power_law = true;
  for (const auto& e : f.ensembles) {
    const ValidationRow& v = e.validation;
    if (!v.found) continue;
    const std::string pz = formatReal(e.paper_z) + (e.r.K == 0 ? " neutral" : " charged");
    if (paper_z.find(pz) == std::string::npos) paper_z += (paper_z.empty() ? "" : ", ") + pz;
    any = true;
    all_no_power_law &= !v.power_law;
    rows += (rows.empty() ? "" : "; ") + std::string("K = ") + formatReal(e.r.K) + ": " +
            whole(v.runs) + " runs of N = " + whole(v.N) + " to t = " + tt(v.t_end) + ", " +
            (v.power_law ? "z = " + fx(v.z) + " [" + fx(v.z_low) + ", " + fx(v.z_high) + "]"
                         : "local slope " + fx(v.zloc_min) + ".." + fx(v.zloc_max));
  }
  if (!any)
    l.push_back("The validation study (docs/validation.md) has no ensemble at these K.");
  else if (all_no_power_law)
    l.push_back(
        "The validation study (docs/validation.md) concluded, from larger and longer "
        "ensembles, that S(t) has no power law within the paper's times (" +
        rows + "): the paper's growth exponents (" + paper_z +
        ") are not reproduced, and there is no beta from MD.");
  else
    l.push_back("The validation study (docs/validation.md), larger and longer ensembles: " + rows +
                ".");
  return l;
}

std::string summaryText(const StudyFindings& f) {
  std::string t = "granagg pair study '" + f.name + "': summary (" + f.out.string() + ")\n\n";
  t += "VERDICT\n";
  for (const auto& line : verdictLines(f)) t += wrap("- " + line);
  t += "\nPER ENSEMBLE (z is given only where S(t) is a power law: a flat local slope)\n";
  for (const auto& e : f.ensembles) {
    for (const auto& line : ensembleLines(e)) t += wrap(line, 100, 4);
    t += "\n";
  }
  t += wrap(
      "Every number, with both fits of z (analyze's over the last decade, fit-beta's where "
      "the local slope is flat) and fit-beta's notes: summary.json; the figures and this "
      "summary: report.html.");
  if (f.bytes > 0)  // (the command on a line of its own, unbroken, to copy)
    t += wrap("The results take " + strf("%.0f", static_cast<double>(f.bytes) / (1 << 20)) +
              " MiB (mostly runs/: the trajectories). Delete them all with:") +
         "  rm -r " + shellQuote(f.out.string()) + "\n";
  return t;
}

std::uintmax_t folderBytes(const fs::path& dir) {
  std::uintmax_t total = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec),
       end;
       !ec && it != end; it.increment(ec)) {
    std::error_code e2;
    if (it->is_regular_file(e2) && !it->is_symlink(e2)) {
      const std::uintmax_t n = it->file_size(e2);
      if (!e2) total += n;
    }
  }
  return total;
}

namespace {

/// The findings of a study folder (what summary.txt and the terminal say).
StudyFindings findings(const fs::path& out, const PairConfig& c, const StudyServices& s,
                       const std::map<std::string, MdPlan>& md,
                       const std::function<std::string(double)>& fit_status) {
  StudyFindings f;
  f.name = c.name;
  f.out = out;
  for (double K : c.K) {
    EnsembleFindings e;
    e.r = readEnsemble(out, K, s);
    e.runs = c.runs;
    const MdPlan& plan = md.at(kName(K));
    e.N = plan.N;
    e.t_end = plan.t_end;
    e.charging_Q = plan.charging_Q;
    e.fit_status = fit_status(K);
    e.validation = readValidation(K, s);
    e.paper_z = K == 0 ? s.paper.z_neutral : s.paper.z_charged;
    e.paper_z_pm = K == 0 ? s.paper.z_neutral_pm : s.paper.z_charged_pm;
    f.ensembles.push_back(e);
  }
  for (double b : c.betas) {
    MeanFieldFinding m;
    m.beta = b;
    m.S = b == 2 ? s.paper.S_beta2 : s.paper.S_beta3;
    m.z_local = localSlopeAt(out / "meanfield" / ("S_beta" + formatReal(b) + ".csv"), m.S);
    m.paper_z = b == 2 ? s.paper.z_meanfield_beta2 : b == 3 ? s.paper.z_meanfield_beta3 : NAN;
    f.meanfield.push_back(m);
  }
  return f;
}

/// A validation row for summary.json (null when the study has none for this K).
ordered_json validationJson(const ValidationRow& v) {
  if (!v.found) return nullptr;
  return {{"N", num(v.N)},
          {"runs", num(v.runs)},
          {"t_end", num(v.t_end)},
          {"z", interval(v.z, v.z_low, v.z_high)},
          {"z_window", {num(v.t0), num(v.t1)}},
          {"onset_time", num(v.onset)},
          {"growth_factor", num(v.growth_factor)},
          {"local_slope_range", {num(v.zloc_min), num(v.zloc_max)}},
          {"power_law", v.power_law}};
}

/// One ensemble of summary.json: the summary's lines and every number behind them.
ordered_json ensembleJson(const EnsembleFindings& f, const MdPlan& plan) {
  const EnsembleResult& r = f.r;
  const ReportedZ z = reportedZ(r, f.runs);
  ordered_json e{
      {"K", r.K},
      {"name", kName(r.K)},
      {"runs", f.runs},
      {"N", plan.N},
      {"phi", plan.phi},
      {"t_end", plan.t_end},
      {"charging_Q", plan.charging_Q},
      {"summary", ensembleLines(f)},
      {"z_reported",
       {{"status", z.status},
        {"value", num(z.value)},
        {"low", num(z.low)},
        {"high", num(z.high)},
        {"window", {num(z.t0), num(z.t1)}},
        {"source", z.source},
        {"text", z.text}}},
      {"local_slope",
       {{"t0", num(r.slope.t0)},
        {"t1", num(r.slope.t1)},
        {"first", num(r.slope.first)},
        {"last", num(r.slope.last)},
        {"min", num(r.slope.min)},
        {"max", num(r.slope.max)},
        {"direction", r.slope.direction}}},
      {"z_analyze", interval(r.z, r.z_low, r.z_high)},
      {"z_analyze_window", {num(r.fit_t_min), num(r.fit_t_max)}},
      {"z_analyze_method", std::string("grid clusters, least squares of ln S on ln t, 95% ") +
                               (f.runs > 1 ? "bootstrap over runs" : "Student t")},
      {"fit_beta", f.fit_status},
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
      {"validation", validationText(f.validation, r.K)},
      {"validation_study", validationJson(f.validation)},
      {"paper_z", num(f.paper_z)},
      {"paper_z_pm", num(f.paper_z_pm)}};
  if (r.K != 0) e["paper_note"] = "the paper's charged value (K = 5)";
  return e;
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
                 {"written", common::utcTimestamp()},
                 {"cores", m_cores},
                 {"backend", m_s.backend}};
  s["paper"] = {{"reference", paper.reference},
                {"z_neutral", num(paper.z_neutral)},
                {"z_neutral_pm", num(paper.z_neutral_pm)},
                {"z_charged", num(paper.z_charged)},
                {"z_charged_pm", num(paper.z_charged_pm)},
                {"z_meanfield_beta2", num(paper.z_meanfield_beta2)},
                {"z_meanfield_beta3", num(paper.z_meanfield_beta3)}};
  const auto fit_status = [this](double K) -> std::string {
    const std::string k = kName(K);
    return fs::exists(m_out / "fit" / k / "fit_beta.json") ? "done"
           : m_fit_note.count(k)                           ? m_fit_note.at(k)
           : m_status.count("fit")                         ? m_status.at("fit")
                                                           : "not run";
  };
  StudyFindings found = findings(m_out, m_c, m_s, m_md, fit_status);
  s["verdict"] = verdictLines(found);
  ordered_json ensembles = ordered_json::array();
  for (const EnsembleFindings& f : found.ensembles)
    ensembles.push_back(ensembleJson(f, m_md.at(kName(f.r.K))));
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
  found.bytes = folderBytes(m_out);
  s["results_bytes"] = found.bytes;
  writeText(m_out / "summary.json", s.dump(2) + "\n");
  writeText(m_out / "summary.txt", summaryText(found));
}

void PairStudy::printSummary() {
  if (m_a.quiet) return;
  std::fprintf(stderr, "pair: ---- summary (also in %s) ----\n%s", (m_out / "summary.txt").c_str(),
               readText(m_out / "summary.txt").c_str());
  std::fprintf(stderr, "pair: wrote %s (summary.txt, summary.json%s) in %.0f s\n", m_out.c_str(),
               fs::exists(m_out / "report.html") ? ", report.html, figures/" : "", seconds());
}

}  // namespace granagg::study
