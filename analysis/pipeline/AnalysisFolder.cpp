/// \file AnalysisFolder.cpp
/// The analyze output folder (AnalysisFolder.h).
#include "analysis/pipeline/AnalysisFolder.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include "analysis/io/AnalysisFile.h"
#include "analysis/stats/PowerLawFit.h"
#include "common/FolderLock.h"
#include "common/H5Journal.h"
#include "common/OutputPath.h"
#include "common/Strings.h"

namespace granagg::analysis {
namespace fs = std::filesystem;

void checkAnalysisFolderRequest(const AnalysisFolderRequest& request) {
  if (request.runs.empty())
    throw std::invalid_argument("give at least one RUN (traj.h5, a run folder or a LAMMPS dump).");
  std::set<fs::path> seen;
  for (const auto& r : request.runs) {
    if (!fs::exists(r))
      throw std::invalid_argument("no such trajectory or run folder: '" + r + "'");
    // a run still being written is read only when it has finished (its file is incomplete)
    const fs::path folder = fs::is_directory(r) ? fs::path(r) : fs::path(r).parent_path();
    if (const auto holder = common::FolderLock::liveHolder(folder.empty() ? "." : folder))
      throw std::invalid_argument("run '" + r + "' is being written by " + holder->describe() +
                                  ": analyse it when that command has finished");
    // the ensemble statistics treat runs as independent samples: one run twice is not two
    fs::path canonical = fs::weakly_canonical(r);
    if (canonical.filename().empty()) canonical = canonical.parent_path();  // "dir/" = "dir"
    if (!seen.insert(canonical).second)
      throw std::invalid_argument("run '" + r +
                                  "' is given twice: an ensemble needs independent runs");
  }
  const fs::path out(request.out);
  if (fs::exists(out) && !fs::is_directory(out))
    throw std::invalid_argument("--out '" + out.string() +
                                "' is a file, not a folder; analyze writes a folder");
  common::checkOutputFolder(out, "--out");  // read-only, or below a file: refused before reading
  common::FolderLock::checkAvailable(out, request.force);
  if (fs::exists(out) && !fs::is_empty(out) && !request.force)
    throw std::invalid_argument(
        "output folder '" + out.string() +
        "' exists and is not empty; choose another --out or pass --force to overwrite it");
}

namespace {

/// The tables of analysed runs into `out` (per_run/ must exist) and `file`, which it closes.
AnalysisFolder writeTables(const fs::path& out, AnalysisFile& file, std::vector<RunResult> results,
                           const AnalysisOptions& o, const std::string& command_line, bool force) {
  const std::vector<Table> ensemble = analyzeEnsemble(results, o);
  const common::Provenance prov = analysisProvenance(command_line, o, results);

  // Per-run tables (long format, leading run column) and ensemble tables.
  for (const Table& t : results.front().tables) {
    std::vector<const Table*> all;
    for (const auto& r : results)
      if (r.hasTable(t.name)) all.push_back(&r.table(t.name));
    writeCsv(stackRuns(all), (out / "per_run" / (t.name + ".csv")).string(), prov, force);
  }
  for (const Table& t : ensemble) writeCsv(t, (out / (t.name + ".csv")).string(), prov, force);

  for (std::size_t k = 0; k < results.size(); ++k) {
    const auto& r = results[k];
    const std::string g = "runs/" + std::to_string(k);
    for (const auto& t : r.tables) file.writeTable(g, t);
    std::map<std::string, std::string> attrs{
        {"source", r.source},
        {"format", r.format},
        {"frames", std::to_string(r.frames)},
        {"particles", std::to_string(r.particles)},
        {"partial", r.partial ? r.partial_reason : "no"},
        {"kappa", common::formatReal(r.kappa) + " (" + r.kappa_source + ")"},
        {"grid_cells_per_side", std::to_string(r.grid_cells)},
        {"grid_cell_size", common::formatReal(r.grid_cell_size)},
        {"grid_min_count", common::formatReal(r.grid_min_count)}};
    std::string notes;
    for (const auto& n : r.notes) notes += (notes.empty() ? "" : "; ") + n;
    attrs["notes"] = notes;
    for (const auto& [key, v] : r.parameters) attrs["parameters." + key] = v;
    file.writeAttributes(g, attrs);
  }
  for (const auto& t : ensemble) file.writeTable("ensemble", t);
  std::map<std::string, std::string> root;
  for (const auto& [key, v] : prov.parameters()) root[key] = v;
  file.writeAttributes("ensemble", root);
  file.close();
  return {std::move(results), ensemble};
}

}  // namespace

AnalysisFolder analyseIntoFolder(
    const AnalysisFolderRequest& request, const AnalysisOptions& o,
    const std::function<void(std::size_t, std::size_t, std::size_t)>& progress) {
  checkAnalysisFolderRequest(request);
  const fs::path out(request.out);
  common::FolderLock lock = common::FolderLock::acquire(out, request.command_line, request.force);
  fs::create_directories(out / "per_run");

  // analysis.h5 is opened first so that --write-grid streams one frame at a time into it; a
  // failed analysis removes it (no half-written file is left behind).
  const std::string h5path = (out / "analysis.h5").string();
  auto file = std::make_unique<AnalysisFile>(h5path, request.force,
                                             analysisProvenance(request.command_line, o, {}));
  std::vector<RunResult> results;
  try {
    for (std::size_t k = 0; k < request.runs.size(); ++k) {
      RunCallbacks cb;
      if (progress)
        cb.progress = [&progress, k](std::size_t frame, std::size_t hint) {
          progress(k, frame, hint);
        };
      if (request.write_grid)
        cb.grid = [&](const Frame& f, const GridClusters& g) { file->writeGridFrame(k, f, g); };
      std::optional<RunResult> stored;
      if (request.stored_result) stored = request.stored_result(request.runs[k]);
      results.push_back(stored ? std::move(*stored) : analyzeRun(request.runs[k], o, cb));
      checkSameSystem(results.front(), results.back());  // before analysing the rest
    }
    // inside the try: a table that cannot be written (a full disk) leaves no folder behind
    // that would pass for a complete analysis
    return writeTables(out, *file, std::move(results), o, request.command_line, request.force);
  } catch (...) {
    file.reset();
    std::error_code ec;
    fs::remove(h5path, ec);
    fs::remove(common::h5journal::journalPathFor(h5path), ec);  // (kept after a failed write)
    // nothing left that would block the rerun: a folder made here goes, an empty per_run too
    if (lock.createdFolder()) {
      lock.release();
      fs::remove_all(out, ec);
    } else {
      fs::remove(out / "per_run", ec);
    }
    throw;
  }
}

AnalysisFolder writeRunAnalysis(const std::string& out_path, RunResult result,
                                const AnalysisOptions& o, const std::string& command_line) {
  const fs::path out(out_path);
  if (fs::exists(out))
    throw std::invalid_argument("analysis folder '" + out.string() +
                                "' exists already: the in-situ analysis never overwrites one");
  // written beside its name and renamed at the end: a failure leaves no half-written folder
  fs::path tmp = out;
  tmp += ".partial";
  std::error_code ec;
  fs::remove_all(tmp, ec);
  try {
    fs::create_directories(tmp / "per_run");
    AnalysisFile file((tmp / "analysis.h5").string(), false,
                      analysisProvenance(command_line, o, {}));
    std::vector<RunResult> results;
    results.push_back(std::move(result));
    AnalysisFolder folder = writeTables(tmp, file, std::move(results), o, command_line, false);
    fs::rename(tmp, out);
    return folder;
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

common::Provenance analysisProvenance(const std::string& command_line, const AnalysisOptions& o,
                                      const std::vector<RunResult>& runs) {
  common::Provenance p(command_line);
  for (std::size_t k = 0; k < runs.size(); ++k) {
    p.add(
        "run." + std::to_string(k),
        runs[k].source + " (" + runs[k].format + ", " + std::to_string(runs[k].frames) +
            " frames, N = " + std::to_string(runs[k].particles) +
            (runs[k].grid_cells > 0
                 ? ", grid " + std::to_string(runs[k].grid_cells) +
                       "^3 cells of h = " + common::formatReal(runs[k].grid_cell_size) +
                       ", occupied at >= " + common::formatReal(runs[k].grid_min_count) + " centres"
                 : std::string()) +
            (runs[k].partial ? ", PARTIAL" : "") + ")");
  }
  p.add("grid_spacing", o.grid.spacing);
  p.add("grid_min_fill", o.grid.min_fill);
  p.add("grid_min_count_option", o.grid.min_count);
  p.add("grid_assign",
        std::string(o.grid.assignment == GridAssignment::CloudInCell ? "cic" : "ngp"));
  p.add("particle_tolerance", o.particle.tolerance);
  p.add("slope_ratio_p", o.slope_ratio);
  p.add("fit_window", o.fit_t_min > 0 || o.fit_t_max > 0
                          ? common::formatReal(o.fit_t_min) + " " + common::formatReal(o.fit_t_max)
                          : std::string("last decade [t_last/10, t_last]"));
  p.add("charge_fit_window",
        common::formatReal(o.charge_fit_t_min) + " " + common::formatReal(o.charge_fit_t_max));
  p.add("mle_min_tail", static_cast<long long>(o.mle_min_tail));
  p.add("speed_max", o.speed_max);
  p.add("speed_bins", o.speed_bins);
  p.add("msd_origins", o.msd_origins);
  p.add("kappa", runs.empty() ? o.kappa : runs.front().kappa);
  p.add("kappa_source", runs.empty() ? std::string("option") : runs.front().kappa_source);
  p.add("track", static_cast<long long>(o.track));
  p.add("bootstrap_replicates", o.bootstrap_replicates);
  p.add("bootstrap_seed", static_cast<long long>(o.bootstrap_seed));
  p.add("onset_factor", o.onset_factor);
  p.add("onset_baseline", o.onset_t_base);
  p.add("fisher_bin_ratio", o.fisher_bin_ratio);
  return p;
}

std::vector<std::string> analysisReport(const AnalysisFolder& folder) {
  std::vector<std::string> lines;
  for (std::size_t k = 0; k < folder.runs.size(); ++k) {
    const auto& r = folder.runs[k];
    lines.push_back(common::printfString("run %zu: %s (%s): %zu frames, N = %zu%s", k,
                                         r.source.c_str(), r.format.c_str(), r.frames, r.particles,
                                         r.partial ? " [PARTIAL]" : ""));
    if (r.grid_cells > 0)
      lines.push_back(common::printfString(
          "  grid: %d^3 cells of h = %.4g d, occupied at >= %g centres per cell", r.grid_cells,
          r.grid_cell_size, r.grid_min_count));
    for (const auto& n : r.notes) lines.push_back("  note: " + n);
  }
  for (const auto& t : folder.ensemble)
    if (t.name == "fits" && !t.rows.empty()) {
      const auto& row = t.rows.front();
      auto c = [&](const char* name) { return row[t.column(name)]; };
      // no exponent (too few frames, S constant: analysisWarnings says which) reads n/a
      auto z = [&](const std::string& kind) {
        const double v = c(("z_" + kind).c_str());
        return std::isfinite(v) ? common::printfString("%.4g [%.4g, %.4g]", v,
                                                       c(("z_" + kind + "_low").c_str()),
                                                       c(("z_" + kind + "_high").c_str()))
                                : std::string("n/a");
      };
      lines.push_back(common::printfString(
          "z (grid) = %s, z (particle) = %s over t in [%.4g, %.4g] (%s)", z("grid").c_str(),
          z("particle").c_str(), c("fit_t_min"), c("fit_t_max"),
          folder.runs.size() > 1 ? "95% bootstrap over runs" : "95% Student t"));
      if (std::isfinite(c("charging_rate_exponent")))
        lines.push_back(common::printfString(
            "d<|q|>/dt ~ t^%.4g [%.4g, %.4g]; expected -5/6 - 5 kappa/3 = %.4g (kappa = "
            "%g, %s)",
            c("charging_rate_exponent"), c("charging_rate_low"), c("charging_rate_high"),
            c("charging_rate_expected"), c("kappa"), folder.runs.front().kappa_source.c_str()));
      if (std::isfinite(c("onset_time_grid")))
        lines.push_back(common::printfString(
            "onset (S_grid reaches %g x its median %.4g over t <= %g) at t_c = %.4g",
            c("onset_factor"), c("onset_S_base_grid"), c("onset_t_base"), c("onset_time_grid")));
    }
  return lines;
}

std::vector<std::string> analysisWarnings(const AnalysisFolder& folder,
                                          const AnalysisOptions& o) {
  std::vector<std::string> lines;
  using common::formatReal;
  // A run stopped before its end: the last frame lies more than a step before run.t_end (the
  // final step is the nearest whole step to t_end, within dt / 2 of it).
  for (std::size_t k = 0; k < folder.runs.size(); ++k) {
    const RunResult& r = folder.runs[k];
    const auto t_end_text = r.parameters.find("run.t_end");
    const auto dt_text = r.parameters.find("dt");
    double t_end = 0.0, dt = 0.0;
    if (t_end_text == r.parameters.end() || !common::parseReal(t_end_text->second, t_end) ||
        !(t_end > 0.0) || !r.hasTable("S_t"))
      continue;
    if (dt_text == r.parameters.end() || !common::parseReal(dt_text->second, dt) || !(dt > 0.0))
      dt = 1e-9 * t_end;
    const std::vector<double> t = r.table("S_t").values("t");
    if (!t.empty() && t.back() < t_end - dt)
      lines.push_back("run " + std::to_string(k) + " (" + r.source + ") ends at t = " +
                      formatReal(t.back()) + ", before its run.t_end = " + formatReal(t_end) +
                      ": an unfinished run (granagg md --restart on its folder continues it)");
  }
  // The growth-exponent window: the frames a fit would use (fitPowerLaw's rule, 3 at least).
  const Table* st = nullptr;
  for (const Table& t : folder.ensemble)
    if (t.name == "S_t") st = &t;
  if (!st && !folder.runs.empty() && folder.runs.front().hasTable("S_t"))
    st = &folder.runs.front().table("S_t");
  if (st && !st->rows.empty()) {
    const std::vector<double> t = st->values("t");
    const bool given = o.fit_t_min > 0 || o.fit_t_max > 0;
    const double w0 = given ? o.fit_t_min : t.back() / 10.0;
    const double w1 = given && o.fit_t_max > 0 ? o.fit_t_max : t.back();
    std::size_t inside = 0;
    for (double x : t)
      inside += x > 0 && x >= w0 * (1 - WINDOW_SLACK) && x <= w1 * (1 + WINDOW_SLACK);
    const std::string window =
        std::string(given ? "--fit-window" : "the growth-exponent window (the last decade)") +
        common::printfString(" [%.4g, %.4g]", w0, w1);
    if (inside < 3)
      lines.push_back(window + " holds " + std::to_string(inside) + " frame" +
                      (inside == 1 ? "" : "s") + " (a fit needs 3; the frames span t = " +
                      common::printfString("%.4g .. %.4g", t.front(), t.back()) +
                      "): z is NaN in fits.csv");
    // S the same at every frame of the window: no growth to fit (PowerLawFitResult::constant)
    auto has = [&](const std::string& name) {
      return std::find(st->columns.begin(), st->columns.end(), name) != st->columns.end();
    };
    for (const std::string kind : {"grid", "particle"}) {
      const std::string col = has("S_" + kind + "_mean") ? "S_" + kind + "_mean" : "S_" + kind;
      if (inside < 3 || !has(col)) continue;
      const std::vector<double> S = st->values(col);
      double lo = INFINITY, hi = -INFINITY;
      std::size_t used = 0;
      for (std::size_t k = 0; k < t.size(); ++k)
        if (t[k] > 0 && t[k] >= w0 * (1 - WINDOW_SLACK) && t[k] <= w1 * (1 + WINDOW_SLACK) &&
            S[k] > 0 && std::isfinite(S[k])) {
          lo = std::min(lo, std::log(S[k]));
          hi = std::max(hi, std::log(S[k]));
          ++used;
        }
      if (used >= 3 && hi - lo <= 1e-12)
        lines.push_back(col + " is " + common::printfString("%.4g", std::exp(lo)) +
                        " at every frame of " +
                        window + ": S does not grow there, so z (" + kind +
                        ") is n/a (NaN in fits.csv)");
    }
  }
  return lines;
}

}  // namespace granagg::analysis
