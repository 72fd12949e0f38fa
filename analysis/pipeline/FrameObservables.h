#pragma once
/// \file FrameObservables.h
/// The per-frame compute objects of `granagg analyze` (freud's compute objects are the model):
/// each owns the tables it fills and names their columns, takes the frames one at a time, and
/// hands its tables over at the end. analyzeRun (RunAnalyzer.h) reads the frames and drives them:
///   - ClusterObservables: grid and particle clusters (N_s_grid, N_s_particle, fisher, nstick);
///   - StructureObservable: the structure factor (S_k) and the density length l;
///   - MotionObservables: velocities, charges and displacements (thermo, speed_dist, msd,
///     msd_all_origins, charge_speed);
///   - GrowthTable: S_t, one row per frame from the others' values, with the local slopes.
/// Internal to analysis/pipeline.
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "analysis/clusters/GridClusters.h"
#include "analysis/clusters/ParticleClusters.h"
#include "analysis/io/Frame.h"
#include "analysis/pipeline/RunAnalyzer.h"
#include "analysis/pipeline/Table.h"
#include "analysis/stats/Msd.h"
#include "analysis/stats/PowerLawMle.h"
#include "analysis/stats/StructureFactor.h"
#include "analysis/stats/VelocityStats.h"

namespace granagg::analysis {

/// The state of the compute objects between two frames, as named arrays (RunAnalysis::saveState
/// writes it to HDF5): every table's rows, and what a compute object carries from frame to frame.
struct ObservableState {
  std::map<std::string, std::vector<double>> reals;
  std::map<std::string, std::vector<std::int64_t>> integers;
  std::map<std::string, std::string> texts;
  /// Stores a table's columns and rows under "table.<name>".
  void putTable(const Table& t);
  /// Restores the rows of `t` (its name, description and flags stay); throws std::runtime_error
  /// when the state lacks the table or holds other columns. `adopt_columns`: take the stored
  /// columns instead (N_stick's depend on the first frame's ids).
  void getTable(Table& t, bool adopt_columns = false) const;
  const std::vector<double>& real(const std::string& key) const;
  const std::vector<std::int64_t>& integer(const std::string& key) const;
  const std::string& text(const std::string& key) const;
};

/// The columns of fisher.csv and fisher_pooled.csv.
extern const std::vector<std::string> FISHER_COLUMNS;
/// One fisher row: the MLE of each definition and the paper's log-binned estimator of each
/// (`n_s`: nullptr for a definition that is off).
std::vector<double> fisherRow(double t, const std::map<std::uint64_t, std::uint64_t>* grid,
                              const std::map<std::uint64_t, std::uint64_t>* particle,
                              const AnalysisOptions& o);

/// kappa of the expected charging exponent and where it came from: the option, else the run's
/// charging.kappa (or kappa) parameter, else 0.83 (Poppe et al. 2000, silica).
std::pair<double, std::string> resolveKappa(const AnalysisOptions& o,
                                            const std::map<std::string, std::string>& parameters);

/// fits.csv of one run: the growth exponents of S_grid and S_particle over the window, the
/// charging rate (from <|q|> when `mean_abs_q` is given) and the onsets (RunAnalyzer.cpp).
Table runFits(const std::vector<double>& t, const std::vector<double>& S_grid,
              const std::vector<double>& S_particle, const std::vector<double>* mean_abs_q,
              double kappa, const AnalysisOptions& o);

/// Grid and particle clusters of each frame.
class ClusterObservables {
 public:
  /// What S_t takes from one definition's clusters (NaN when the definition is off).
  struct Sizes {
    double S, clusters, largest, S_without_largest, largest_share;
  };
  /// What S_t takes from the clusters of one frame.
  struct Row {
    Sizes grid, particle;
    double occupied_fraction, mean_contacts;
  };

  explicit ClusterObservables(const AnalysisOptions& o);
  /// The tracked particles of N_stick: the `track` smallest ids (frames are in id order).
  void first(const Frame& f);
  Row add(const Frame& f, const RunCallbacks& cb);
  /// The grid's size and threshold into the run's record.
  void describe(RunResult& r) const;
  void save(ObservableState& s) const;
  void restore(const ObservableState& s);

  Table& nsGrid() { return m_ns_grid; }
  Table& nsParticle() { return m_ns_particle; }
  Table& fisher() { return m_fisher; }
  Table& nstick() { return m_nstick; }
  bool tracks() const { return !m_tracked.empty(); }

 private:
  const AnalysisOptions& m_o;
  GridClusters m_grid;
  ParticleClusters m_particle;
  Table m_ns_grid, m_ns_particle, m_fisher, m_nstick;
  std::vector<std::size_t> m_tracked;
  // the grid of the last frame (describe)
  double m_grid_cells = 0, m_grid_cell_size = 0, m_grid_min_count = 0;
};

/// S(k) of each frame and, where the frame has velocities, the velocity field's S_par(k) and
/// S_perp(k) (analysis/stats/StructureFactor.h), on one mesh.
class StructureObservable {
 public:
  /// The lengths of one frame (NaN for what was not computed).
  struct Lengths {
    double density, par, perp;
  };
  explicit StructureObservable(const AnalysisOptions& o);
  /// Adds the frame's S(k) and S_u(k) rows; returns its lengths.
  Lengths add(const Frame& f);
  Table& table() { return m_table; }
  Table& velocityTable() { return m_velocity; }
  void save(ObservableState& s) const {
    s.putTable(m_table);
    s.putTable(m_velocity);
  }
  void restore(const ObservableState& s) {
    s.getTable(m_table);
    s.getTable(m_velocity);
  }

 private:
  const AnalysisOptions& m_o;
  Table m_table, m_velocity;
  StructureFactorMesh m_mesh;  // one mesh for all frames of the run
};

/// Temperature, the speed distribution, charges, their correlation and the MSD of each frame.
class MotionObservables {
 public:
  explicit MotionObservables(const AnalysisOptions& o);
  /// What the trajectory lacks goes into the run's notes.
  void first(const Frame& f, RunResult& r);
  void add(const Frame& f);
  /// <|q|> of every frame so far (NaN without charges).
  const std::vector<double>& meanAbsCharge() const { return m_mean_q; }
  bool hasCharges() const { return m_have_q; }
  /// The tables in analysis order; throws std::invalid_argument for --msd-origins all when the
  /// frames do not allow it (`path` names the run).
  void finish(const std::string& path, RunResult& r);
  void save(ObservableState& s) const;
  void restore(const ObservableState& s);

 private:
  const AnalysisOptions& m_o;
  SpeedHistogram m_hist;
  MsdFromOrigin m_msd0;
  MsdAllOrigins m_msd_all;
  Table m_thermo, m_msd, m_speed;
  bool m_have_vel = false, m_have_q = false;
  std::vector<double> m_mean_q;
  double m_scatter_t = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> m_scatter_q, m_scatter_v;
  std::vector<std::int64_t> m_scatter_ids;
};

/// S_t: the cluster sizes, occupation and density length per frame, with the local slopes of S.
class GrowthTable {
 public:
  GrowthTable();
  void add(double t, std::int64_t step, const ClusterObservables::Row& c,
           const StructureObservable::Lengths& l);
  /// Fills the local slopes z(t) = ln[S(t)/S(t/p)] / ln p of both S.
  void finish(double slope_ratio);
  const std::vector<double>& times() const { return m_t; }
  const std::vector<double>& sGrid() const { return m_S_grid; }
  const std::vector<double>& sParticle() const { return m_S_particle; }
  Table& table() { return m_table; }
  void save(ObservableState& s) const { s.putTable(m_table); }
  /// The table's rows, and the series of the fits from them.
  void restore(const ObservableState& s);

 private:
  Table m_table;
  std::vector<double> m_t, m_S_grid, m_S_particle;
};

}  // namespace granagg::analysis
