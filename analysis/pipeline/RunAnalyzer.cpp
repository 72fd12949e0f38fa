#include "analysis/pipeline/RunAnalyzer.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "analysis/io/TrajectoryReader.h"
#include "analysis/pipeline/FrameObservables.h"
#include "analysis/pipeline/RunAnalysis.h"
#include "analysis/stats/ChargeStats.h"
#include "analysis/stats/GrowthMarkers.h"
#include "analysis/stats/PowerLawFit.h"
#include "common/Csv.h"
#include "common/Strings.h"

namespace granagg::analysis {

namespace {

constexpr double DEFAULT_KAPPA = 0.83;  // Poppe et al. 2000, silica (docs/model.md section 7)
const double NaN = std::numeric_limits<double>::quiet_NaN();

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

/// Growth-exponent window: the options, or the last decade of the data.
std::pair<double, double> fitWindow(const AnalysisOptions& o, const std::vector<double>& t) {
  if (o.fit_t_min > 0 || o.fit_t_max > 0) {
    return {o.fit_t_min, o.fit_t_max > 0 ? o.fit_t_max : std::numeric_limits<double>::infinity()};
  }
  const double last = t.empty() ? 0.0 : t.back();
  return {last / 10.0, last};
}

const std::vector<std::string> FITS_COLUMNS = {"z_grid",
                                               "z_grid_err",
                                               "z_grid_low",
                                               "z_grid_high",
                                               "z_particle",
                                               "z_particle_err",
                                               "z_particle_low",
                                               "z_particle_high",
                                               "fit_t_min",
                                               "fit_t_max",
                                               "fit_points",
                                               "charging_rate_exponent",
                                               "charging_rate_exponent_err",
                                               "charging_rate_low",
                                               "charging_rate_high",
                                               "charging_rate_expected",
                                               "kappa",
                                               "charge_fit_t_min",
                                               "charge_fit_t_max",
                                               "charge_fit_points",
                                               "runs",
                                               "onset_time_grid",
                                               "onset_time_grid_err",
                                               "onset_time_particle",
                                               "onset_time_particle_err",
                                               "onset_S_base_grid",
                                               "onset_factor",
                                               "onset_t_base"};
const char* FITS_DESCRIPTION =
    "growth exponent z of S(t) ~ t^z (grid and particle clusters) by least squares of ln S on ln t "
    "over [fit_t_min, fit_t_max] with its 95% interval [low, high] (Student t for one run; for the "
    "ensemble the bootstrap over runs, z -/+ t_{R-1} sqrt(R/(R-1)) sd of the replicates, the rule "
    "of fit-beta); err = standard error (bootstrap: sd of the replicates); charging_rate_exponent: "
    "the same fit to d<|q|>/dt over [charge_fit_t_min, charge_fit_t_max], beside the expected -5/6 "
    "- 5 kappa/3; onset_time: first time S reaches onset_factor x its median over 0 < t <= "
    "onset_t_base (onset_S_base_grid), interpolated in (ln t, ln S); ensemble: onset of the mean "
    "S, err = standard error of the runs' onsets";

/// Onset times of one table's S_grid and S_particle, with the standard errors over runs (ensemble).
struct Onsets {
  OnsetTime grid, particle;
  double grid_err = NaN, particle_err = NaN;
};

std::vector<double> fitColumns(const PowerLawFitResult& g, const PowerLawFitResult& p, double t0,
                               double t1, const PowerLawFitResult& q, double kappa, double q0,
                               double q1, double runs, const Onsets& on, const AnalysisOptions& o) {
  auto v = [](const PowerLawFitResult& f, double x) { return f.valid ? x : NaN; };
  auto ov = [](const OnsetTime& m, double x) { return m.valid ? x : NaN; };
  return {v(g, g.exponent),
          v(g, g.stderr_z),
          v(g, g.low),
          v(g, g.high),
          v(p, p.exponent),
          v(p, p.stderr_z),
          v(p, p.low),
          v(p, p.high),
          t0,
          t1,
          static_cast<double>(std::max(g.points, p.points)),
          v(q, q.exponent),
          v(q, q.stderr_z),
          v(q, q.low),
          v(q, q.high),
          expectedChargingRateExponent(kappa),
          kappa,
          q0,
          q1,
          static_cast<double>(q.points),
          runs,
          ov(on.grid, on.grid.t_c),
          on.grid_err,
          ov(on.particle, on.particle.t_c),
          on.particle_err,
          on.grid.S_base > 0 ? on.grid.S_base : NaN,
          o.onset_factor,
          o.onset_t_base};
}

/// Onsets of S_grid and S_particle; empty series give invalid onsets.
Onsets onsetsOf(const std::vector<double>& t, const std::vector<double>& Sg,
                const std::vector<double>& Sp, const AnalysisOptions& o) {
  Onsets on;
  on.grid = onsetTime(t, Sg, o.onset_factor, o.onset_t_base);
  on.particle = onsetTime(t, Sp, o.onset_factor, o.onset_t_base);
  return on;
}

/// Standard error of the mean of values, NaN unless every one is finite and there are >= 2.
double standardErrorOfAll(const std::vector<double>& x) {
  if (x.size() < 2) return NaN;
  double m = 0;
  for (double v : x) {
    if (!std::isfinite(v)) return NaN;
    m += v;
  }
  m /= static_cast<double>(x.size());
  double ss = 0;
  for (double v : x) ss += (v - m) * (v - m);
  return std::sqrt(ss / static_cast<double>(x.size() - 1) / static_cast<double>(x.size()));
}

}  // namespace

std::pair<double, std::string> resolveKappa(const AnalysisOptions& o,
                                            const std::map<std::string, std::string>& parameters) {
  if (std::isfinite(o.kappa)) return {o.kappa, "option"};
  for (const char* key : {"charging.kappa", "kappa"}) {
    auto it = parameters.find(key);
    double v;
    if (it != parameters.end() && common::parseReal(it->second, v) && std::isfinite(v))
      return {v, std::string("file (") + key + ")"};
  }
  return {DEFAULT_KAPPA, "default"};
}

Table runFits(const std::vector<double>& t, const std::vector<double>& S_grid,
              const std::vector<double>& S_particle, const std::vector<double>* mean_abs_q,
              double kappa, const AnalysisOptions& o) {
  const auto [w0, w1] = fitWindow(o, t);
  const PowerLawFitResult fit_g = fitPowerLaw(t, S_grid, w0, w1),
                          fit_p = fitPowerLaw(t, S_particle, w0, w1);
  PowerLawFitResult fit_q;
  if (mean_abs_q) {
    const auto [tr, rate] = chargingRate(t, *mean_abs_q);
    fit_q = fitPowerLaw(tr, rate, o.charge_fit_t_min, o.charge_fit_t_max);
  }
  Table fits("fits", FITS_DESCRIPTION, FITS_COLUMNS, 0);
  fits.ensemble = false;
  fits.add(fitColumns(fit_g, fit_p, w0, w1, fit_q, kappa, o.charge_fit_t_min, o.charge_fit_t_max,
                      1, onsetsOf(t, S_grid, S_particle, o), o));
  return fits;
}

void AnalysisOptions::validate() const {
  require(slope_ratio > 1.0 && std::isfinite(slope_ratio),
          "--slope-ratio must be > 1 (got " + common::formatReal(slope_ratio) + ").");
  require(fit_t_min >= 0 && fit_t_max >= 0 && (fit_t_max == 0 || fit_t_max > fit_t_min),
          "--fit-window must be two times 0 <= t_min < t_max.");
  require(charge_fit_t_max > charge_fit_t_min && charge_fit_t_min >= 0,
          "--charge-fit-window must be two times 0 <= t_min < t_max.");
  require(speed_max > 0 && std::isfinite(speed_max), "--speed-max must be positive.");
  require(speed_bins >= 1 && speed_bins <= 100000, "--speed-bins must lie in [1, 100000].");
  require(msd_origins == "auto" || msd_origins == "t0" || msd_origins == "all",
          "--msd-origins must be auto, t0 or all (got '" + msd_origins + "').");
  require(!(std::isfinite(kappa)) || kappa >= 0, "--kappa must be >= 0.");
  require(std::isnan(kappa) || std::isfinite(kappa), "--kappa must be finite.");
  require(mle_min_tail >= 2, "--mle-min-tail must be at least 2.");
  require(bootstrap_replicates >= 10, "--bootstrap must be at least 10 replicates.");
  require(lammps_dt >= 0 && std::isfinite(lammps_dt), "--lammps-dt must be >= 0.");
  require(onset_factor > 1 && std::isfinite(onset_factor),
          "--onset-factor must be > 1 (got " + common::formatReal(onset_factor) + ").");
  require(onset_t_base > 0 && std::isfinite(onset_t_base),
          "--onset-baseline must be > 0 (got " + common::formatReal(onset_t_base) + ").");
  require(fisher_bin_ratio > 1 && fisher_bin_ratio <= 100,
          "--fisher-bin-ratio must lie in (1, 100] (got " + common::formatReal(fisher_bin_ratio) +
              ").");
  // The constructors validate their own parameters (and name them).
  GridClusters g(grid);
  ParticleClusters p(particle);
}

const Table& RunResult::table(const std::string& name) const {
  for (const auto& t : tables)
    if (t.name == name) return t;
  throw std::out_of_range("no table '" + name + "' for run " + source);
}

bool RunResult::hasTable(const std::string& name) const {
  for (const auto& t : tables)
    if (t.name == name) return true;
  return false;
}

RunResult analyzeRun(const std::string& path, const AnalysisOptions& o, const RunCallbacks& cb) {
  o.validate();
  auto reader = openTrajectory(path, o.lammps_dt);
  std::map<std::string, std::string> parameters = reader->parameters();
  RunAnalysis analysis(o, path, reader->format(), std::move(parameters), cb);
  Frame f;
  while (true) {
    try {
      if (!reader->next(f)) break;
      analysis.add(f);
    } catch (const TrajectoryError& e) {
      if (!o.allow_partial || analysis.frames() == 0) throw;
      analysis.setPartial(e.what());
      break;
    }
    if (cb.progress) cb.progress(analysis.frames(), reader->frameCountHint());
  }
  if (analysis.frames() == 0)
    throw std::invalid_argument("trajectory '" + path + "' holds no frames");
  return analysis.finish();
}

void checkSameSystem(const RunResult& a, const RunResult& b) {
  if (a.particles != b.particles)
    throw std::invalid_argument("runs '" + a.source + "' (N = " + std::to_string(a.particles) +
                                ") and '" + b.source + "' (N = " + std::to_string(b.particles) +
                                ") simulate different systems: an ensemble averages runs of one "
                                "system (same N and box); analyse them separately");
  if (std::fabs(a.box - b.box) > 1e-9 * std::max(a.box, b.box))
    throw std::invalid_argument("runs '" + a.source + "' (box L = " + common::formatReal(a.box) +
                                ") and '" + b.source + "' (box L = " + common::formatReal(b.box) +
                                ") simulate different systems: an ensemble averages runs of one "
                                "system (same N and box); analyse them separately");
}

namespace {

/// The ensemble average of every per-frame table present in all runs.
std::vector<Table> ensembleAverages(const std::vector<RunResult>& runs) {
  std::vector<Table> out;
  for (const Table& t : runs.front().tables) {
    if (!t.ensemble) continue;
    std::vector<const Table*> same;
    for (const auto& r : runs)
      if (r.hasTable(t.name)) same.push_back(&r.table(t.name));
    if (same.size() != runs.size()) continue;
    out.push_back(ensembleAverage(same));
  }
  return out;
}

/// Adds to the ensemble S(t) the local slope of its mean (less noisy than the mean of the runs'
/// local slopes).
void addLocalSlopeOfMean(std::vector<Table>& out, const AnalysisOptions& o) {
  for (Table& t : out)
    if (t.name == "S_t") {
      const auto tt = t.values("t");
      const auto zg = localSlope(tt, t.values("S_grid_mean"), o.slope_ratio);
      const auto zp = localSlope(tt, t.values("S_particle_mean"), o.slope_ratio);
      t.columns.push_back("z_local_grid_of_mean");
      t.columns.push_back("z_local_particle_of_mean");
      for (std::size_t k = 0; k < t.rows.size(); ++k) {
        t.rows[k].push_back(zg[k]);
        t.rows[k].push_back(zp[k]);
      }
      t.description += "; z_local_*_of_mean: local slope of the ensemble-mean S(t)";
    }
}

/// Fisher exponents of N_s summed over all runs at each time.
Table pooledFisher(const std::vector<RunResult>& runs, const AnalysisOptions& o) {
  Table pooled("fisher_pooled",
               "Fisher exponent of N_s summed over all runs at each time (MLE, xmin by KS, and "
               "the paper's log-binned least squares, as in fisher.csv)",
               FISHER_COLUMNS);
  std::map<double, std::map<std::uint64_t, std::uint64_t>> g, p;
  for (const auto& r : runs) {
    for (const char* name : {"N_s_grid", "N_s_particle"}) {
      if (!r.hasTable(name)) continue;
      auto& target = std::string(name) == "N_s_grid" ? g : p;
      for (const auto& row : r.table(name).rows) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.9g", row[0]);
        target[std::strtod(buf, nullptr)][static_cast<std::uint64_t>(row[1])] +=
            static_cast<std::uint64_t>(row[2]);
      }
    }
  }
  std::map<double, bool> times;
  for (const auto& kv : g) times[kv.first] = true;
  for (const auto& kv : p) times[kv.first] = true;
  for (const auto& kv : times) {
    const double t = kv.first;
    pooled.add(fisherRow(t, g.count(t) ? &g[t] : nullptr, p.count(t) ? &p[t] : nullptr, o));
  }
  return pooled;
}

/// Ensemble fits of S(t) and of the charging rate (bootstrap over runs on the frame times common
/// to all runs) and the onsets, from the ensemble S(t) table `st` (null: no row).
Table ensembleFits(const std::vector<RunResult>& runs, const Table* st, const AnalysisOptions& o) {
  Table fits("fits", FITS_DESCRIPTION, FITS_COLUMNS, 0);
  fits.ensemble = false;
  if (st) {
    std::vector<double> t;
    const std::size_t n_runs = st->column("n_runs");
    for (const auto& row : st->rows)
      if (row[n_runs] == static_cast<double>(runs.size())) t.push_back(row[0]);  // in every run
    auto seriesOf = [&](const std::string& col, const std::string& table) {
      std::vector<std::vector<double>> ys;
      for (const auto& r : runs) {
        const Table& tb = r.table(table);
        const auto tt = tb.values("t"), y = tb.values(col);
        std::vector<double> v;
        std::size_t j = 0;
        for (double tk : t) {
          while (j < tt.size() && std::fabs(tt[j] - tk) > 1e-9 * std::max(1.0, std::fabs(tk))) ++j;
          v.push_back(j < tt.size() ? y[j] : NaN);
        }
        ys.push_back(std::move(v));
      }
      return ys;
    };
    const auto [w0, w1] = fitWindow(o, t);
    auto fitOf = [&](const std::vector<std::vector<double>>& ys, const std::vector<double>& tt,
                     double a, double b) {
      if (ys.size() >= 2)
        return bootstrapPowerLaw(tt, ys, a, b, o.bootstrap_replicates, o.bootstrap_seed);
      return fitPowerLaw(tt, ys.front(), a, b);
    };
    const auto fg = fitOf(seriesOf("S_grid", "S_t"), t, w0, w1);
    const auto fp = fitOf(seriesOf("S_particle", "S_t"), t, w0, w1);
    // Charging rate per run, then bootstrap of the mean rate.
    PowerLawFitResult fq;
    const auto q = seriesOf("mean_abs_q", "thermo");
    bool have_q = true;
    for (const auto& v : q)
      for (double x : v) have_q &= std::isfinite(x);
    if (have_q && t.size() >= 2) {
      std::vector<std::vector<double>> rates;
      std::vector<double> tr;
      for (const auto& v : q) {
        auto [tm, rate] = chargingRate(t, v);
        tr = tm;
        rates.push_back(rate);
      }
      fq = fitOf(rates, tr, o.charge_fit_t_min, o.charge_fit_t_max);
    }
    // Onset: of the ensemble-mean S (every frame time, as the local slope of the mean), with the
    // standard error of the runs' own onsets.
    Onsets on =
        onsetsOf(st->values("t"), st->values("S_grid_mean"), st->values("S_particle_mean"), o);
    std::vector<double> tg, tp;
    for (const auto& r : runs) {
      const Table& tb = r.table("S_t");
      const Onsets one = onsetsOf(tb.values("t"), tb.values("S_grid"), tb.values("S_particle"), o);
      tg.push_back(one.grid.valid ? one.grid.t_c : NaN);
      tp.push_back(one.particle.valid ? one.particle.t_c : NaN);
    }
    on.grid_err = standardErrorOfAll(tg);
    on.particle_err = standardErrorOfAll(tp);
    fits.add(fitColumns(fg, fp, w0, w1, fq, runs.front().kappa, o.charge_fit_t_min,
                        o.charge_fit_t_max, static_cast<double>(runs.size()), on, o));
  }
  return fits;
}

}  // namespace

std::vector<Table> analyzeEnsemble(const std::vector<RunResult>& runs, const AnalysisOptions& o) {
  if (runs.empty()) throw std::invalid_argument("analyzeEnsemble needs at least one run.");
  for (const RunResult& r : runs) checkSameSystem(runs.front(), r);
  std::vector<Table> out = ensembleAverages(runs);
  addLocalSlopeOfMean(out, o);
  out.push_back(pooledFisher(runs, o));
  const Table* st = nullptr;
  for (const Table& t : out)
    if (t.name == "S_t") st = &t;
  Table fits = ensembleFits(runs, st, o);
  out.push_back(std::move(fits));
  return out;
}

}  // namespace granagg::analysis
