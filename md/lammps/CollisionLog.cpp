/// \file CollisionLog.cpp
/// collisions.csv (CollisionLog.h).
#include "md/lammps/CollisionLog.h"

#include <algorithm>
#include <stdexcept>

#include "common/Version.h"
#include "md/lammps/LammpsEngine.h"

namespace granagg::md::lammps {

namespace fs = std::filesystem;

std::vector<CollisionRecord> gatherCollisions(const std::vector<CollisionRecord>& mine,
                                              MPI_Comm comm) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int bytes = static_cast<int>(mine.size() * sizeof(CollisionRecord));
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(counts.size());
  MPI_Gather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::vector<CollisionRecord> all;
  if (rank == 0) {
    int total = 0;
    for (std::size_t r = 0; r < counts.size(); ++r) {
      displs[r] = total;
      total += counts[r];
    }
    all.resize(static_cast<std::size_t>(total) / sizeof(CollisionRecord));
  }
  MPI_Gatherv(mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, 0,
              comm);
  std::sort(all.begin(), all.end(), [](const CollisionRecord& a, const CollisionRecord& b) {
    return a.step != b.step ? a.step < b.step
                            : (a.id_lo != b.id_lo ? a.id_lo < b.id_lo : a.id_hi < b.id_hi);
  });
  return all;
}

namespace {
const std::vector<std::string> COLUMNS = {"step", "id_lo", "id_hi", "xi_dot", "dq_lo"};
}

CollisionLog::CollisionLog(const LammpsEngine& engine, const fs::path& path,
                           const std::string& command_line, std::int64_t resumed_from)
    : m_engine(engine) {
  std::string failure;
  if (engine.writesFiles()) {
    try {
      std::vector<std::vector<double>> kept;
      if (resumed_from >= 0 && fs::exists(path)) {
        const common::CsvTable old = common::readCsv(path.string());
        const std::size_t step = old.column("step");
        for (const auto& row : old.rows)
          if (row.at(step) <= static_cast<double>(resumed_from)) kept.push_back(row);
      }
      common::Provenance prov(command_line);
      prov.add("version", common::versionString());
      prov.add("backend", engine.description());
      m_csv =
          std::make_unique<common::CsvWriter>(path.string(), prov, COLUMNS, /*overwrite=*/true);
      for (const auto& row : kept) m_csv->row(row);
    } catch (const std::exception& e) {
      failure = e.what();
    }
  }
  if (engine.anyRank(!failure.empty()))  // (every rank stops, not only rank 0)
    throw std::runtime_error("cannot write " + path.string() +
                             (failure.empty() ? std::string(" (on rank 0)") : ": " + failure));
}

void CollisionLog::report(const Simulation&) {
  FixCharging& fix = m_engine.fix();
  const auto records = gatherCollisions(fix.collisionRecords(), m_engine.comm());
  fix.clearCollisionRecords();
  if (!m_csv) return;
  for (const auto& r : records)
    m_csv->row({static_cast<double>(r.step), static_cast<double>(r.id_lo),
                static_cast<double>(r.id_hi), r.xi_dot, r.dq_lo});
}

void CollisionLog::finish(const Simulation&) {
  if (!m_csv) return;
  try {  // (called while run() unwinds too: nothing may escape)
    m_csv->close();
  } catch (const std::exception& e) {
    m_error = e.what();
  }
  m_csv.reset();
}

}  // namespace granagg::md::lammps
