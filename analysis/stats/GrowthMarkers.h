#pragma once
/// \file GrowthMarkers.h
/// Two estimators the paper's figures rest on, beside the MLE of PowerLawMle.h:
///
/// - the paper's Fisher exponent (Singh & Mazza 2018, Fig. 3(b-d)): a straight line through
///   log N_s against log s. Here: N_s summed into logarithmic bins [r^k, r^{k+1}) (ratio r,
///   default 2), divided by the number of integer sizes in each bin (a density per size), and
///   fitted by ordinary least squares of ln density on ln s_c, s_c = sqrt(first x last integer
///   size of the bin). Log bins are the standard way to draw a power law over decades without the
///   empty sizes of the tail (Newman, Contemp. Phys. 46, 323 (2005), section 2); for a power law
///   N_s = A s^-tau the bin densities are A' s_c^-tau up to a factor that tends to the same
///   constant in every bin, so the slope is -tau exactly in the limit of large s. The estimator is
///   biased where few clusters fill a bin (Clauset et al. 2009, section 3.5): granagg reports it
///   beside the MLE, never instead of it.
/// - the onset time t_c of aggregation (the paper's "characteristic time t_c for the emergence of
///   aggregation", which falls as K grows): the first time at which S(t) reaches `factor` times its
///   early plateau S_base, the median of S over the samples with 0 < t <= t_base; the crossing is
///   interpolated linearly in (ln t, ln S) between the two samples that bracket it.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace granagg::analysis {

struct LogBinnedFit {
  bool valid = false;
  double tau = 0.0;         ///< minus the least-squares slope of ln(density) on ln(s_c)
  double tau_err = 0.0;     ///< its standard error from the residuals (bins - 2 degrees of freedom)
  std::size_t bins = 0;     ///< non-empty bins fitted
  std::uint64_t s_max = 0;  ///< largest size present
};

/// The paper's Fisher exponent from a size histogram (size -> count). Bins with no cluster are left
/// out (their logarithm does not exist). Needs clusters in at least `min_bins` (>= 3) bins,
/// otherwise `valid` is false. Throws std::invalid_argument for ratio <= 1 or min_bins < 3.
LogBinnedFit fitLogBinnedPowerLaw(const std::map<std::uint64_t, std::uint64_t>& counts,
                                  double ratio = 2.0, std::size_t min_bins = 3);

struct OnsetTime {
  bool valid =
      false;         ///< false when S never reaches the threshold or no sample lies in (0, t_base]
  double t_c = 0.0;  ///< onset time
  double S_base = 0.0;       ///< median S over 0 < t <= t_base
  double S_threshold = 0.0;  ///< factor x S_base
};

/// Onset time of the growth of S(t) (samples in increasing t; non-finite S are skipped).
/// Throws std::invalid_argument when the lengths differ, factor <= 1 or t_base <= 0.
OnsetTime onsetTime(const std::vector<double>& t, const std::vector<double>& S, double factor = 2.0,
                    double t_base = 10.0);

/// Relative spread (max - min) / mean of the local slope over the last half decade below which S(t)
/// counts as a power law ("scaling"): the paper's own local slopes vary by about this much over
/// its plateau (Singh & Mazza 2018, Fig. 5 inset).
constexpr double FLAT_SLOPE_TOLERANCE = 0.25;

/// Which regime a measured S(t) is in at its end, so that a short run is not read as a result.
struct GrowthRegime {
  double growth_factor = 0.0;  ///< S at the last sample / S_base (NaN without a baseline)
  double t_c = 0.0;            ///< onset time (NaN when not reached)
  double z_local_min = 0.0, z_local_max = 0.0;  ///< local slope range over the last half decade
  /// "none" (S has not reached factor x S_base), "onset" (S grows but the local slope still
  /// changes by more than `flat_tolerance` of its mean over the last half decade of t), or
  /// "scaling" (the local slope is flat within that tolerance there).
  std::string regime;
  std::string reason;  ///< one sentence with the numbers behind the verdict
};

/// Classifies S(t) with its local slope z_local(t) (same samples): growth factor and onset as in
/// onsetTime(factor, t_base); the local slope over [t_last / sqrt(10), t_last] (finite values, at
/// least 3, else "onset") decides between onset and scaling. flat_tolerance: relative spread
/// (max - min) / mean allowed for "scaling" (default 0.25: the paper's own local slopes vary by
/// about that much over its plateau). Throws std::invalid_argument for mismatched lengths.
GrowthRegime classifyGrowth(const std::vector<double>& t, const std::vector<double>& S,
                            const std::vector<double>& z_local, double factor = 2.0,
                            double t_base = 10.0, double flat_tolerance = FLAT_SLOPE_TOLERANCE);

}  // namespace granagg::analysis
