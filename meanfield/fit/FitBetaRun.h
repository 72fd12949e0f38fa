#pragma once
/// \file FitBetaRun.h
/// What `granagg fit-beta` does, as a library (docs/fit-beta.md): from S(t) (GrowthInput.h) to
/// z over a window, beta from z (at the data's S range, at S / S_c, and by the asymptotic law),
/// the full-curve fit, and the outputs fit_beta.csv, fit_curve.csv and fit_beta.json
/// (nlohmann-json), plus the summary lines the terminal shows. The steps themselves are
/// BetaFit.h's.
#include <string>
#include <vector>

#include "common/PaperValues.h"
#include "meanfield/fit/BetaFit.h"
#include "meanfield/fit/GrowthInput.h"

namespace granagg::meanfield {

struct FitBetaRequest {
  std::vector<double> window;  ///< [] (automatic) or {t0, t1}
  double beta_min = 1.5, beta_max = 6.0;
  bool curve_fit = true;
  int min_points = 5;  ///< fewest samples with t > 0 (and in the window)
};

struct FitBetaResult {
  GrowthInput input;  ///< after dropUnusableRows
  GrowthData data;
  FitBetaRequest request;
  SlopeWindow window;
  BootstrapOptions bootstrap;
  ZFit z;
  BetaFromZ from_z;               ///< at the window's S range [S0, S1]
  BetaFromZ from_z_scaled;        ///< at [S0, S1] / S_c (S_c from the curve fit; NaN without it)
  BetaFromZ asymptotic;           ///< 3 z / (3 - z)
  double z_mf_beta2, z_mf_beta3;  ///< the mean field's exponent over [S0, S1] at beta = 2, 3
  CurveFit curve;                 ///< NaN without the curve fit
  /// the mean field for beta = 2 and 3 with the fitted S_c and tau_c, at the data's times
  std::vector<double> S_mf_beta2, S_mf_beta3;
  double mf_ratio = 0.0, mf_rtol = 0.0;  ///< the mean-field curves' grid ratio and tolerance
};

/// Runs every step on `input`. Throws std::invalid_argument naming INPUT for unusable data (too
/// few samples, S not positive, a bad window or beta range).
FitBetaResult runFitBeta(GrowthInput input, const FitBetaRequest& request);

/// The files written into a folder.
struct FitBetaFiles {
  std::string csv, curve, json;
};
FitBetaFiles fitBetaFiles(const std::string& folder);

/// Refuses (std::invalid_argument) to overwrite existing outputs unless `force`: call before
/// runFitBeta, so that a refusal costs nothing.
void checkFitBetaOutputs(const std::string& folder, bool curve_fit, bool force);

/// Writes fit_beta.csv, fit_curve.csv (with the curve fit) and fit_beta.json into `folder`, with
/// the command line and every setting as provenance; the paper's values go into the JSON beside
/// ours.
void writeFitBeta(const FitBetaResult& r, const std::string& folder,
                  const std::string& command_line, const common::PaperValues& paper, bool force);

/// The summary for the terminal, one line each (without a prefix).
std::vector<std::string> fitBetaReport(const FitBetaResult& r, const common::PaperValues& paper);

}  // namespace granagg::meanfield
