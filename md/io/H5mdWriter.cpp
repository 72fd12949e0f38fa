#include "md/io/H5mdWriter.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <algorithm>
#include <cerrno>
#include <exception>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/Csv.h"
#include "common/H5Journal.h"
#include "common/Hdf5.h"
#include "common/Strings.h"
#include "common/Version.h"
#include "md/io/InitialState.h"

namespace granagg::md {
namespace h5 = common::h5;  // (common/Hdf5.h)

namespace {

constexpr hsize_t STEP_CHUNK = 256;           // rows per chunk of step/time (one row per frame)
constexpr hsize_t OBS_CHUNK = 1024;           // rows per chunk of observable series
constexpr std::size_t OBS_BUFFER_MAX = 4096;  // buffered observable samples before a write
constexpr std::size_t XDMF_EVERY_FRAME_UP_TO =
    1000;  // then every XDMF_STRIDE frames (and at flush)
constexpr std::size_t XDMF_STRIDE = 100;

std::string particlePath() { return std::string("/particles/") + H5MD_PARTICLE_GROUP; }

std::string authorName() {
  for (const char* var : {"USER", "LOGNAME"}) {
    const char* v = std::getenv(var);
    if (v && *v) return v;
  }
  return "unknown";
}

std::string baseName(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string xmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

struct H5mdWriter::Impl {
  // The file handle is declared first so that it is closed last (members die in reverse order).
  h5::Handle file;
  std::string path, xdmf_path;
  std::size_t n = 0;
  bool velocities = true;
  bool forces = false;
  bool closed = false;

  h5::Handle pos, vel, force, charge, image, edges, step, time;
  std::size_t frames = 0;
  bool have_last_step = false;
  std::int64_t last_step = 0;
  std::vector<double> frame_times;                         // for the XDMF sidecar
  std::size_t xdmf_frames = static_cast<std::size_t>(-1);  // frames described by the sidecar

  // observables
  std::vector<std::string> obs_names;
  std::vector<h5::Handle> obs_value;
  h5::Handle obs_step, obs_time;
  std::size_t obs_written = 0;
  bool have_last_obs_step = false;
  std::int64_t last_obs_step = 0;
  std::vector<std::int64_t> buf_step;
  std::vector<double> buf_time;
  std::vector<std::vector<double>> buf_values;  // [name][sample]
  // A reopened file's observables may differ from what the restarted program writes (a run
  // continued by a newer granagg, which has an observable more): see writeObservables.
  bool reopened = false;
  std::string repair_note;  // what reopen() rolled back ("" if nothing)

  std::string ctx() const { return "H5MD file '" + path + "'"; }

  void requireOpen() const {
    if (closed) throw std::logic_error("H5mdWriter: '" + path + "' is already closed");
  }

  void createLayout(const std::vector<std::pair<std::string, std::string>>& parameters,
                    const std::string& config_toml) {
    const std::string c = ctx();
    {
      h5::Handle g = h5::createGroup(file.get(), "h5md", c);
      const int version[2] = {1, 1};
      h5::writeAttribute(g.get(), "version", H5T_STD_I32LE, H5T_NATIVE_INT, version, {2},
                         c + " /h5md");
      h5::Handle author = h5::createGroup(g.get(), "author", c);
      h5::writeFixedStringAttribute(author.get(), "name", authorName(), c + " /h5md/author");
      h5::Handle creator = h5::createGroup(g.get(), "creator", c);
      h5::writeFixedStringAttribute(creator.get(), "name", "granagg", c + " /h5md/creator");
      h5::writeFixedStringAttribute(creator.get(), "version", common::versionString(),
                                    c + " /h5md/creator");
    }
    const std::string pg = particlePath();
    h5::Handle part = h5::createGroup(file.get(), pg, c);
    const hsize_t N = n;
    // Chunks of one frame, capped at ~8 MiB so that huge systems do not make huge chunks; the
    // particles are split into equal chunks because HDF5 stores a partial edge chunk full size.
    const hsize_t rows_cap = std::max<hsize_t>(1, (8u << 20) / (3 * sizeof(double)));
    const hsize_t pieces = (N + rows_cap - 1) / rows_cap;
    const hsize_t nchunk = (N + pieces - 1) / pieces;
    auto series = [&](const std::string& name, hid_t type, std::vector<hsize_t> inner) {
      h5::Handle g = h5::createGroup(part.get(), name, c);
      std::vector<hsize_t> chunk_inner = inner;
      chunk_inner[0] = nchunk;
      return h5::createExtendible(g.get(), "value", type, inner, 1, c + " " + pg + "/" + name,
                                  chunk_inner);
    };
    pos = series("position", H5T_IEEE_F64LE, {N, 3});
    if (velocities) vel = series("velocity", H5T_IEEE_F64LE, {N, 3});
    if (forces) force = series("force", H5T_IEEE_F64LE, {N, 3});
    charge = series("charge", H5T_IEEE_F64LE, {N});
    image = series("image", H5T_STD_I32LE, {N, 3});
    {
      h5::Handle box = h5::createGroup(part.get(), "box", c);
      const int dim = 3;
      h5::writeAttribute(box.get(), "dimension", H5T_STD_I32LE, H5T_NATIVE_INT, &dim, {},
                         c + " box");
      h5::writeFixedStringArrayAttribute(box.get(), "boundary",
                                         {"periodic", "periodic", "periodic"}, c + " box");
      h5::Handle eg = h5::createGroup(box.get(), "edges", c);
      edges = h5::createExtendible(eg.get(), "value", H5T_IEEE_F64LE, {3, 3}, 16, c + " box/edges");
    }
    // The single step/time pair, hard-linked into every element.
    {
      h5::Handle g = h5::check(H5Gopen2(part.get(), "position", H5P_DEFAULT), c);
      step = h5::createExtendible(g.get(), "step", H5T_STD_I64LE, {}, STEP_CHUNK, c + " position");
      time = h5::createExtendible(g.get(), "time", H5T_IEEE_F64LE, {}, STEP_CHUNK, c + " position");
      std::vector<std::string> others{"charge", "image", "box/edges"};
      if (velocities) others.push_back("velocity");
      if (forces) others.push_back("force");
      for (const auto& o : others) {
        for (const char* what : {"step", "time"}) {
          const std::string src = pg + "/position/" + what, dst = pg + "/" + o + "/" + what;
          h5::checkStatus(H5Lcreate_hard(file.get(), src.c_str(), file.get(), dst.c_str(),
                                         H5P_DEFAULT, H5P_DEFAULT),
                          c + ": cannot link " + dst);
        }
      }
    }
    {
      h5::Handle par = h5::createGroup(file.get(), "parameters", c);
      for (const auto& [k, v] : parameters)
        h5::writeStringAttribute(par.get(), k, v, c + " /parameters");
      h5::writeStringDataset(par.get(), H5MD_CONFIG_DATASET, config_toml, c + " /parameters");
    }
  }

  void openLayout() {
    const std::string c = ctx(), pg = particlePath();
    auto open = [&](const std::string& p) {
      if (h5::objectType(file.get(), p) != H5I_DATASET)
        throw std::invalid_argument(c + " has no dataset '" + p +
                                    "' (not written by granagg's H5mdWriter?)");
      return h5::check(H5Dopen2(file.get(), p.c_str(), H5P_DEFAULT), c + ": cannot open " + p);
    };
    pos = open(pg + "/position/value");
    charge = open(pg + "/charge/value");
    image = open(pg + "/image/value");
    edges = open(pg + "/box/edges/value");
    step = open(pg + "/position/step");
    time = open(pg + "/position/time");
    const bool has_vel = h5::exists(file.get(), pg + "/velocity/value");
    if (has_vel != velocities)
      throw std::invalid_argument(
          c + (has_vel ? " has" : " has no") +
          " velocities but write_velocities = " + (velocities ? "true" : "false"));
    if (velocities) vel = open(pg + "/velocity/value");
    const bool has_force = h5::exists(file.get(), pg + "/force/value");
    if (has_force != forces)
      throw std::invalid_argument(c + (has_force ? " has" : " has no") +
                                  " forces but write_forces = " + (forces ? "true" : "false"));
    if (forces) force = open(pg + "/force/value");
    const auto d = h5::datasetDims(pos.get(), c);
    if (d.size() != 3 || d[1] != n || d[2] != 3)
      throw std::invalid_argument(c + " holds " +
                                  (d.size() == 3 ? std::to_string(d[1]) : std::string("?")) +
                                  " particles, expected N = " + std::to_string(n));
    if (h5::exists(file.get(), H5MD_OBSERVABLES_GROUP)) {
      h5::Handle og = h5::check(H5Gopen2(file.get(), H5MD_OBSERVABLES_GROUP, H5P_DEFAULT), c);
      for (const auto& name : h5::children(og.get())) {
        const std::string base = std::string(H5MD_OBSERVABLES_GROUP) + "/" + name;
        obs_names.push_back(name);
        obs_value.push_back(open(base + "/value"));
        if (!obs_step) {
          obs_step = open(base + "/step");
          obs_time = open(base + "/time");
        }
      }
      buf_values.assign(obs_names.size(), {});
    }
  }

  /// Shrinks every time series to the rows with step <= restart_step.
  void truncateAfter(std::int64_t restart_step) {
    const std::string c = ctx();
    auto keepRows = [&](hid_t step_ds) {
      const auto steps = h5::readAll<std::int64_t>(step_ds, H5T_NATIVE_INT64, c + " step");
      std::size_t keep = 0;
      while (keep < steps.size() && steps[keep] <= restart_step) ++keep;
      return keep;
    };
    auto shrink = [&](hid_t d, std::size_t rows) {
      auto dims = h5::datasetDims(d, c);
      if (dims[0] > rows) {
        dims[0] = rows;
        h5::checkStatus(H5Dset_extent(d, dims.data()), c + ": cannot truncate");
      }
    };
    // Frames are complete only when their step/time rows exist (written last); value rows past
    // them are leftovers of a killed run and are cut as well.
    const std::size_t nt =
        std::min<std::size_t>(h5::datasetDims(step.get(), c)[0], h5::datasetDims(time.get(), c)[0]);
    frames = std::min<std::size_t>(keepRows(step.get()), nt);
    for (hid_t d : {pos.get(), vel.get(), force.get(), charge.get(), image.get(), edges.get(),
                    step.get(), time.get()})
      if (d >= 0) shrink(d, frames);
    frame_times = h5::readAll<double>(time.get(), H5T_NATIVE_DOUBLE, c + " time");
    if (frames > 0) {
      const auto steps = h5::readAll<std::int64_t>(step.get(), H5T_NATIVE_INT64, c + " step");
      have_last_step = true;
      last_step = steps.back();
    }
    if (obs_step) {
      std::size_t rows =
          std::min<std::size_t>(keepRows(obs_step.get()), h5::datasetDims(obs_time.get(), c)[0]);
      for (const auto& v : obs_value)
        rows = std::min<std::size_t>(rows, h5::datasetDims(v.get(), c)[0]);
      for (const auto& v : obs_value) shrink(v.get(), rows);
      shrink(obs_step.get(), rows);
      shrink(obs_time.get(), rows);
      obs_written = rows;
      if (rows > 0) {
        const auto s = h5::readAll<std::int64_t>(obs_step.get(), H5T_NATIVE_INT64, c);
        have_last_obs_step = true;
        last_obs_step = s.back();
      }
    }
  }

  void createObservables(const std::vector<std::pair<std::string, double>>& values) {
    const std::string c = ctx();
    std::set<std::string> seen;
    for (const auto& kv : values) {
      const std::string& name = kv.first;
      if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..")
        throw std::invalid_argument("H5mdWriter: observable name '" + name +
                                    "' is not allowed (empty, '.', or contains '/')");
      if (!seen.insert(name).second)
        throw std::invalid_argument("H5mdWriter: observable '" + name + "' given twice");
    }
    if (values.empty())
      throw std::invalid_argument("H5mdWriter: writeObservables needs at least one value");
    h5::Handle og = h5::createGroup(file.get(), H5MD_OBSERVABLES_GROUP, c);
    const std::string first = std::string(H5MD_OBSERVABLES_GROUP) + "/" + values[0].first;
    for (std::size_t k = 0; k < values.size(); ++k) {
      const std::string& name = values[k].first;
      h5::Handle g = h5::createGroup(og.get(), name, c);
      obs_names.push_back(name);
      obs_value.push_back(h5::createExtendible(g.get(), "value", H5T_IEEE_F64LE, {}, OBS_CHUNK,
                                               c + " observable " + name));
      if (k == 0) {
        obs_step = h5::createExtendible(g.get(), "step", H5T_STD_I64LE, {}, OBS_CHUNK,
                                        c + " observable " + name);
        obs_time = h5::createExtendible(g.get(), "time", H5T_IEEE_F64LE, {}, OBS_CHUNK,
                                        c + " observable " + name);
      } else {
        for (const char* what : {"step", "time"}) {
          const std::string src = first + "/" + what;
          h5::checkStatus(
              H5Lcreate_hard(file.get(), src.c_str(), g.get(), what, H5P_DEFAULT, H5P_DEFAULT),
              c + ": cannot link observable " + name + "/" + what);
        }
      }
    }
    buf_values.assign(obs_names.size(), {});
  }

  /// A new observable in a reopened file: its value series gets NaN ("not recorded") for the
  /// obs_written samples before it and shares the step and time series of the others.
  void addObservable(const std::string& name) {
    const std::string c = ctx();
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..")
      throw std::invalid_argument("H5mdWriter: observable name '" + name +
                                  "' is not allowed (empty, '.', or contains '/')");
    writeObservableBuffer();  // the new series starts after every sample buffered so far
    h5::Handle og = h5::check(H5Gopen2(file.get(), H5MD_OBSERVABLES_GROUP, H5P_DEFAULT), c);
    h5::Handle g = h5::createGroup(og.get(), name, c);
    h5::Handle v = h5::createExtendible(g.get(), "value", H5T_IEEE_F64LE, {}, OBS_CHUNK,
                                        c + " observable " + name);
    if (obs_written > 0) {
      const std::vector<double> nan(obs_written, std::numeric_limits<double>::quiet_NaN());
      h5::writeRows(v.get(), 0, obs_written, H5T_NATIVE_DOUBLE, nan.data(),
                    c + " observable " + name);
    }
    const std::string first = std::string(H5MD_OBSERVABLES_GROUP) + "/" + obs_names[0];
    for (const char* what : {"step", "time"}) {
      const std::string src = first + "/" + what;
      h5::checkStatus(
          H5Lcreate_hard(file.get(), src.c_str(), g.get(), what, H5P_DEFAULT, H5P_DEFAULT),
          c + ": cannot link observable " + name + "/" + what);
    }
    obs_names.push_back(name);
    obs_value.push_back(std::move(v));
    buf_values.emplace_back();
  }

  void writeObservableBuffer() {
    if (buf_step.empty()) return;
    const std::string c = ctx() + " observables";
    const hsize_t rows = buf_step.size();
    for (std::size_t k = 0; k < obs_names.size(); ++k)
      h5::writeRows(obs_value[k].get(), obs_written, rows, H5T_NATIVE_DOUBLE, buf_values[k].data(),
                    c + " " + obs_names[k]);
    // step/time last: a sample exists once they are written (as for frames)
    h5::writeRows(obs_step.get(), obs_written, rows, H5T_NATIVE_INT64, buf_step.data(),
                  c + " step");
    h5::writeRows(obs_time.get(), obs_written, rows, H5T_NATIVE_DOUBLE, buf_time.data(),
                  c + " time");
    obs_written += rows;
    buf_step.clear();
    buf_time.clear();
    for (auto& b : buf_values) b.clear();
  }

  /// The file is complete after a flush: make it the state a killed run rolls back to.
  void flushFile() {
    h5::checkStatus(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), ctx() + ": flush failed");
    common::h5journal::commit(file.get());
  }

  std::string xdmfText() const {
    const std::string h5 = xmlEscape(baseName(path));
    const std::string pg = particlePath();
    const std::string F = std::to_string(frames), N = std::to_string(n);
    std::ostringstream x;
    x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
      << "<!-- Written by " << xmlEscape(common::versionString()) << ": particles of " << h5
      << " for ParaView's XDMF Reader (reduced units; positions wrapped into [0, L)). -->\n"
      << "<Xdmf Version=\"2.0\">\n <Domain>\n"
      << "  <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    auto slab = [&](std::size_t f, const std::string& dset, bool vec, const char* num, int prec) {
      std::ostringstream s;
      const std::string inner = vec ? " 3" : "";
      s << "      <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 " << N << inner
        << "\" Type=\"HyperSlab\">\n"
        << "       <DataItem Dimensions=\"3 " << (vec ? 3 : 2) << "\" Format=\"XML\">" << f << " 0"
        << (vec ? " 0" : "") << "  1 1" << (vec ? " 1" : "") << "  1 " << N << inner
        << "</DataItem>\n"
        << "       <DataItem Dimensions=\"" << F << " " << N << inner << "\" NumberType=\"" << num
        << "\" Precision=\"" << prec << "\" Format=\"HDF\">" << h5 << ":" << pg << "/" << dset
        << "/value</DataItem>\n"
        << "      </DataItem>\n";
      return s.str();
    };
    char tbuf[64];
    for (std::size_t f = 0; f < frames; ++f) {
      std::snprintf(tbuf, sizeof tbuf, "%.17g", frame_times[f]);
      x << "   <Grid Name=\"frame" << f << "\" GridType=\"Uniform\">\n"
        << "    <Time Value=\"" << tbuf << "\"/>\n"
        << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << N
        << "\" NodesPerElement=\"1\"/>\n"
        << "    <Geometry GeometryType=\"XYZ\">\n"
        << slab(f, "position", true, "Float", 8) << "    </Geometry>\n";
      if (velocities)
        x << "    <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">\n"
          << slab(f, "velocity", true, "Float", 8) << "    </Attribute>\n";
      x << "    <Attribute Name=\"charge\" AttributeType=\"Scalar\" Center=\"Node\">\n"
        << slab(f, "charge", false, "Float", 8) << "    </Attribute>\n"
        << "    <Attribute Name=\"image\" AttributeType=\"Vector\" Center=\"Node\">\n"
        << slab(f, "image", true, "Int", 4) << "    </Attribute>\n"
        << "   </Grid>\n";
    }
    x << "  </Grid>\n </Domain>\n</Xdmf>\n";
    return x.str();
  }

  /// Rewrites the sidecar atomically (temporary file + rename) so ParaView never sees half of it.
  void writeXdmf() {
    if (xdmf_frames == frames) return;
    const std::string tmp = xdmf_path + ".tmp";
    {
      std::ofstream out(tmp, std::ios::trunc);
      if (!out) throw std::runtime_error("cannot write XDMF sidecar '" + tmp + "'");
      errno = 0;
      out << xdmfText();
      out.close();
      if (!out) {
        const int err = errno;
        std::remove(tmp.c_str());
        throw std::runtime_error("writing the XDMF sidecar '" + tmp + "' failed" +
                                 (err ? ": " + common::writeErrorReason(err) : std::string()));
      }
    }
    if (std::rename(tmp.c_str(), xdmf_path.c_str()) != 0) {
      std::remove(tmp.c_str());
      throw std::runtime_error("cannot rename '" + tmp + "' to '" + xdmf_path + "'");
    }
    xdmf_frames = frames;
  }
};

H5mdWriter::H5mdWriter(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}

H5mdWriter::H5mdWriter(const std::string& path, std::size_t N,
                       const std::vector<std::pair<std::string, std::string>>& parameters,
                       const std::string& config_toml, bool overwrite, bool write_velocities,
                       bool write_forces)
    : m_impl(std::make_unique<Impl>()) {
  if (path.empty()) throw std::invalid_argument("H5mdWriter requires a file name.");
  if (N == 0) throw std::invalid_argument("H5mdWriter requires N >= 1 particles, got N = 0.");
  std::set<std::string> keys;
  for (const auto& kv : parameters) {
    if (kv.first.empty()) throw std::invalid_argument("H5mdWriter: a parameter has an empty name.");
    if (!keys.insert(kv.first).second)
      throw std::invalid_argument("H5mdWriter: parameter '" + kv.first + "' is given twice.");
  }
  common::refuseToOverwrite(path, overwrite);
  h5::silenceErrors();
  Impl& m = *m_impl;
  m.path = path;
  m.xdmf_path = xdmfPathFor(path);
  m.n = N;
  m.velocities = write_velocities;
  m.forces = write_forces;
  const h5::Handle fapl(common::h5journal::fileAccess());
  m.file = h5::check(
      H5Fcreate(path.c_str(), overwrite ? H5F_ACC_TRUNC : H5F_ACC_EXCL, H5P_DEFAULT, fapl.get()),
      "cannot create H5MD file '" + path + "'");
  try {
    m.createLayout(parameters, config_toml);
    m.flushFile();
    m.writeXdmf();
  } catch (...) {
    // Leave nothing half-made behind: a retry must not trip over our own partial file.
    m.file.reset();
    std::remove(path.c_str());
    throw;
  }
}

H5mdWriter H5mdWriter::reopen(const std::string& path, std::size_t N, std::int64_t restart_step,
                              bool write_velocities, bool write_forces) {
  h5::silenceErrors();
  auto impl = std::make_unique<Impl>();
  Impl& m = *impl;
  m.path = path;
  m.xdmf_path = xdmfPathFor(path);
  m.n = N;
  m.velocities = write_velocities;
  m.forces = write_forces;
  // A run killed while it wrote leaves the write unfinished: back to the last complete state
  m.repair_note = common::h5journal::recover(path).summary(path);
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    h5::lastError();
    throw std::invalid_argument("cannot reopen '" + path + "': no such HDF5 file");
  }
  const h5::Handle fapl(common::h5journal::fileAccess());
  m.file = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl.get()),
                     "cannot reopen H5MD file '" + path + "'");
  m.openLayout();
  m.reopened = true;
  m.truncateAfter(restart_step);
  m.flushFile();
  m.writeXdmf();
  return H5mdWriter(std::move(impl));
}

H5mdWriter::~H5mdWriter() {
  if (!m_impl) return;
  try {
    close();
  } catch (...) {
    // destructors must not throw; close() explicitly to see errors
  }
}

H5mdWriter::H5mdWriter(H5mdWriter&&) noexcept = default;
H5mdWriter& H5mdWriter::operator=(H5mdWriter&& o) noexcept {
  if (this != &o) {
    if (m_impl) {
      try {
        close();
      } catch (...) {
      }
    }
    m_impl = std::move(o.m_impl);
  }
  return *this;
}

void H5mdWriter::recordRestart(std::int64_t step, double time, double t_end,
                               const std::string& command, const std::string& version) {
  Impl& m = *m_impl;
  m.requireOpen();
  const std::string ctx = "H5mdWriter ('" + m.path + "'): restart record";
  const hid_t file = m.file.get();
  if (!h5::exists(file, "/granagg/restarts")) h5::createGroup(file, "/granagg/restarts", ctx);
  const h5::Handle all = h5::check(H5Gopen2(file, "/granagg/restarts", H5P_DEFAULT), ctx);
  const std::string name = std::to_string(h5::children(all.get()).size());
  const h5::Handle g = h5::createGroup(all.get(), name, ctx);
  h5::writeAttribute(g.get(), "step", step, ctx);
  h5::writeAttribute(g.get(), "time", time, ctx);
  h5::writeAttribute(g.get(), "t_end", t_end, ctx);
  h5::writeStringAttribute(g.get(), "command", command, ctx);
  h5::writeStringAttribute(g.get(), "version", version, ctx);
  h5::writeStringAttribute(g.get(), "utc", common::utcTimestamp(), ctx);
  m.flushFile();
}

void H5mdWriter::writeFrame(const Frame& f) {
  Impl& m = *m_impl;
  m.requireOpen();
  const std::size_t N = m.n;
  const std::string where = "H5mdWriter ('" + m.path + "', step " + std::to_string(f.step) + "): ";
  if (f.size() != N)
    throw std::invalid_argument(where + "frame has " + std::to_string(f.size()) +
                                " particles, expected " + std::to_string(N));
  auto need = [&](std::size_t size, const char* name) {
    if (size != N)
      throw std::invalid_argument(where + "array " + name + " has " + std::to_string(size) +
                                  " entries, expected " + std::to_string(N));
  };
  need(f.y.size(), "y");
  need(f.z.size(), "z");
  need(f.ix.size(), "ix");
  need(f.iy.size(), "iy");
  need(f.iz.size(), "iz");
  if (m.velocities) {
    need(f.vx.size(), "vx");
    need(f.vy.size(), "vy");
    need(f.vz.size(), "vz");
  }
  if (!f.charge.empty()) need(f.charge.size(), "charge");
  if (m.forces) {
    need(f.force.x.size(), "force.x");
    need(f.force.y.size(), "force.y");
    need(f.force.z.size(), "force.z");
  }
  if (!(f.box > 0.0) || !std::isfinite(f.box))
    throw std::invalid_argument(where + "box edge must be positive and finite, got " +
                                common::formatReal(f.box));
  if (!std::isfinite(f.time)) throw std::invalid_argument(where + "time is not finite");
  if (m.have_last_step && f.step <= m.last_step)
    throw std::invalid_argument(where + "steps must increase, previous frame was at step " +
                                std::to_string(m.last_step));

  std::vector<double> xyz(3 * N);
  std::vector<std::int32_t> img(3 * N);
  const std::vector<double>* coords[3] = {&f.x, &f.y, &f.z};
  const std::vector<std::int32_t>* images[3] = {&f.ix, &f.iy, &f.iz};
  for (std::size_t i = 0; i < N; ++i) {
    for (int d = 0; d < 3; ++d) {
      double x = (*coords[d])[i];
      std::int32_t im = (*images[d])[i];
      if (!wrapCoordinate(x, im, f.box))
        throw std::invalid_argument(where + "particle " + std::to_string(i) + " has position " +
                                    "xyz"[d] + " = " + common::formatReal((*coords[d])[i]) +
                                    " (not finite, or too many box lengths away)");
      xyz[3 * i + d] = x;
      img[3 * i + d] = im;
    }
  }
  const std::string c = m.ctx();
  const hsize_t row = m.frames;
  h5::writeRows(m.pos.get(), row, 1, H5T_NATIVE_DOUBLE, xyz.data(), c + " position");
  if (m.velocities) {
    for (std::size_t i = 0; i < N; ++i) {
      xyz[3 * i] = f.vx[i];
      xyz[3 * i + 1] = f.vy[i];
      xyz[3 * i + 2] = f.vz[i];
    }
    h5::writeRows(m.vel.get(), row, 1, H5T_NATIVE_DOUBLE, xyz.data(), c + " velocity");
  }
  if (m.forces) {
    for (std::size_t i = 0; i < N; ++i) {
      xyz[3 * i] = f.force.x[i];
      xyz[3 * i + 1] = f.force.y[i];
      xyz[3 * i + 2] = f.force.z[i];
    }
    h5::writeRows(m.force.get(), row, 1, H5T_NATIVE_DOUBLE, xyz.data(), c + " force");
  }
  if (f.charge.empty()) {
    const std::vector<double> zeros(N, 0.0);
    h5::writeRows(m.charge.get(), row, 1, H5T_NATIVE_DOUBLE, zeros.data(), c + " charge");
  } else {
    h5::writeRows(m.charge.get(), row, 1, H5T_NATIVE_DOUBLE, f.charge.data(), c + " charge");
  }
  h5::writeRows(m.image.get(), row, 1, H5T_NATIVE_INT32, img.data(), c + " image");
  const double e[9] = {f.box, 0, 0, 0, f.box, 0, 0, 0, f.box};
  h5::writeRows(m.edges.get(), row, 1, H5T_NATIVE_DOUBLE, e, c + " box/edges");
  // step and time last: the frame is complete once they exist
  h5::writeRows(m.step.get(), row, 1, H5T_NATIVE_INT64, &f.step, c + " step");
  h5::writeRows(m.time.get(), row, 1, H5T_NATIVE_DOUBLE, &f.time, c + " time");
  ++m.frames;
  m.frame_times.push_back(f.time);
  m.have_last_step = true;
  m.last_step = f.step;
  m.writeObservableBuffer();
  m.flushFile();
  if (m.frames <= XDMF_EVERY_FRAME_UP_TO || m.frames % XDMF_STRIDE == 0) m.writeXdmf();
}

void H5mdWriter::writeObservables(std::int64_t step, double time,
                                  const std::vector<std::pair<std::string, double>>& values) {
  Impl& m = *m_impl;
  m.requireOpen();
  if (m.obs_names.empty()) m.createObservables(values);
  // A reopened file may lack an observable that this program writes (the run was started by a
  // granagg without it): the series is added, NaN before the restart. One it holds but this
  // program does not write gets NaN from the restart on. A file this writer created keeps the
  // names of its first call.
  if (m.reopened) {
    std::set<std::string> seen;
    for (const auto& kv : values)
      if (!seen.insert(kv.first).second)
        throw std::invalid_argument("H5mdWriter: observable '" + kv.first + "' given twice");
    for (const auto& kv : values)
      if (std::find(m.obs_names.begin(), m.obs_names.end(), kv.first) == m.obs_names.end())
        m.addObservable(kv.first);
  }
  if (!m.reopened && values.size() != m.obs_names.size())
    throw std::invalid_argument("H5mdWriter: writeObservables got " +
                                std::to_string(values.size()) + " values, the first call fixed " +
                                std::to_string(m.obs_names.size()));
  if (m.have_last_obs_step && step <= m.last_obs_step)
    throw std::invalid_argument("H5mdWriter: observable steps must increase (step " +
                                std::to_string(step) + " after " + std::to_string(m.last_obs_step) +
                                ")");
  std::vector<double> row(m.obs_names.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<bool> filled(m.obs_names.size(), false);
  for (const auto& [name, v] : values) {
    std::size_t k = 0;
    while (k < m.obs_names.size() && m.obs_names[k] != name) ++k;
    if (k == m.obs_names.size())
      throw std::invalid_argument("H5mdWriter: unknown observable '" + name +
                                  "' (the first call fixes the names)");
    if (filled[k]) throw std::invalid_argument("H5mdWriter: observable '" + name + "' given twice");
    filled[k] = true;
    row[k] = v;
  }
  m.buf_step.push_back(step);
  m.buf_time.push_back(time);
  for (std::size_t k = 0; k < row.size(); ++k) m.buf_values[k].push_back(row[k]);
  m.have_last_obs_step = true;
  m.last_obs_step = step;
  if (m.buf_step.size() >= OBS_BUFFER_MAX) {
    m.writeObservableBuffer();
    m.flushFile();
  }
}

void H5mdWriter::flush() {
  Impl& m = *m_impl;
  m.requireOpen();
  m.writeObservableBuffer();
  m.flushFile();
  m.writeXdmf();
}

void H5mdWriter::close() {
  if (!m_impl || m_impl->closed) return;
  Impl& m = *m_impl;
  m.closed = true;  // even if what follows throws: never try twice
  std::exception_ptr pending;
  try {
    m.writeObservableBuffer();
    m.writeXdmf();
  } catch (...) {
    pending = std::current_exception();  // still close the file below
  }
  for (h5::Handle* h : {&m.pos, &m.vel, &m.force, &m.charge, &m.image, &m.edges, &m.step, &m.time,
                        &m.obs_step, &m.obs_time})
    h->reset();
  m.obs_value.clear();
  const bool closed_ok = m.file.reset();
  if (pending) std::rethrow_exception(pending);
  if (!closed_ok) h5::fail("H5MD file '" + m.path + "': closing failed (data may be lost)");
}

std::size_t H5mdWriter::frames() const { return m_impl->frames; }
std::size_t H5mdWriter::observableSamples() const {
  return m_impl->obs_written + m_impl->buf_step.size();
}
std::size_t H5mdWriter::size() const { return m_impl->n; }
const std::string& H5mdWriter::repairNote() const { return m_impl->repair_note; }
const std::string& H5mdWriter::path() const { return m_impl->path; }
const std::string& H5mdWriter::xdmfPath() const { return m_impl->xdmf_path; }

std::string H5mdWriter::xdmfPathFor(const std::string& h5_path) {
  for (const char* ext : {".h5", ".hdf5", ".h5md", ".hdf"}) {
    const std::string e(ext);
    if (h5_path.size() > e.size() && h5_path.compare(h5_path.size() - e.size(), e.size(), e) == 0)
      return h5_path.substr(0, h5_path.size() - e.size()) + ".xdmf";
  }
  return h5_path + ".xdmf";
}

}  // namespace granagg::md
