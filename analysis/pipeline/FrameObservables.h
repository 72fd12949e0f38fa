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

/// The columns of fisher.csv and fisher_pooled.csv.
extern const std::vector<std::string> FISHER_COLUMNS;
/// One fisher row: the MLE of each definition and the paper's log-binned estimator of each
/// (`n_s`: nullptr for a definition that is off).
std::vector<double> fisherRow(double t, const std::map<std::uint64_t, std::uint64_t>* grid,
                              const std::map<std::uint64_t, std::uint64_t>* particle,
                              const AnalysisOptions& o);

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
};

/// S(k) of each frame (analysis/stats/StructureFactor.h).
class StructureObservable {
 public:
  explicit StructureObservable(const AnalysisOptions& o);
  /// Adds the frame's S(k) rows; returns its density length l.
  double add(const Frame& f);
  Table& table() { return m_table; }

 private:
  const AnalysisOptions& m_o;
  Table m_table;
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
  void add(double t, std::int64_t step, const ClusterObservables::Row& c, double l_density);
  /// Fills the local slopes z(t) = ln[S(t)/S(t/p)] / ln p of both S.
  void finish(double slope_ratio);
  const std::vector<double>& times() const { return m_t; }
  const std::vector<double>& sGrid() const { return m_S_grid; }
  const std::vector<double>& sParticle() const { return m_S_particle; }
  Table& table() { return m_table; }

 private:
  Table m_table;
  std::vector<double> m_t, m_S_grid, m_S_particle;
};

}  // namespace granagg::analysis
