#pragma once
/// \file CollisionLog.h
/// collisions.csv of granagg-lammps --collisions: every collision of the run (step, the two
/// particle ids, the approach speed and the charge the lower id gained), as a md::Reporter. The
/// fix records the collisions on the rank that holds each pair (FixCharging `record yes`); after
/// every chunk of steps they are gathered to rank 0 and written in (step, id_lo, id_hi) order.
/// A continued run (--restart) keeps the rows up to its checkpoint's step and appends its own, so
/// the file ends as the uninterrupted run's would. The table appears when the run ends
/// (common::CsvWriter): a run killed without a chance to stop (SIGKILL) leaves none.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "common/Csv.h"
#include "md/lammps/FixCharging.h"
#include "md/run/Simulation.h"

namespace granagg::md::lammps {

class LammpsEngine;

/// Every rank's collision records to rank 0, sorted by (step, id_lo, id_hi); empty elsewhere
/// (collective).
std::vector<CollisionRecord> gatherCollisions(const std::vector<CollisionRecord>& mine,
                                              MPI_Comm comm);

class CollisionLog : public Reporter {
 public:
  /// Collective. `path` is written by rank 0; with resumed_from >= 0 the rows of an existing
  /// file up to that step are kept.
  CollisionLog(const LammpsEngine& engine, const std::filesystem::path& path,
               const std::string& command_line, std::int64_t resumed_from = -1);
  /// Gathers and writes the collisions of the chunk (collective).
  void report(const Simulation& sim) override;
  /// Closes the table (rank 0); a failure is kept for error().
  void finish(const Simulation& sim) override;
  /// Why the table could not be written ("" if it was).
  const std::string& error() const { return m_error; }

 private:
  const LammpsEngine& m_engine;
  std::unique_ptr<common::CsvWriter> m_csv;  // rank 0
  std::string m_error;
};

}  // namespace granagg::md::lammps
