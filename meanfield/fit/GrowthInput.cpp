/// \file GrowthInput.cpp
/// Reading S(t) for the beta fit (GrowthInput.h).
#include "meanfield/fit/GrowthInput.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "common/Csv.h"
#include "common/Hdf5.h"
#include "common/Strings.h"

namespace granagg::meanfield {
namespace fs = std::filesystem;

namespace {

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
  namespace h5 = common::h5;
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
GrowthInput loadEnsemble(const Columns& ens, const std::vector<Columns>& perRun,
                         const std::string& input, const std::string& columnArg,
                         const std::string& source) {
  requireT(ens, input);
  GrowthInput L;
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

GrowthInput loadH5(const std::string& path, const std::string& columnArg) {
  namespace h5 = common::h5;
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

GrowthInput loadCsv(const std::string& path, const std::string& columnArg) {
  const Columns c = fromCsv(path);
  requireT(c, path);
  if (c.has("run")) {  // long format, one block of rows per run (per_run/S_t.csv)
    const auto per = splitRuns(c);
    GrowthInput L;
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
  GrowthInput L;
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

}  // namespace

GrowthInput readGrowthInput(const std::string& input, const std::string& columnArg) {
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
  common::h5::silenceErrors();
  if (H5Fis_hdf5(input.c_str()) > 0) return loadH5(input, columnArg);
  return loadCsv(input, columnArg);
}

std::string dropUnusableRows(GrowthInput& L) {
  std::size_t zero = 0, missing = 0;
  std::vector<double> t;
  std::vector<std::vector<double>> runs(L.runs.size());
  // per run: how many rows have S = NaN, and the first and last such time
  std::vector<std::size_t> nan_rows(L.runs.size(), 0);
  std::vector<double> nan_first(L.runs.size(), 0.0), nan_last(L.runs.size(), 0.0);
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
    for (std::size_t r = 0; r < L.runs.size(); ++r)
      if (std::isnan(L.runs[r][i])) {
        nan = true;
        if (nan_rows[r]++ == 0) nan_first[r] = L.t[i];
        nan_last[r] = L.t[i];
      }
    if (nan) {
      ++missing;
      continue;
    }
    t.push_back(L.t[i]);
    for (std::size_t r = 0; r < runs.size(); ++r) runs[r].push_back(L.runs[r][i]);
  }
  std::vector<std::string> added;
  if (zero) added.push_back(std::to_string(zero) + " row(s) at t = 0 left out (fits are in log t)");
  if (missing) {
    // which runs and times: NaN is what analyze writes for a frame without a cluster (for
    // S_grid: no grid cell reached the occupation threshold)
    std::string where;
    for (std::size_t r = 0; r < L.runs.size(); ++r) {
      if (nan_rows[r] == 0) continue;
      where += (where.empty() ? "" : "; ") +
               (L.runs.size() > 1 ? "run " + std::to_string(r) : std::string("the series")) +
               " at " + std::to_string(nan_rows[r]) + " time(s), t = " +
               common::printfString("%.4g", nan_first[r]) +
               (nan_rows[r] > 1 ? common::printfString(" .. %.4g", nan_last[r]) : std::string());
    }
    // the runs' own column: S_grid for the ensemble's S_grid_mean
    std::string column = L.column;
    const std::string mean = "_mean";
    if (L.runs.size() > 1 && column.size() > mean.size() &&
        column.compare(column.size() - mean.size(), mean.size(), mean) == 0)
      column.resize(column.size() - mean.size());
    added.push_back(std::to_string(missing) + " row(s) with " + column + " = NaN left out (" +
                    where + "): frames without a cluster, e.g. no occupied grid cell");
  }
  L.notes.insert(L.notes.end(), added.begin(), added.end());
  L.t = t;
  L.runs = runs;
  return common::join(added, "; ");
}

}  // namespace granagg::meanfield
