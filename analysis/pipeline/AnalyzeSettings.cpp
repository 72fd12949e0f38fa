/// \file AnalyzeSettings.cpp
/// The analyze command's options into AnalysisOptions (AnalyzeSettings.h).
#include "analysis/pipeline/AnalyzeSettings.h"

#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "common/Csv.h"

namespace granagg::analysis {

AnalysisOptions analysisOptions(const AnalyzeSettings& a, bool write_grid) {
  // the options by their names (the libraries' own checks name their parameters instead)
  if (!(a.grid_spacing > 0.0) || !std::isfinite(a.grid_spacing))
    throw std::invalid_argument("--grid-spacing must be > 0 and finite (got " +
                                common::formatReal(a.grid_spacing) + ")");
  if (!(a.grid_min_fill > 0.0 && a.grid_min_fill <= 1.0))
    throw std::invalid_argument("--grid-min-fill must lie in (0, 1] (got " +
                                common::formatReal(a.grid_min_fill) + ")");
  if (a.grid_min_count < 0)
    throw std::invalid_argument("--grid-min-count must be >= 0 (got " +
                                std::to_string(a.grid_min_count) + ")");
  if (!(a.tolerance >= 0.0) || !std::isfinite(a.tolerance))
    throw std::invalid_argument("--tolerance must be >= 0 and finite (got " +
                                common::formatReal(a.tolerance) + ")");
  AnalysisOptions o;
  o.grid.spacing = a.grid_spacing;
  o.grid.min_fill = a.grid_min_fill;
  o.grid.min_count = a.grid_min_count;
  if (a.grid_assign == "ngp")
    o.grid.assignment = GridAssignment::Nearest;
  else if (a.grid_assign == "cic")
    o.grid.assignment = GridAssignment::CloudInCell;
  else
    throw std::invalid_argument("--grid-assign must be ngp or cic (got '" + a.grid_assign + "').");
  o.grid_clusters = !a.no_grid;
  o.particle_clusters = !a.no_particle;
  if (a.no_grid && a.no_particle)
    throw std::invalid_argument(
        "--no-grid and --no-particle together leave no cluster definition.");
  if (write_grid && a.no_grid)
    throw std::invalid_argument("--write-grid needs grid clusters (drop --no-grid).");
  o.particle.tolerance = a.tolerance;
  o.structure_factor = !a.no_structure;
  if (!(a.structure_k_cut > 0.0) || !std::isfinite(a.structure_k_cut))
    throw std::invalid_argument("--structure-kcut must be > 0 and finite (got " +
                                common::formatReal(a.structure_k_cut) + ")");
  o.structure.k_cut = a.structure_k_cut;
  o.slope_ratio = a.slope_ratio;
  if (!a.fit_window.empty()) {
    if (a.fit_window.size() != 2)
      throw std::invalid_argument("--fit-window takes two times T_MIN T_MAX.");
    o.fit_t_min = a.fit_window[0];
    o.fit_t_max = a.fit_window[1];
    if (!(o.fit_t_max > o.fit_t_min) || !(o.fit_t_min >= 0))
      throw std::invalid_argument("--fit-window must be two times 0 <= T_MIN < T_MAX (got " +
                                  common::formatReal(o.fit_t_min) + " " +
                                  common::formatReal(o.fit_t_max) + ").");
  }
  if (!a.charge_fit_window.empty()) {
    if (a.charge_fit_window.size() != 2)
      throw std::invalid_argument("--charge-fit-window takes two times T_MIN T_MAX.");
    o.charge_fit_t_min = a.charge_fit_window[0];
    o.charge_fit_t_max = a.charge_fit_window[1];
  }
  o.mle_min_tail = a.mle_min_tail;
  o.speed_max = a.speed_max;
  o.speed_bins = a.speed_bins;
  o.msd_origins = a.msd_origins;
  if (!(a.msd_max_memory_mib >= 0) || !std::isfinite(a.msd_max_memory_mib))
    throw std::invalid_argument("--msd-max-memory must be >= 0 MiB.");
  o.msd_max_bytes = static_cast<std::size_t>(a.msd_max_memory_mib * 1024.0 * 1024.0);
  o.kappa = a.kappa;
  o.track = a.track;
  o.allow_partial = a.allow_partial;
  o.lammps_dt = a.lammps_dt;
  o.bootstrap_replicates = a.bootstrap;
  if (a.seed < 0) throw std::invalid_argument("--seed must be >= 0.");
  o.bootstrap_seed = static_cast<std::uint64_t>(a.seed);
  o.onset_factor = a.onset_factor;
  o.onset_t_base = a.onset_baseline;
  o.fisher_bin_ratio = a.fisher_bin_ratio;
  o.validate();
  return o;
}

}  // namespace granagg::analysis
