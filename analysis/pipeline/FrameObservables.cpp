#include "analysis/pipeline/FrameObservables.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "analysis/stats/ChargeStats.h"
#include "analysis/stats/GrowthMarkers.h"
#include "analysis/stats/PowerLawFit.h"
#include "analysis/stats/StructureFactor.h"

namespace granagg::analysis {

namespace {

const double NaN = std::numeric_limits<double>::quiet_NaN();

/// The paper's Fisher exponent (log-binned least squares) as three table values.
std::vector<double> lsColumns(const std::map<std::uint64_t, std::uint64_t>& n_s, double ratio) {
  const LogBinnedFit f = fitLogBinnedPowerLaw(n_s, ratio);
  return {f.valid ? f.tau : NaN, f.valid ? f.tau_err : NaN, static_cast<double>(f.bins)};
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : "\n") + n;
  return out;
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  if (text.empty()) return out;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find('\n', start);
    out.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return out;
    start = end + 1;
  }
}

}  // namespace

// ---- state between frames ----------------------------------------------------------------------

void ObservableState::putTable(const Table& t) {
  const std::string key = "table." + t.name;
  std::vector<double> flat;
  flat.reserve(t.rows.size() * t.columns.size());
  for (const auto& row : t.rows) flat.insert(flat.end(), row.begin(), row.end());
  reals[key] = std::move(flat);
  integers[key + ".shape"] = {static_cast<std::int64_t>(t.rows.size()),
                              static_cast<std::int64_t>(t.columns.size())};
  texts[key + ".columns"] = joined(t.columns);
}

void ObservableState::getTable(Table& t, bool adopt_columns) const {
  const std::string key = "table." + t.name;
  const std::vector<std::string> columns = split(text(key + ".columns"));
  if (!adopt_columns && columns != t.columns)
    throw std::runtime_error("the saved table " + t.name + " has the columns '" +
                             joined(columns) + "', this analysis '" + joined(t.columns) + "'");
  const auto& shape = integer(key + ".shape");
  const auto& flat = real(key);
  if (shape.size() != 2 || shape[1] != static_cast<std::int64_t>(columns.size()) || shape[0] < 0 ||
      flat.size() != static_cast<std::size_t>(shape[0] * shape[1]))
    throw std::runtime_error("the saved table " + t.name + " has an inconsistent shape");
  t.columns = columns;
  t.rows.assign(static_cast<std::size_t>(shape[0]), {});
  const std::size_t nc = columns.size();
  for (std::size_t r = 0; r < t.rows.size(); ++r)
    t.rows[r].assign(flat.begin() + static_cast<long>(r * nc),
                     flat.begin() + static_cast<long>((r + 1) * nc));
}

namespace {
template <class Map>
const typename Map::mapped_type& lookup(const Map& m, const std::string& key) {
  const auto it = m.find(key);
  if (it == m.end()) throw std::runtime_error("the saved analysis state has no '" + key + "'");
  return it->second;
}
}  // namespace

const std::vector<double>& ObservableState::real(const std::string& key) const {
  return lookup(reals, key);
}
const std::vector<std::int64_t>& ObservableState::integer(const std::string& key) const {
  return lookup(integers, key);
}
const std::string& ObservableState::text(const std::string& key) const {
  return lookup(texts, key);
}

const std::vector<std::string> FISHER_COLUMNS = {
    "t",           "tau_grid",        "tau_grid_err",        "xmin_grid",
    "tail_grid",   "ks_grid",         "tau_particle",        "tau_particle_err",
    "xmin_particle", "tail_particle", "ks_particle",         "tau_ls_grid",
    "tau_ls_grid_err", "bins_ls_grid", "tau_ls_particle",    "tau_ls_particle_err",
    "bins_ls_particle"};

std::vector<double> fisherRow(double t, const std::map<std::uint64_t, std::uint64_t>* grid,
                              const std::map<std::uint64_t, std::uint64_t>* particle,
                              const AnalysisOptions& o) {
  PowerLawMleResult fg, fp;
  std::vector<double> ls_g{NaN, NaN, NaN}, ls_p{NaN, NaN, NaN};
  if (grid) {
    fg = fitDiscretePowerLawKs(*grid, o.mle_min_tail);
    ls_g = lsColumns(*grid, o.fisher_bin_ratio);
  }
  if (particle) {
    fp = fitDiscretePowerLawKs(*particle, o.mle_min_tail);
    ls_p = lsColumns(*particle, o.fisher_bin_ratio);
  }
  auto fv = [](const PowerLawMleResult& m, double x) { return m.valid ? x : NaN; };
  return {t,         fv(fg, fg.tau),      fv(fg, fg.tau_err), fv(fg, double(fg.xmin)),
          fv(fg, double(fg.n_tail)), fv(fg, fg.ks), fv(fp, fp.tau), fv(fp, fp.tau_err),
          fv(fp, double(fp.xmin)), fv(fp, double(fp.n_tail)), fv(fp, fp.ks), ls_g[0],
          ls_g[1],   ls_g[2],             ls_p[0],            ls_p[1],
          ls_p[2]};
}

// ---- clusters ----------------------------------------------------------------------------------

ClusterObservables::ClusterObservables(const AnalysisOptions& o)
    : m_o(o),
      m_grid(o.grid),
      m_particle(o.particle),
      m_ns_grid("N_s_grid",
                "t: time; s: cluster size in grid sites; N_s: number of grid clusters of s sites",
                {"t", "s", "N_s"}, 2),
      m_ns_particle(
          "N_s_particle",
          "t: time; s: cluster size in particles; N_s: number of particle clusters of s particles",
          {"t", "s", "N_s"}, 2),
      m_fisher("fisher",
               "Fisher exponent tau of N_s ~ s^-tau per frame: discrete power-law MLE with xmin by "
               "KS distance (Clauset, Shalizi & Newman 2009); tau_err = 1/sqrt(n I(tau)); tail = "
               "clusters with s >= xmin; ks = KS distance; NaN when fewer than min_tail clusters "
               "or no maximum; tau_ls: the paper's estimator, minus the least-squares slope of "
               "ln N_s on ln s over logarithmic bins (analysis/stats/GrowthMarkers.h), bins_ls = "
               "non-empty bins (NaN below 3)",
               FISHER_COLUMNS),
      m_nstick("nstick", "", {}) {
  m_ns_grid.missing_is_zero = true;
  m_ns_particle.missing_is_zero = true;
}

void ClusterObservables::first(const Frame& f) {
  std::vector<std::string> columns{"t", "n_stick_mean"};
  for (std::size_t i = 0; i < std::min(m_o.track, f.size()); ++i) {
    m_tracked.push_back(i);
    columns.push_back("n_stick_id" + std::to_string(f.id[i]));
  }
  m_nstick = Table("nstick",
                   "t: time; n_stick_id<k>: number of particles within 1 + tolerance of tracked "
                   "particle k (N_stick, contact persistence); n_stick_mean: their mean",
                   columns);
}

namespace {

ClusterObservables::Sizes sizesOf(const ClusterSizes& c) {
  return {c.S, static_cast<double>(c.clusters), static_cast<double>(c.largest),
          c.S_without_largest, c.largest_share};
}

void addSizes(Table& table, double t, const ClusterSizes& c) {
  for (const auto& [s, count] : c.n_s)
    table.add({t, static_cast<double>(s), static_cast<double>(count)});
}

}  // namespace

ClusterObservables::Row ClusterObservables::add(const Frame& f, const RunCallbacks& cb) {
  const Sizes none{NaN, NaN, NaN, NaN, NaN};
  Row row{none, none, NaN, NaN};
  const double t = f.time;
  const std::map<std::uint64_t, std::uint64_t>* grid_ns = nullptr;
  const std::map<std::uint64_t, std::uint64_t>* particle_ns = nullptr;
  if (m_o.grid_clusters) {
    m_grid.compute(f);
    row.grid = sizesOf(m_grid.result());
    row.occupied_fraction = m_grid.occupiedFraction();
    addSizes(m_ns_grid, t, m_grid.result());
    grid_ns = &m_grid.result().n_s;
    m_grid_cells = m_grid.cellsPerSide();
    m_grid_cell_size = m_grid.cellSize();
    m_grid_min_count = m_grid.minCount();
    if (cb.grid) cb.grid(f, m_grid);
  }
  if (m_o.particle_clusters) {
    m_particle.compute(f);
    row.particle = sizesOf(m_particle.result());
    row.mean_contacts =
        2.0 * static_cast<double>(m_particle.bonds()) / static_cast<double>(f.size());
    addSizes(m_ns_particle, t, m_particle.result());
    particle_ns = &m_particle.result().n_s;
    std::vector<double> stick{t, 0.0};
    double sum = 0;
    for (std::size_t i : m_tracked) {
      stick.push_back(m_particle.contacts()[i]);
      sum += m_particle.contacts()[i];
    }
    stick[1] = m_tracked.empty() ? NaN : sum / static_cast<double>(m_tracked.size());
    m_nstick.add(stick);
  }
  m_fisher.add(fisherRow(t, grid_ns, particle_ns, m_o));
  return row;
}

void ClusterObservables::describe(RunResult& r) const {
  if (!m_o.grid_clusters) return;
  r.grid_cells = static_cast<int>(m_grid_cells);
  r.grid_cell_size = m_grid_cell_size;
  r.grid_min_count = m_grid_min_count;
}

void ClusterObservables::save(ObservableState& s) const {
  s.putTable(m_ns_grid);
  s.putTable(m_ns_particle);
  s.putTable(m_fisher);
  s.putTable(m_nstick);
  s.integers["clusters.tracked"].assign(m_tracked.begin(), m_tracked.end());
  s.reals["clusters.grid"] = {m_grid_cells, m_grid_cell_size, m_grid_min_count};
  s.texts["clusters.nstick_description"] = m_nstick.description;
}

void ClusterObservables::restore(const ObservableState& s) {
  s.getTable(m_ns_grid);
  s.getTable(m_ns_particle);
  s.getTable(m_fisher);
  m_nstick.description = s.text("clusters.nstick_description");
  s.getTable(m_nstick, /*adopt_columns=*/true);
  const auto& tracked = s.integer("clusters.tracked");
  m_tracked.assign(tracked.begin(), tracked.end());
  const auto& g = s.real("clusters.grid");
  if (g.size() != 3) throw std::runtime_error("the saved grid description is not 3 values");
  m_grid_cells = g[0];
  m_grid_cell_size = g[1];
  m_grid_min_count = g[2];
}

// ---- structure factor --------------------------------------------------------------------------

StructureObservable::StructureObservable(const AnalysisOptions& o)
    : m_o(o),
      m_table("S_k",
              "t: time; k: shell centre m 2 pi / L [1/d]; S_k: static structure factor "
              "<|sum_j exp(-i k.r_j)|^2>/N over the shell (CIC mesh, FFTW, Jing's alias "
              "correction: analysis/stats/StructureFactor.h); modes: independent wave vectors in "
              "the shell",
              {"t", "k", "S_k", "modes"}, 2),
      m_velocity("S_u_k",
                 "t: time; k: shell centre m 2 pi / L [1/d]; with u(k) = sum_j c_j exp(-i k.r_j) "
                 "of the peculiar velocities c_j: S_par = <|k^.u|^2>/(N T_g) (longitudinal) and "
                 "S_perp = <|u - k^(k^.u)|^2>/(2 N T_g) (transverse: shear, vorticity) over the "
                 "shell, both 1 for uncorrelated velocities (the mesh and shells of S_k; "
                 "analysis/stats/StructureFactor.h); modes: independent wave vectors",
                 {"t", "k", "S_par", "S_perp", "modes"}, 2) {}

StructureObservable::Lengths StructureObservable::add(const Frame& f) {
  const StructureFactor sk = structureFactor(f, m_o.structure, m_mesh);
  for (std::size_t m = 0; m < sk.k.size(); ++m)
    m_table.add({f.time, sk.k[m], sk.S[m], static_cast<double>(sk.modes[m])});
  Lengths l{sk.length, NaN, NaN};
  if (f.hasVelocities()) {
    const VelocityStructure su = velocityStructure(f, m_o.structure, m_mesh);
    for (std::size_t m = 0; m < su.k.size(); ++m)
      m_velocity.add({f.time, su.k[m], su.S_long[m], su.S_trans[m],
                      static_cast<double>(su.modes[m])});
    l.par = su.length_long;
    l.perp = su.length_trans;
  }
  return l;
}

// ---- velocities, charges, displacements --------------------------------------------------------

MotionObservables::MotionObservables(const AnalysisOptions& o)
    : m_o(o),
      m_hist(o.speed_max, o.speed_bins),
      m_msd_all(o.msd_origins == "t0" ? 0 : o.msd_max_bytes),
      m_thermo("thermo",
               "t: time; T_g = <|v - <v>|^2>/3 [T0]; a2 = (3/5)<c^4>/<c^2>^2 - 1 (Sonine) and its "
               "standard error; mean_abs_q = <|q|> [q_ref]; rms_q; net_q = sum q; max_abs_q; "
               "corr_absq_speed = Pearson correlation of |q~| and v~",
               {"t", "T_g", "a2", "a2_err", "mean_abs_q", "rms_q", "net_q", "max_abs_q",
                "corr_absq_speed"}),
      m_msd("msd",
            "t: time; msd = <|r(t) - r(t0)|^2> [d^2] from the first frame t0, unwrapped with image "
            "counts",
            {"t", "msd"}),
      m_speed("speed_dist",
              "t: time; v_low, v_high: bin of v~ = |c|/<|c|^2>^{1/2}; f: probability density of "
              "v~; f_maxwell: the Maxwellian sqrt(54/pi) v~^2 exp(-3 v~^2/2) averaged over the "
              "bin; count: particles in the bin",
              {"t", "v_low", "v_high", "f", "f_maxwell", "count"}, 3) {}

void MotionObservables::first(const Frame& f, RunResult& r) {
  m_have_vel = f.hasVelocities();
  m_have_q = f.hasCharges();
  if (!f.hasImages()) r.notes.push_back("no image counts in the trajectory: MSD skipped");
  if (!m_have_vel)
    r.notes.push_back("no velocities: T_g, a2, f(v~) and the charge-speed scatter skipped");
  if (!m_have_q) r.notes.push_back("no charges: charge observables skipped");
}

void MotionObservables::add(const Frame& f) {
  const double t = f.time;
  std::vector<double> speeds;
  VelocityMoments vm;
  vm.T_g = vm.a2 = vm.a2_err = NaN;
  if (m_have_vel && f.hasVelocities()) {
    vm = velocityMoments(f.velocity);
    m_hist.reset();
    speeds = m_hist.add(f.velocity);
    const auto dens = m_hist.density();
    for (int k = 0; k < m_hist.bins(); ++k) {
      const double lo = m_hist.binLow(k), hi = lo + m_hist.binWidth();
      const double fm =
          (maxwellianScaledSpeedCdf(hi) - maxwellianScaledSpeedCdf(lo)) / m_hist.binWidth();
      m_speed.add({t, lo, hi, dens[static_cast<std::size_t>(k)], fm,
                   m_hist.counts()[static_cast<std::size_t>(k)]});
    }
  }
  ChargeMoments qm{NaN, NaN, NaN, NaN};
  double corr = NaN;
  if (m_have_q && f.hasCharges()) {
    qm = chargeMoments(f.charge);
    if (!speeds.empty()) {
      std::vector<double> aq = scaledCharges(f.charge);
      for (double& x : aq) x = std::fabs(x);
      corr = pearson(aq, speeds);
    }
  }
  m_mean_q.push_back(qm.mean_abs);
  m_thermo.add({t, vm.T_g, vm.a2, vm.a2_err, qm.mean_abs, qm.rms, qm.net, qm.max_abs, corr});
  if (f.hasImages()) {
    m_msd0.accumulate(f);
    m_msd.add({t, m_msd0.msd().back()});
    if (m_o.msd_origins != "t0") m_msd_all.accumulate(f);
  } else if (m_o.msd_origins != "t0") {
    m_msd_all.accumulate(f);  // records why it is unavailable
  }
  // charge-speed scatter: kept for the last frame only (the table is built at the end)
  if (m_have_q && !speeds.empty()) {
    m_scatter_t = t;
    m_scatter_q = scaledCharges(f.charge);
    m_scatter_v = std::move(speeds);
    m_scatter_ids = f.id;
  }
}

void MotionObservables::finish(const std::string& path, RunResult& r) {
  r.tables.push_back(std::move(m_thermo));
  if (!m_msd.rows.empty()) r.tables.push_back(std::move(m_msd));
  if (m_o.msd_origins != "t0") {
    if (m_msd_all.available()) {
      std::vector<double> lag;
      const auto m = m_msd_all.compute(lag);
      Table all("msd_all_origins",
                "lag: time lag [sqrt(m d^2/T0)]; msd = <|r(t0 + lag) - r(t0)|^2> averaged over "
                "all time origins t0 (FFT method; frames evenly spaced)",
                {"lag", "msd"});
      for (std::size_t k = 0; k < m.size(); ++k) all.add({lag[k], m[k]});
      r.tables.push_back(std::move(all));
    } else if (m_o.msd_origins == "all") {
      throw std::invalid_argument("--msd-origins all: not possible for '" + path +
                                  "': " + m_msd_all.reason());
    } else {
      r.notes.push_back("all-origins MSD skipped: " + m_msd_all.reason());
    }
  }
  if (!m_speed.rows.empty()) r.tables.push_back(std::move(m_speed));
  if (!m_scatter_q.empty()) {
    Table sc("charge_speed",
             "id: particle id; q_tilde = q / <q^2>^{1/2}; v_tilde = |c| / <|c|^2>^{1/2} (last "
             "frame analysed, at time t)",
             {"t", "id", "q_tilde", "v_tilde"});
    sc.ensemble = false;
    sc.rows.reserve(m_scatter_q.size());
    for (std::size_t i = 0; i < m_scatter_q.size(); ++i)
      sc.add({m_scatter_t, static_cast<double>(m_scatter_ids[i]), m_scatter_q[i],
              m_scatter_v[i]});
    r.tables.push_back(std::move(sc));
  }
}

void MotionObservables::save(ObservableState& s) const {
  s.putTable(m_thermo);
  s.putTable(m_msd);
  s.putTable(m_speed);
  s.integers["motion.flags"] = {m_have_vel, m_have_q};
  s.reals["motion.mean_q"] = m_mean_q;
  s.reals["motion.scatter_t"] = {m_scatter_t};
  s.reals["motion.scatter_q"] = m_scatter_q;
  s.reals["motion.scatter_v"] = m_scatter_v;
  s.integers["motion.scatter_ids"] = m_scatter_ids;
  const MsdFromOrigin::State m0 = m_msd0.state();
  s.reals["msd0.origin"] = m0.origin;
  s.reals["msd0.t"] = m0.t;
  s.reals["msd0.msd"] = m0.msd;
  const MsdAllOrigins::State ma = m_msd_all.state();
  s.integers["msd_all.counts"] = {static_cast<std::int64_t>(ma.n),
                                  static_cast<std::int64_t>(ma.frames), ma.available};
  s.texts["msd_all.reason"] = ma.reason;
  s.reals["msd_all.times"] = {ma.t0, ma.dt};
  s.reals["msd_all.xyz"] = ma.xyz;
}

void MotionObservables::restore(const ObservableState& s) {
  s.getTable(m_thermo);
  s.getTable(m_msd);
  s.getTable(m_speed);
  const auto& flags = s.integer("motion.flags");
  if (flags.size() != 2) throw std::runtime_error("the saved motion flags are not 2 values");
  m_have_vel = flags[0] != 0;
  m_have_q = flags[1] != 0;
  m_mean_q = s.real("motion.mean_q");
  m_scatter_t = s.real("motion.scatter_t").at(0);
  m_scatter_q = s.real("motion.scatter_q");
  m_scatter_v = s.real("motion.scatter_v");
  m_scatter_ids = s.integer("motion.scatter_ids");
  m_msd0.restore({s.real("msd0.origin"), s.real("msd0.t"), s.real("msd0.msd")});
  const auto& counts = s.integer("msd_all.counts");
  const auto& times = s.real("msd_all.times");
  if (counts.size() != 3 || times.size() != 2)
    throw std::runtime_error("the saved all-origins MSD is incomplete");
  m_msd_all.restore({static_cast<std::size_t>(counts[0]), static_cast<std::size_t>(counts[1]),
                     counts[2] != 0, s.text("msd_all.reason"), times[0], times[1],
                     s.real("msd_all.xyz")});
}

// ---- S_t ---------------------------------------------------------------------------------------

GrowthTable::GrowthTable()
    : m_table("S_t",
              "t: time [sqrt(m d^2/T0)]; step; S = sum s^2 N_s / sum s N_s (grid: s in sites; "
              "particle: s in particles); clusters = number of clusters; largest = largest s; "
              "occupied_fraction = occupied grid sites / all sites; mean_contacts = partners "
              "within 1 + tolerance per particle; z_local = ln[S(t)/S(t/p)]/ln p; "
              "S_*_without_largest = (sum s^2 N_s - s_max^2) / (sum s N_s - s_max); "
              "largest_share_* = s_max / sum s N_s; l_density = 2 pi / k_1, k_1 the first moment "
              "of S(k) over k <= k_c (analysis/stats/StructureFactor.h; an ideal gas gives about "
              "4 pi / k_c); l_par, l_perp: the same first moments of the velocity field's S_par and "
              "S_perp (S_u_k: longitudinal and transverse, l_perp the vortex length)",
              {"t", "step", "S_grid", "S_particle", "clusters_grid", "clusters_particle",
               "largest_grid", "largest_particle", "occupied_fraction", "mean_contacts",
               "z_local_grid", "z_local_particle", "S_grid_without_largest",
               "S_particle_without_largest", "largest_share_grid", "largest_share_particle",
               "l_density", "l_par", "l_perp"}) {}

void GrowthTable::add(double t, std::int64_t step, const ClusterObservables::Row& c,
                      const StructureObservable::Lengths& l) {
  m_t.push_back(t);
  m_S_grid.push_back(c.grid.S);
  m_S_particle.push_back(c.particle.S);
  // the local slopes come when the series is complete (finish)
  m_table.add({t, static_cast<double>(step), c.grid.S, c.particle.S, c.grid.clusters,
               c.particle.clusters, c.grid.largest, c.particle.largest, c.occupied_fraction,
               c.mean_contacts, NaN, NaN, c.grid.S_without_largest, c.particle.S_without_largest,
               c.grid.largest_share, c.particle.largest_share, l.density, l.par, l.perp});
}

void GrowthTable::restore(const ObservableState& s) {
  s.getTable(m_table);
  m_t = m_table.values("t");
  m_S_grid = m_table.values("S_grid");
  m_S_particle = m_table.values("S_particle");
}

void GrowthTable::finish(double slope_ratio) {
  const auto zg = localSlope(m_t, m_S_grid, slope_ratio);
  const auto zp = localSlope(m_t, m_S_particle, slope_ratio);
  const std::size_t cg = m_table.column("z_local_grid"), cp = m_table.column("z_local_particle");
  for (std::size_t k = 0; k < m_table.rows.size(); ++k) {
    m_table.rows[k][cg] = zg[k];
    m_table.rows[k][cp] = zp[k];
  }
}

}  // namespace granagg::analysis
