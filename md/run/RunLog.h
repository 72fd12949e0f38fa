#pragma once
/// \file RunLog.h
/// What a run tells its user (`granagg md` writes it on stderr): the lines before a run (version,
/// backend, system, time step, Coulomb set-up), the summary after it, the profile by phase, and
/// the progress line as a Reporter. Each line starts with "md: " and has no newline.
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "common/ProgressLine.h"
#include "md/run/Simulation.h"

namespace granagg::md {

/// Version, backend, N / phi / L / contact model / seed, dt and its reason, the Coulomb set-up
/// and multiple time stepping, and where a resumed run restarts.
std::vector<std::string> runStartLines(const Simulation& sim);
/// Steps, wall time and rate, the final state (summary.observables), slow Coulomb evaluations,
/// the files written.
std::vector<std::string> runSummaryLines(const Simulation& sim, const RunSummary& summary);
/// `--profile`: the loop's wall time by phase (profile.csv holds the same numbers).
std::vector<std::string> profileLines(const RunEngine& engine, std::int64_t steps,
                                      double loop_seconds);

/// The progress line (common/ProgressLine.h): time, T_g, rate and the time left; in place on a
/// terminal, a line a minute in a log.
class ProgressReporter : public Reporter {
 public:
  explicit ProgressReporter(const Simulation& sim);
  void report(const Simulation& sim) override;
  void finish(const Simulation&) override;

 private:
  using Clock = std::chrono::steady_clock;
  common::ProgressLine m_line;
  double m_t_end, m_t_start;
  std::int64_t m_first_step;
  Clock::time_point m_start;
};

}  // namespace granagg::md
