/// \file RunAnalysis.cpp
/// One run's analysis frame by frame (RunAnalysis.h), and its state file.
#include "analysis/pipeline/RunAnalysis.h"

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <utility>

#include "analysis/pipeline/FrameObservables.h"
#include "common/Hdf5.h"
#include "common/Strings.h"

namespace granagg::analysis {
namespace fs = std::filesystem;
namespace h5 = common::h5;

namespace {
/// Written into every state file: a file without it, or with another value, is not a state this
/// build can continue.
constexpr const char* STATE_KIND = "granagg run-analysis state 1";
}  // namespace

struct RunAnalysis::Impl {
  // The compute objects hold a reference to the options: they live here, at a fixed address.
  AnalysisOptions options;
  RunCallbacks callbacks;
  RunResult result;  // source, format, parameters, kappa, notes; the tables come at finish()
  ClusterObservables clusters;
  StructureObservable structure;
  MotionObservables motion;
  GrowthTable growth;
  std::int64_t last_step = -1;
  bool finished = false;

  Impl(const AnalysisOptions& o, RunCallbacks cb)
      : options(o), callbacks(std::move(cb)), clusters(options), structure(options),
        motion(options) {}

  ObservableState state() const {
    ObservableState s;
    clusters.save(s);
    if (options.structure_factor) structure.save(s);
    motion.save(s);
    growth.save(s);
    std::string notes;
    for (const auto& n : result.notes) notes += (notes.empty() ? "" : "\n") + n;
    s.texts["run.notes"] = notes;
    s.texts["run.source"] = result.source;
    s.integers["run.counts"] = {static_cast<std::int64_t>(result.frames),
                                static_cast<std::int64_t>(result.particles), last_step};
    s.reals["run.box"] = {result.box};
    return s;
  }
};

RunAnalysis::RunAnalysis(const AnalysisOptions& options, std::string source, std::string format,
                         std::map<std::string, std::string> parameters, RunCallbacks callbacks) {
  options.validate();
  m_impl = std::make_unique<Impl>(options, std::move(callbacks));
  RunResult& r = m_impl->result;
  r.source = std::move(source);
  r.format = std::move(format);
  r.parameters = std::move(parameters);
  std::tie(r.kappa, r.kappa_source) = resolveKappa(options, r.parameters);
}

RunAnalysis::RunAnalysis(RunAnalysis&&) noexcept = default;
RunAnalysis& RunAnalysis::operator=(RunAnalysis&&) noexcept = default;
RunAnalysis::~RunAnalysis() = default;

void RunAnalysis::add(const Frame& f) {
  Impl& d = *m_impl;
  if (d.finished) throw std::logic_error("RunAnalysis::add after finish()");
  RunResult& r = d.result;
  const bool first = r.frames == 0;
  // the checks come first: a refused frame leaves the state as it was
  if (!first && f.size() != r.particles)
    throw TrajectoryError(r.source, f.index,
                          "has " + std::to_string(f.size()) + " particles, the first frame had " +
                              std::to_string(r.particles));
  if (!first && !(f.time > d.growth.times().back()))
    throw TrajectoryError(r.source, f.index,
                          "time " + common::formatReal(f.time) + " does not increase");
  if (first) {
    r.particles = f.size();
    r.box = f.box;
    d.clusters.first(f);
    d.motion.first(f, r);
  }
  const ClusterObservables::Row c = d.clusters.add(f, d.callbacks);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const StructureObservable::Lengths l =
      d.options.structure_factor ? d.structure.add(f) : StructureObservable::Lengths{nan, nan, nan};
  d.growth.add(f.time, f.step, c, l);
  d.motion.add(f);
  d.last_step = f.step;
  ++r.frames;
}

std::size_t RunAnalysis::frames() const { return m_impl->result.frames; }

double RunAnalysis::lastTime() const {
  const auto& t = m_impl->growth.times();
  return t.empty() ? std::numeric_limits<double>::quiet_NaN() : t.back();
}

std::int64_t RunAnalysis::lastStep() const { return m_impl->last_step; }

void RunAnalysis::setPartial(const std::string& reason) {
  m_impl->result.partial = true;
  m_impl->result.partial_reason = reason;
}

RunResult RunAnalysis::finish() {
  Impl& d = *m_impl;
  if (d.finished) throw std::logic_error("RunAnalysis::finish called twice");
  RunResult& r = d.result;
  if (r.frames == 0)
    throw std::invalid_argument("run '" + r.source + "': no frame was analysed");
  d.finished = true;
  const AnalysisOptions& o = d.options;
  d.clusters.describe(r);
  d.growth.finish(o.slope_ratio);
  Table fits = runFits(d.growth.times(), d.growth.sGrid(), d.growth.sParticle(),
                       d.motion.hasCharges() ? &d.motion.meanAbsCharge() : nullptr, r.kappa, o);
  // the tables in the order of the output
  r.tables.push_back(std::move(d.growth.table()));
  if (o.grid_clusters) r.tables.push_back(std::move(d.clusters.nsGrid()));
  if (o.particle_clusters) r.tables.push_back(std::move(d.clusters.nsParticle()));
  if (o.structure_factor) r.tables.push_back(std::move(d.structure.table()));
  if (o.structure_factor && !d.structure.velocityTable().rows.empty())
    r.tables.push_back(std::move(d.structure.velocityTable()));
  r.tables.push_back(std::move(d.clusters.fisher()));
  d.motion.finish(r.source, r);
  if (o.particle_clusters && d.clusters.tracks()) r.tables.push_back(std::move(d.clusters.nstick()));
  r.tables.push_back(std::move(fits));
  if (r.partial) r.notes.push_back("partial: " + r.partial_reason);
  return std::move(r);
}

// ---- the state file ----------------------------------------------------------------------------
// One HDF5 file: attributes kind and tag; groups reals/, integers/ and texts/ with one dataset per
// key. It is written beside its final name and renamed over it after an fsync, so that a kill
// leaves the previous file or the new one, never a torn one.

void RunAnalysis::saveState(const std::string& path, std::int64_t tag) const {
  if (m_impl->finished) throw std::logic_error("RunAnalysis::saveState after finish()");
  const ObservableState s = m_impl->state();
  const std::string tmp = path + ".tmp";
  const std::string ctx = "analysis state '" + path + "'";
  h5::silenceErrors();
  {
    h5::Handle file = h5::check(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                                ctx + ": cannot create " + tmp);
    h5::writeStringAttribute(file.get(), "kind", STATE_KIND, ctx);
    h5::writeAttribute(file.get(), "tag", static_cast<std::int64_t>(tag), ctx);
    h5::Handle reals = h5::createGroup(file.get(), "reals", ctx);
    h5::Handle ints = h5::createGroup(file.get(), "integers", ctx);
    h5::Handle texts = h5::createGroup(file.get(), "texts", ctx);
    const double no_real = 0.0;
    const std::int64_t no_int = 0;
    for (const auto& [key, v] : s.reals)
      h5::writeDataset(reals.get(), key, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {v.size()},
                       v.empty() ? &no_real : v.data(), ctx);
    for (const auto& [key, v] : s.integers)
      h5::writeDataset(ints.get(), key, H5T_STD_I64LE, H5T_NATIVE_INT64, {v.size()},
                       v.empty() ? &no_int : v.data(), ctx);
    for (const auto& [key, v] : s.texts) h5::writeStringDataset(texts.get(), key, v, ctx);
    h5::checkStatus(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), ctx + ": cannot flush");
    if (!file.reset()) h5::fail(ctx + ": cannot close " + tmp);
  }
  const int fd = ::open(tmp.c_str(), O_RDONLY);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  std::error_code ec;
  if (!synced) {
    fs::remove(tmp, ec);
    throw std::runtime_error(ctx + ": cannot sync " + tmp);
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(ctx + ": cannot rename " + tmp + ": " + ec.message());
  }
  const std::string dir = fs::path(path).parent_path().empty()
                              ? std::string(".")
                              : fs::path(path).parent_path().string();
  if (const int dfd = ::open(dir.c_str(), O_RDONLY); dfd >= 0) {
    ::fsync(dfd);  // the rename itself
    ::close(dfd);
  }
}

namespace {

h5::Handle openState(const std::string& path) {
  h5::silenceErrors();
  const std::string ctx = "analysis state '" + path + "'";
  h5::Handle file = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                              ctx + ": cannot open");
  if (!h5::openAttribute(file.get(), "kind") ||
      h5::readStringAttribute(file.get(), "kind", ctx) != STATE_KIND)
    throw std::runtime_error(ctx + ": not a granagg run-analysis state");
  return file;
}

}  // namespace

std::int64_t RunAnalysis::stateTag(const std::string& path) {
  h5::Handle file = openState(path);
  h5::Handle attr = h5::openAttribute(file.get(), "tag");
  const std::string ctx = "analysis state '" + path + "': tag";
  if (!attr) throw std::runtime_error(ctx + " is missing");
  const auto v = h5::readNumericAttribute<std::int64_t>(attr.get(), H5T_NATIVE_INT64, ctx);
  if (v.size() != 1) throw std::runtime_error(ctx + " is not one number");
  return v[0];
}

void RunAnalysis::restoreState(const std::string& path) {
  Impl& d = *m_impl;
  if (d.finished) throw std::logic_error("RunAnalysis::restoreState after finish()");
  const std::string ctx = "analysis state '" + path + "'";
  h5::Handle file = openState(path);
  ObservableState s;
  auto group = [&](const char* name) {
    return h5::check(H5Gopen2(file.get(), name, H5P_DEFAULT), ctx + ": no group " + name);
  };
  {
    h5::Handle g = group("reals");
    for (const auto& key : h5::datasetNames(g.get(), ctx)) {
      h5::Handle ds = h5::check(H5Dopen2(g.get(), key.c_str(), H5P_DEFAULT), ctx + ": " + key);
      s.reals[key] = h5::readAll<double>(ds.get(), H5T_NATIVE_DOUBLE, ctx + ": " + key);
    }
  }
  {
    h5::Handle g = group("integers");
    for (const auto& key : h5::datasetNames(g.get(), ctx)) {
      h5::Handle ds = h5::check(H5Dopen2(g.get(), key.c_str(), H5P_DEFAULT), ctx + ": " + key);
      s.integers[key] = h5::readAll<std::int64_t>(ds.get(), H5T_NATIVE_INT64, ctx + ": " + key);
    }
  }
  {
    h5::Handle g = group("texts");
    for (const auto& key : h5::datasetNames(g.get(), ctx)) {
      h5::Handle ds = h5::check(H5Dopen2(g.get(), key.c_str(), H5P_DEFAULT), ctx + ": " + key);
      s.texts[key] = h5::readString(ds.get(), false, ctx + ": " + key);
    }
  }
  try {
    d.clusters.restore(s);
    if (d.options.structure_factor) d.structure.restore(s);
    d.motion.restore(s);
    d.growth.restore(s);
    const auto& counts = s.integer("run.counts");
    if (counts.size() != 3 || counts[0] < 0 || counts[1] < 0)
      throw std::runtime_error("the saved run counts are not 3 values");
    d.result.frames = static_cast<std::size_t>(counts[0]);
    d.result.particles = static_cast<std::size_t>(counts[1]);
    d.last_step = counts[2];
    d.result.box = s.real("run.box").at(0);
    d.result.notes.clear();
    const std::string& notes = s.text("run.notes");
    for (std::size_t a = 0; !notes.empty() && a <= notes.size();) {
      const std::size_t b = std::min(notes.find('\n', a), notes.size());
      d.result.notes.push_back(notes.substr(a, b - a));
      a = b + 1;
    }
    if (d.growth.times().size() != d.result.frames)
      throw std::runtime_error("its S_t table holds " + std::to_string(d.growth.times().size()) +
                               " rows for " + std::to_string(d.result.frames) + " frames");
  } catch (const std::exception& e) {
    throw std::runtime_error(ctx + ": " + e.what());
  }
}

}  // namespace granagg::analysis
