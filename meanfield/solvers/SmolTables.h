#pragma once
/// \file SmolTables.h
/// The tables `granagg smol` writes (docs/kinetic.md, README): S(t) of one solution of the
/// Smoluchowski equation from a monodisperse start, with its local slope, and the z(beta) table.
/// Requests are checked first: bad input throws std::invalid_argument with one sentence naming
/// the option (the command-line spelling, e.g. "--t-end") and its range; nothing is written then.
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/Csv.h"
#include "meanfield/solvers/SmolResult.h"

namespace granagg::meanfield {

class Kernel;

/// One solution: kernel, method and its numerical settings, output times, local-slope ratio.
struct SmolRequest {
  std::string kernel = "beta";  ///< beta, constant, additive, multiplicative
  double beta = 2.0, K0 = 1.0;
  std::string method = "sectional";  ///< sectional, discrete, mono
  double t_min = 1e-2, t_end = 1e6;
  int per_decade = 20;
  double s_end = std::numeric_limits<double>::infinity();
  long long max_size = 1 << 21;  ///< --M: the discrete method's largest size class
  double ratio = 1.05, rtol = 1e-8, atol = 1e-14;
  std::string integrator = "adams";
  double p = 2.0, z_tolerance = 1e-3;
  int snapshot_max_size = 0;  ///< discrete: keep n_k for k <= this at every output time (0: none)
};

/// z(beta) from the full equation beside 3 beta/(beta + 3).
struct ZbetaRequest {
  double beta_min = 2.0, beta_max = 4.0;
  int count = 21;
  std::string method = "sectional";
  double s_end = 1e8, ratio = 1.05;
};

/// Receives the summary lines (the command's log on stderr); may be empty (quiet).
using LogLine = std::function<void(const std::string&)>;

/// One solution of a SmolRequest in memory: what writeSmolTable writes.
struct SmolSolution {
  SmolResult result;            ///< samples (and snapshots with snapshot_max_size > 0, discrete)
  std::vector<double> z_local;  ///< per sample of result.samples: the local slope, NaN where the
                                ///  table has NaN (invalid samples, the first ones)
  std::string stopped;          ///< "cause; advice" when the solve stopped early, else ""
  std::string kernel_name;
  double wall_seconds = 0.0;
};

/// Checks a request (std::invalid_argument naming the option, as writeSmolTable does).
/// snapshot_max_size must be >= 0; the sectional and mono methods ignore it.
void checkSmolRequest(const SmolRequest& request);
/// Checks and solves; throws std::runtime_error when S stops being finite, as writeSmolTable.
SmolSolution solveSmol(const SmolRequest& request);

/// checkSmolRequest, then the target (CsvTarget::checkWritable), then solveSmol, written as t, S,
/// moments, z_local, mass_loss, valid, max_size (snapshots are not written). Nothing is written
/// when solveSmol throws.
void writeSmolTable(const SmolRequest& request, const common::CsvTarget& target,
                    const LogLine& log);
/// Solves once per beta and writes the z(beta) table, logging a line per beta.
void writeZbetaTable(const ZbetaRequest& request, const common::CsvTarget& target,
                     const LogLine& log);

/// Runs the chosen method ("sectional", "discrete", "mono"); all return moments on `times`.
/// snapshot_max_size > 0 keeps n_k for k <= it at every output time (discrete only).
SmolResult solveSmoluchowski(const Kernel& kernel, const std::string& method,
                             const std::vector<double>& times, double s_end, int max_size,
                             double ratio, double rtol, double atol, const std::string& integrator,
                             int snapshot_max_size = 0);

}  // namespace granagg::meanfield
