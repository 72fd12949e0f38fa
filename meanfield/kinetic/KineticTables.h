#pragma once
/// \file KineticTables.h
/// The tables `granagg kinetic` writes (docs/kinetic.md): each request is checked, evaluated with
/// the kinetic-theory functions of this folder and written as one CSV with its provenance. Bad
/// input throws std::invalid_argument with one sentence naming the option (the command-line
/// spelling, e.g. "--phi") and its allowed range; nothing is written then.
#include <string>
#include <vector>

#include "common/Csv.h"
#include "meanfield/kinetic/Restitution.h"

namespace granagg::meanfield {

using common::CsvTarget;

/// e(v) and contact times at the given impact speeds (restitution).
struct RestitutionRequest {
  double E = 278.6, D = 27.7;
  bool unclamped = false;
  std::string speeds = "0.05,0.1,1,2";  ///< comma separated, each > 0
};

/// Haff's law T(t) for constant restitution eps.
struct HaffRequest {
  double eps = 0.9, phi = 0.076, T0 = 1.0;
  double t_min = 1e-2, t_end = 1000.0;
  int points = 50;
};

/// Homogeneous cooling with the viscoelastic e(g).
struct CoolingRequest {
  double E = 278.6, D = 27.7;
  bool unclamped = false;
  double phi = 0.076;
  double t_min = 1e-2, t_end = 1000.0;
  int points = 50;
};

/// n, g2 and the Enskog collision frequency.
struct EnskogRequest {
  double phi = 0.076, T = 1.0;
};

/// The charging-rate exponent -a (1/2 + kappa).
struct ChargingRequest {
  double kappa = 0.83, cooling_exponent = 5.0 / 3.0;
};

/// One table of `granagg kinetic` in memory: what writeTable writes, without the command line.
struct KineticTable {
  common::Provenance provenance;  ///< the parameters (no command line)
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;  ///< one entry per row, columns.size() values each
  std::vector<std::string> comments;      ///< warnings the CSV carries as comment lines
};

/// Checks a request (std::invalid_argument as above) and computes its table. Nothing is printed:
/// a warning (an impact too fast for the Hertz law) is one of the table's comments.
KineticTable kineticTable(const RestitutionRequest& request);
KineticTable kineticTable(const HaffRequest& request);
KineticTable kineticTable(const CoolingRequest& request);
KineticTable kineticTable(const EnskogRequest& request);
KineticTable kineticTable(const ChargingRequest& request);

/// Writes kineticTable(request) as one CSV: the request is checked and computed before the target
/// is (CsvTarget::checkWritable), so bad input is named first. A warning comment precedes the row
/// it is about and also goes to stderr.
void writeTable(const RestitutionRequest& request, const CsvTarget& target);
void writeTable(const HaffRequest& request, const CsvTarget& target);
void writeTable(const CoolingRequest& request, const CsvTarget& target);
void writeTable(const EnskogRequest& request, const CsvTarget& target);
void writeTable(const ChargingRequest& request, const CsvTarget& target);

/// --v: comma-separated impact speeds, each > 0 and finite; an empty or malformed item is an
/// error.
std::vector<double> impactSpeeds(const std::string& text);

/// t = 0 followed by `points` log-spaced times from t_min to t_end (exactly t_end last).
std::vector<double> tableTimes(double t_min, double t_end, int points);

}  // namespace granagg::meanfield
