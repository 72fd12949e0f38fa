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

#include "analysis/io/Hdf5Lite.h"
#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Version.h"
#include "meanfield/fit/BetaFit.h"

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

/// Named numeric columns (column-major), from a CSV or an HDF5 group.
struct Columns {
  std::string source;
  std::vector<std::string> names;
  std::vector<std::vector<double>> values;
  bool has(const std::string& n) const {
    return std::find(names.begin(), names.end(), n) != names.end();
  }
  const std::vector<double>& get(const std::string& n) const {
    const auto it = std::find(names.begin(), names.end(), n);
    if (it == names.end())
      throw std::invalid_argument(source + " has no column '" + n + "' (columns: " + list() + ").");
    return values[static_cast<std::size_t>(it - names.begin())];
  }
  std::string list() const {
    std::string s;
    for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
    return s;
  }
};

Columns fromCsv(const std::string& path) {
  const common::CsvTable t = common::readCsv(path);
  Columns c;
  c.source = "'" + path + "'";
  c.names = t.columns;
  c.values.assign(t.columns.size(), {});
  for (const auto& row : t.rows)
    for (std::size_t j = 0; j < row.size(); ++j) c.values[j].push_back(row[j]);
  return c;
}

Columns fromH5Group(hid_t file, const std::string& group, const std::string& path) {
  namespace h5 = granagg::analysis::h5;
  Columns c;
  c.source = "'" + path + "' group " + group;
  h5::Handle g(H5Gopen2(file, group.c_str(), H5P_DEFAULT));
  if (!g) h5::fail("'" + path + "': cannot open " + group);
  for (const std::string& name : h5::children(g.get())) {
    if (h5::objectType(g.get(), name) != H5I_DATASET) continue;
    h5::Handle d(H5Dopen2(g.get(), name.c_str(), H5P_DEFAULT));
    if (!d) h5::fail("'" + path + "': cannot open " + group + "/" + name);
    c.names.push_back(name);
    c.values.push_back(
        h5::readAll<double>(d.get(), H5T_NATIVE_DOUBLE, "'" + path + "' " + group + "/" + name));
  }
  return c;
}

/// S(t) as read: times, one or several runs (or one series), what was read and notes.
struct Loaded {
  std::string source;
  std::string column;
  std::vector<double> t;
  std::vector<std::vector<double>> runs;  ///< one entry: a single series
  std::vector<std::string> notes;
};

/// Times rounded to 9 significant digits, to match rows across tables (as `granagg analyze` does).
double key9(double x) {
  if (x == 0.0 || !std::isfinite(x)) return x;
  const double scale = std::pow(10.0, 8 - static_cast<int>(std::floor(std::log10(std::fabs(x)))));
  return std::round(x * scale) / scale;
}

/// The default S column: S_grid_mean, else S_grid, else S, else the only column besides t (and
/// run).
std::string defaultColumn(const Columns& c, const std::string& input) {
  for (const char* n : {"S_grid_mean", "S_grid", "S"})
    if (c.has(n)) return n;
  std::vector<std::string> others;
  for (const auto& n : c.names)
    if (n != "t" && n != "run") others.push_back(n);
  if (others.size() == 1) return others.front();
  if (others.empty())
    throw std::invalid_argument("INPUT '" + input + "' has no S column besides t.");
  throw std::invalid_argument("INPUT '" + input + "' has several columns besides t (" + c.list() +
                              "); choose the S column with --column.");
}

/// Columns selected by --column NAME: NAME itself, else every column whose name starts with NAME
/// (runs).
std::vector<std::string> selectColumns(const Columns& c, const std::string& name,
                                       const std::string& input) {
  if (c.has(name)) return {name};
  std::vector<std::string> out;
  for (const auto& n : c.names)
    if (n != "t" && n.rfind(name, 0) == 0) out.push_back(n);
  if (out.empty())
    throw std::invalid_argument("INPUT '" + input + "' has no column '" + name +
                                "' nor columns starting with it (columns: " + c.list() + ").");
  return out;
}

void requireT(const Columns& c, const std::string& input) {
  if (!c.has("t"))
    throw std::invalid_argument("INPUT '" + input + "' has no column 't' (columns: " + c.list() +
                                ").");
}

/// Splits a long-format table (leading `run` column, as per_run/S_t.csv) into one Columns per run.
std::vector<Columns> splitRuns(const Columns& c) {
  const auto& run = c.get("run");
  std::map<double, std::vector<std::size_t>> rows;
  for (std::size_t i = 0; i < run.size(); ++i) rows[run[i]].push_back(i);
  std::vector<Columns> out;
  for (const auto& [r, idx] : rows) {
    Columns one;
    one.source = c.source + " run " + common::formatReal(r);
    one.names = c.names;
    one.values.assign(c.names.size(), {});
    for (std::size_t j = 0; j < c.names.size(); ++j)
      for (std::size_t i : idx) one.values[j].push_back(c.values[j][i]);
    out.push_back(std::move(one));
  }
  return out;
}

/// Puts the per-run series of `column` on the times `t` (matched to 9 digits); keeps the times that
/// every run holds. Returns false (with a note) when a run lacks the column.
bool alignRuns(const std::vector<Columns>& perRun, const std::string& column,
               std::vector<double>& t, std::vector<std::vector<double>>& runs,
               std::vector<std::string>& notes) {
  std::vector<std::map<double, double>> maps;
  for (const Columns& r : perRun) {
    if (!r.has("t") || !r.has(column)) {
      notes.push_back("per-run tables lack column '" + column + "': no interval over runs");
      return false;
    }
    std::map<double, double> m;
    const auto& rt = r.get("t");
    const auto& rs = r.get(column);
    for (std::size_t i = 0; i < rt.size(); ++i) m[key9(rt[i])] = rs[i];
    maps.push_back(std::move(m));
  }
  std::vector<double> kept;
  runs.assign(maps.size(), {});
  for (double x : t) {
    bool all = true;
    for (const auto& m : maps) all = all && m.count(key9(x));
    if (!all) continue;
    kept.push_back(x);
    for (std::size_t r = 0; r < maps.size(); ++r) runs[r].push_back(maps[r].at(key9(x)));
  }
  if (kept.size() < t.size())
    notes.push_back(std::to_string(t.size() - kept.size()) +
                    " times not held by every run were left out");
  t = kept;
  return true;
}

/// The ensemble mean S column (c_mean) and its per-run column c, read from an ensemble table and
/// the per-run tables (analyze folder or analysis.h5).
Loaded loadEnsemble(const Columns& ens, const std::vector<Columns>& perRun,
                    const std::string& input, const std::string& columnArg,
                    const std::string& source) {
  requireT(ens, input);
  Loaded L;
  L.source = source;
  const std::string col = columnArg.empty() ? defaultColumn(ens, input) : columnArg;
  const auto cols = selectColumns(ens, col, input);
  if (cols.size() > 1)
    throw std::invalid_argument("INPUT '" + input + "': --column '" + col +
                                "' matches several columns (" + std::to_string(cols.size()) +
                                "); name one of them.");
  L.column = cols.front();
  L.t = ens.get("t");
  const std::string suffix = "_mean";
  const bool isMean = L.column.size() > suffix.size() &&
                      L.column.compare(L.column.size() - suffix.size(), suffix.size(), suffix) == 0;
  if (isMean && perRun.size() >= 2) {
    const std::string base = L.column.substr(0, L.column.size() - suffix.size());
    std::vector<double> t = L.t;
    std::vector<std::vector<double>> runs;
    if (alignRuns(perRun, base, t, runs, L.notes)) {
      L.t = t;
      L.runs = runs;
      L.notes.push_back("S = mean of " + std::to_string(runs.size()) + " runs' " + base +
                        " (the ensemble " + L.column + "); intervals over runs");
      return L;
    }
  }
  L.runs = {ens.get(L.column)};
  return L;
}

Loaded loadH5(const std::string& path, const std::string& columnArg) {
  namespace h5 = granagg::analysis::h5;
  h5::silenceErrors();
  h5::Handle f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!f) throw std::invalid_argument("INPUT '" + path + "' cannot be opened as HDF5.");
  if (h5::objectType(f.get(), "/ensemble/S_t") != H5I_GROUP)
    throw std::invalid_argument(
        "INPUT '" + path +
        "' has no /ensemble/S_t group (expected an analysis.h5 written by granagg analyze).");
  const Columns ens = fromH5Group(f.get(), "/ensemble/S_t", path);
  std::vector<Columns> perRun;
  if (h5::objectType(f.get(), "/runs") == H5I_GROUP) {
    h5::Handle runs(H5Gopen2(f.get(), "/runs", H5P_DEFAULT));
    std::vector<std::string> names = h5::children(runs.get());
    std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
      return a.size() != b.size() ? a.size() < b.size() : a < b;
    });
    for (const auto& k : names)
      if (h5::objectType(f.get(), "/runs/" + k + "/S_t") == H5I_GROUP)
        perRun.push_back(fromH5Group(f.get(), "/runs/" + k + "/S_t", path));
  }
  return loadEnsemble(ens, perRun, path, columnArg, "'" + path + "' /ensemble/S_t");
}

Loaded loadCsv(const std::string& path, const std::string& columnArg) {
  const Columns c = fromCsv(path);
  requireT(c, path);
  if (c.has("run")) {  // long format, one block of rows per run (per_run/S_t.csv)
    const auto per = splitRuns(c);
    Loaded L;
    L.source = "'" + path + "'";
    L.column = columnArg.empty() ? defaultColumn(c, path) : columnArg;
    if (!c.has(L.column))
      throw std::invalid_argument("INPUT '" + path + "' has no column '" + L.column +
                                  "' (columns: " + c.list() + ").");
    L.t = per.front().get("t");
    if (!alignRuns(per, L.column, L.t, L.runs, L.notes))
      throw std::invalid_argument("INPUT '" + path + "': runs differ.");
    L.notes.push_back(std::to_string(per.size()) + " runs from the 'run' column");
    return L;
  }
  Loaded L;
  L.source = "'" + path + "'";
  const std::string col = columnArg.empty() ? defaultColumn(c, path) : columnArg;
  const auto cols = selectColumns(c, col, path);
  L.column = cols.size() == 1 ? cols.front() : col + "*";
  L.t = c.get("t");
  for (const auto& n : cols) L.runs.push_back(c.get(n));
  if (cols.size() > 1)
    L.notes.push_back(std::to_string(cols.size()) + " run columns matching '" + col + "*'");
  return L;
}

Loaded load(const std::string& input, const std::string& columnArg) {
  if (input.empty())
    throw std::invalid_argument("INPUT is required (an analyze folder, a CSV or an analysis.h5).");
  const fs::path p(input);
  if (fs::is_directory(p)) {
    const fs::path st = p / "S_t.csv";
    if (!fs::exists(st))
      throw std::invalid_argument("INPUT folder '" + input +
                                  "' has no S_t.csv (expected a `granagg analyze` output folder).");
    const Columns ens = fromCsv(st.string());
    std::vector<Columns> perRun;
    const fs::path pr = p / "per_run" / "S_t.csv";
    if (fs::exists(pr)) {
      const Columns c = fromCsv(pr.string());
      if (c.has("run")) perRun = splitRuns(c);
    }
    return loadEnsemble(ens, perRun, st.string(), columnArg, "'" + st.string() + "'");
  }
  if (!fs::exists(p)) throw std::invalid_argument("INPUT '" + input + "' does not exist.");
  granagg::analysis::h5::silenceErrors();
  if (H5Fis_hdf5(input.c_str()) > 0) return loadH5(input, columnArg);
  return loadCsv(input, columnArg);
}

/// Drops the rows with t = 0 (fits are in log t) and the rows where S is NaN in the series or in
/// any run (`granagg analyze` writes NaN where a frame has no cluster); rejects negative or
/// non-finite t. Infinite or non-positive S stays, for validateGrowthData to reject.
void dropUnusableRows(Loaded& L) {
  std::size_t zero = 0, missing = 0;
  std::vector<double> t;
  std::vector<std::vector<double>> runs(L.runs.size());
  for (std::size_t i = 0; i < L.t.size(); ++i) {
    if (!std::isfinite(L.t[i]) || L.t[i] < 0.0)
      throw std::invalid_argument(
          "INPUT " + L.source + ": t must be non-negative and finite (t = " +
          common::formatReal(L.t[i]) + " at row " + std::to_string(i + 1) + ").");
    if (L.t[i] == 0.0) {
      ++zero;
      continue;
    }
    bool nan = false;
    for (const auto& r : L.runs) nan = nan || std::isnan(r[i]);
    if (nan) {
      ++missing;
      continue;
    }
    t.push_back(L.t[i]);
    for (std::size_t r = 0; r < runs.size(); ++r) runs[r].push_back(L.runs[r][i]);
  }
  if (zero)
    L.notes.push_back(std::to_string(zero) + " row(s) at t = 0 left out (fits are in log t)");
  if (missing)
    L.notes.push_back(std::to_string(missing) + " row(s) with S = NaN (no cluster" +
                      (L.runs.size() > 1 ? std::string(" in some run") : std::string()) +
                      ") left out");
  L.t = t;
  L.runs = runs;
}

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
  Loaded L = load(a.input, a.column);
  dropUnusableRows(L);
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
