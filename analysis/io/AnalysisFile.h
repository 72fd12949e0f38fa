#pragma once
/// \file AnalysisFile.h
/// analysis.h5: everything `granagg analyze` computed, in one HDF5 file readable with h5py:
///
///     /            attributes: command, version, options (provenance)
///     /runs/<k>/   attributes: source, format, frames, ...; one group per table, one 1-D
///                  dataset per column (/runs/0/S_t/t, /runs/0/S_t/S_grid, ...)
///     /runs/<k>/grid/  (--write-grid) occupancy [F, n, n, n] uint8, labels [F, n, n, n] int32
///                  (-1 = empty site, clusters numbered from 0), time [F], step [F]
///     /ensemble/<table>/<column>   ensemble averages (mean, se)
///
/// Grid index order [frame, ix, iy, iz], cell (ix, iy, iz) covering [ix h, (ix+1) h) x ...
#include <map>
#include <memory>
#include <string>

#include "analysis/clusters/GridClusters.h"
#include "analysis/io/Frame.h"
#include "analysis/pipeline/Table.h"
#include "common/Csv.h"

namespace granagg::analysis {

class AnalysisFile {
 public:
  /// Creates `path`; refuses to overwrite an existing file unless `overwrite`.
  AnalysisFile(const std::string& path, bool overwrite, const common::Provenance& provenance);
  ~AnalysisFile();
  AnalysisFile(const AnalysisFile&) = delete;
  AnalysisFile& operator=(const AnalysisFile&) = delete;

  /// Writes `table` under /<group>/<table name>/.
  void writeTable(const std::string& group, const Table& table);
  /// String attributes on /<group> (created if needed).
  void writeAttributes(const std::string& group,
                       const std::map<std::string, std::string>& attributes);
  /// Appends one frame's occupancy and labels to /runs/<run>/grid (streamed: one frame in memory).
  void writeGridFrame(std::size_t run, const Frame& frame, const GridClusters& grid);
  /// Flushes and closes; throws std::runtime_error when HDF5 fails.
  void close();
  const std::string& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::analysis
