#include "analysis/io/AnalysisFile.h"

#include <cstdint>
#include <stdexcept>

#include "common/H5Journal.h"
#include "common/Hdf5.h"
#include "common/Version.h"

namespace granagg::analysis {
namespace h5 = common::h5;  // (common/Hdf5.h)

struct AnalysisFile::Impl {
  h5::Handle file;
  std::string path;
  // grid datasets of the run being written
  std::size_t grid_run = static_cast<std::size_t>(-1);
  int grid_n = 0;
  hsize_t grid_frames = 0;
  h5::Handle occ, lab, time, step;

  h5::Handle group(const std::string& g) {
    const std::string p = "/" + g;
    if (h5::exists(file.get(), p))
      return h5::check(H5Gopen2(file.get(), p.c_str(), H5P_DEFAULT), path + " " + p);
    return h5::createGroup(file.get(), p, "'" + path + "'");
  }

  h5::Handle extendible(hid_t loc, const char* name, hid_t type, int n) {
    std::vector<hsize_t> dims{0}, maxd{H5S_UNLIMITED}, chunk{1};
    for (int k = 0; k < (n > 0 ? 3 : 0); ++k) {
      dims.push_back(static_cast<hsize_t>(n));
      maxd.push_back(static_cast<hsize_t>(n));
      chunk.push_back(static_cast<hsize_t>(n));
    }
    if (n == 0) chunk[0] = 256;
    h5::Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxd.data()));
    h5::Handle dcpl(H5Pcreate(H5P_DATASET_CREATE));
    H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data());
    if (n > 0) H5Pset_deflate(dcpl.get(), 1);  // occupancy grids are mostly empty: compress
    return h5::check(H5Dcreate2(loc, name, type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                     "'" + path + "': cannot create " + name);
  }

  void append(hid_t d, hid_t mem, const void* data, int n) {
    std::vector<hsize_t> dims{grid_frames + 1}, start{grid_frames}, count{1};
    for (int k = 0; k < (n > 0 ? 3 : 0); ++k) {
      dims.push_back(static_cast<hsize_t>(n));
      start.push_back(0);
      count.push_back(static_cast<hsize_t>(n));
    }
    h5::checkStatus(H5Dset_extent(d, dims.data()), "'" + path + "': cannot extend the grid");
    h5::Handle fs(H5Dget_space(d));
    H5Sselect_hyperslab(fs.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
    h5::Handle ms(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr));
    h5::checkStatus(H5Dwrite(d, mem, ms.get(), fs.get(), H5P_DEFAULT, data),
                    "'" + path + "': cannot write the grid");
  }
};

AnalysisFile::AnalysisFile(const std::string& path, bool overwrite, const common::Provenance& prov)
    : m_impl(std::make_unique<Impl>()) {
  common::refuseToOverwrite(path, overwrite);
  h5::silenceErrors();
  m_impl->path = path;
  // Through the journaled driver (common/H5Journal.h), for its handling of a failed write: the
  // file freezes and closes cleanly, where HDF5's own driver leaves a half-closed file that
  // HDF5 crashes on at exit (a full disk ended `granagg analyze` with a segmentation fault).
  // Nothing is committed before the file is complete, so no journal entries are ever written.
  h5::Handle fapl(static_cast<hid_t>(common::h5journal::fileAccess()));
  m_impl->file = h5::check(
      H5Fcreate(path.c_str(), overwrite ? H5F_ACC_TRUNC : H5F_ACC_EXCL, H5P_DEFAULT, fapl.get()),
      "cannot create '" + path + "'");
  const std::string c = "'" + path + "'";
  h5::writeStringAttribute(m_impl->file.get(), "command", prov.command(), c);
  h5::writeStringAttribute(m_impl->file.get(), "version", common::versionString(), c);
  for (const auto& [k, v] : prov.parameters())
    h5::writeStringAttribute(m_impl->file.get(), k, v, c);
}

AnalysisFile::~AnalysisFile() {
  try {
    close();
  } catch (...) {
  }
}

const std::string& AnalysisFile::path() const { return m_impl->path; }

void AnalysisFile::writeTable(const std::string& group, const Table& t) {
  Impl& m = *m_impl;
  h5::Handle g = m.group(group + "/" + t.name);
  const std::string c = "'" + m.path + "' /" + group + "/" + t.name;
  h5::writeStringAttribute(g.get(), "description", t.description, c);
  for (std::size_t k = 0; k < t.columns.size(); ++k) {
    std::vector<double> v;
    v.reserve(t.rows.size());
    for (const auto& r : t.rows) v.push_back(r[k]);
    h5::writeDataset(g.get(), t.columns[k], H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {v.size()}, v.data(),
                     c);
  }
}

void AnalysisFile::writeAttributes(const std::string& group,
                                   const std::map<std::string, std::string>& attrs) {
  Impl& m = *m_impl;
  h5::Handle g = m.group(group);
  for (const auto& [k, v] : attrs) {
    if (H5Aexists(g.get(), k.c_str()) > 0) H5Adelete(g.get(), k.c_str());
    h5::writeStringAttribute(g.get(), k, v, "'" + m.path + "' /" + group);
  }
}

void AnalysisFile::writeGridFrame(std::size_t run, const Frame& f, const GridClusters& gc) {
  Impl& m = *m_impl;
  const int n = gc.cellsPerSide();
  if (run != m.grid_run) {
    m.occ.reset();
    m.lab.reset();
    m.time.reset();
    m.step.reset();
    h5::Handle g = m.group("runs/" + std::to_string(run) + "/grid");
    const std::string c = "'" + m.path + "' grid";
    h5::writeAttribute(g.get(), "cells_per_side", static_cast<double>(n), c);  // (stored as F64)
    h5::writeAttribute(g.get(), "cell_size", gc.cellSize(), c);
    h5::writeAttribute(g.get(), "min_count", gc.minCount(), c);
    h5::writeStringAttribute(
        g.get(), "layout",
        "[frame, ix, iy, iz]; labels -1 = empty, clusters from 0 (6-connectivity, periodic)", c);
    m.occ = m.extendible(g.get(), "occupancy", H5T_STD_U8LE, n);
    m.lab = m.extendible(g.get(), "labels", H5T_STD_I32LE, n);
    m.time = m.extendible(g.get(), "time", H5T_IEEE_F64LE, 0);
    m.step = m.extendible(g.get(), "step", H5T_STD_I64LE, 0);
    m.grid_run = run;
    m.grid_n = n;
    m.grid_frames = 0;
  }
  if (n != m.grid_n)
    throw std::runtime_error("--write-grid: the grid size changed within run " +
                             std::to_string(run) + " (box changed)");
  m.append(m.occ.get(), H5T_NATIVE_UINT8, gc.occupancy().data(), n);
  m.append(m.lab.get(), H5T_NATIVE_INT32, gc.labels().data(), n);
  m.append(m.time.get(), H5T_NATIVE_DOUBLE, &f.time, 0);
  m.append(m.step.get(), H5T_NATIVE_INT64, &f.step, 0);
  ++m.grid_frames;
}

void AnalysisFile::close() {
  if (!m_impl || !m_impl->file) return;
  Impl& m = *m_impl;
  m.occ.reset();
  m.lab.reset();
  m.time.reset();
  m.step.reset();
  // every write must have reached the file: HDF5 does not report each failure to us (a closed
  // dataset flushes its buffer without a status anyone reads), the journaled driver does
  common::h5journal::requireWritten(m.file.get());
  if (!m.file.reset()) h5::fail("'" + m.path + "': closing failed");
}

}  // namespace granagg::analysis
