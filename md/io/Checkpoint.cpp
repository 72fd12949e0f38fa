#include "md/io/Checkpoint.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <stdexcept>

#include "common/Csv.h"
#include "common/Hdf5.h"
#include "common/Version.h"

namespace granagg::md {
namespace h5 = common::h5;  // (common/Hdf5.h)

namespace {

constexpr const char* FORMAT_NAME = "granagg-checkpoint";
constexpr std::int64_t FORMAT_VERSION = 1;
constexpr hsize_t CHUNK_MAX = 1 << 16;  // elements per chunk of the checksummed arrays

/// fsync a file or directory by path; false on failure.
bool syncPath(const std::string& p, bool directory) {
  const int fd = ::open(p.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

std::string parentDir(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

/// 1D array dataset of n elements, chunked with the Fletcher-32 checksum filter.
void writeArray(hid_t loc, const std::string& name, hid_t file_type, hid_t mem_type,
                const void* data, std::size_t n, const std::string& ctx) {
  const hsize_t dims[1] = {n};
  h5::Handle space(H5Screate_simple(1, dims, nullptr));
  h5::Handle dcpl = h5::check(H5Pcreate(H5P_DATASET_CREATE), ctx);
  const hsize_t chunk[1] = {std::max<hsize_t>(1, std::min<hsize_t>(n, CHUNK_MAX))};
  h5::checkStatus(H5Pset_chunk(dcpl.get(), 1, chunk), ctx);
  h5::checkStatus(H5Pset_fletcher32(dcpl.get()), ctx);
  h5::Handle d = h5::check(
      H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
      ctx + ": cannot create dataset '" + name + "'");
  h5::checkStatus(H5Dwrite(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
                  ctx + ": cannot write dataset '" + name + "'");
}

void writeU64(hid_t obj, const std::string& name, std::uint64_t v, const std::string& ctx) {
  h5::writeAttribute(obj, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, &v, {}, ctx);
}

void writeFile(const std::string& file_path, const Checkpoint& e) {
  const Frame& s = e.state;
  const std::string c = "checkpoint '" + file_path + "'";
  h5::Handle file = h5::check(H5Fcreate(file_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                              "cannot create " + c);
  const hid_t f = file.get();
  h5::writeFixedStringAttribute(f, "format", FORMAT_NAME, c);
  h5::writeAttribute(f, "format_version", FORMAT_VERSION, c);
  h5::writeStringAttribute(f, "creator", common::versionString(), c);
  const std::size_t n = s.size();
  {
    h5::Handle g = h5::createGroup(f, "state", c);
    h5::writeAttribute(g.get(), "step", static_cast<std::int64_t>(s.step), c);
    h5::writeAttribute(g.get(), "time", s.time, c);
    h5::writeAttribute(g.get(), "box", s.box, c);
    h5::writeAttribute(g.get(), "N", static_cast<std::int64_t>(n), c);
    const std::pair<const char*, const std::vector<double>*> reals[] = {
        {"x", &s.x},   {"y", &s.y},           {"z", &s.z},   {"vx", &s.vx}, {"vy", &s.vy},
        {"vz", &s.vz}, {"charge", &s.charge}, {"fx", &e.forces.x}, {"fy", &e.forces.y},
        {"fz", &e.forces.z}};
    for (const auto& [name, v] : reals)
      writeArray(g.get(), name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v->data(), n, c);
    const std::pair<const char*, const std::vector<std::int32_t>*> ints[] = {
        {"ix", &s.ix}, {"iy", &s.iy}, {"iz", &s.iz}};
    for (const auto& [name, v] : ints)
      writeArray(g.get(), name, H5T_STD_I32LE, H5T_NATIVE_INT32, v->data(), n, c);
  }
  {
    h5::Handle g = h5::createGroup(f, "integrator", c);
    h5::writeAttribute(g.get(), "dt", e.dt, c);
  }
  {
    h5::Handle g = h5::createGroup(f, "run", c);
    writeU64(g.get(), "seed", e.run.seed, c);
    writeU64(g.get(), "frames_written", e.run.frames_written, c);
    writeU64(g.get(), "next_frame_index", e.run.next_frame_index, c);
    h5::writeStringDataset(g.get(), "config_toml", e.run.config_toml, c);
  }
  {
    h5::Handle gi = h5::createGroup(f, "scalars/int", c);
    for (const auto& [k, v] : e.engine.ints)
      h5::writeAttribute(gi.get(), k, static_cast<std::int64_t>(v), c + " /scalars/int");
    h5::Handle gr = h5::createGroup(f, "scalars/real", c);
    for (const auto& [k, v] : e.engine.reals)
      h5::writeAttribute(gr.get(), k, v, c + " /scalars/real");
  }
  if (!e.engine.arrays.empty()) {
    h5::Handle g = h5::createGroup(f, "arrays", c);
    for (const auto& [k, v] : e.engine.arrays)
      writeArray(g.get(), k, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.data(), n, c);
  }
  if (!file.reset()) h5::fail("cannot close " + c + " (disk full?)");
}

void validate(const Checkpoint& e) {
  const Frame& s = e.state;
  const std::size_t n = s.size();
  if (n == 0) throw std::invalid_argument("writeCheckpoint: the state has no particles.");
  auto need = [&](std::size_t size, const char* name) {
    if (size != n)
      throw std::invalid_argument(std::string("writeCheckpoint: array ") + name + " has " +
                                  std::to_string(size) +
                                  " entries, expected N = " + std::to_string(n) + ".");
  };
  need(s.y.size(), "y");
  need(s.z.size(), "z");
  need(s.vx.size(), "vx");
  need(s.vy.size(), "vy");
  need(s.vz.size(), "vz");
  need(s.charge.size(), "charge");
  need(s.ix.size(), "ix");
  need(s.iy.size(), "iy");
  need(s.iz.size(), "iz");
  need(e.forces.x.size(), "fx");
  need(e.forces.y.size(), "fy");
  need(e.forces.z.size(), "fz");
  if (!(s.box > 0.0) || !std::isfinite(s.box))
    throw std::invalid_argument("writeCheckpoint: the box edge must be positive and finite, got " +
                                common::formatReal(s.box) + ".");
  if (!(e.dt > 0.0) || !std::isfinite(e.dt))
    throw std::invalid_argument("writeCheckpoint: dt must be positive and finite, got " +
                                common::formatReal(e.dt) + ".");
  for (const auto& kv : e.engine.ints)
    if (kv.first.empty())
      throw std::invalid_argument("writeCheckpoint: an integer scalar has an empty name.");
  for (const auto& kv : e.engine.reals)
    if (kv.first.empty())
      throw std::invalid_argument("writeCheckpoint: a real scalar has an empty name.");
  for (const auto& kv : e.engine.arrays) {
    if (kv.first.empty() || kv.first.find('/') != std::string::npos)
      throw std::invalid_argument("writeCheckpoint: an array name is empty or contains '/'.");
    need(kv.second.size(), kv.first.c_str());
  }
}

}  // namespace

void writeCheckpoint(const std::string& path, const Checkpoint& checkpoint) {
  if (path.empty()) throw std::invalid_argument("writeCheckpoint requires a file name.");
  validate(checkpoint);
  h5::silenceErrors();
  const std::string tmp = path + ".tmp";
  try {
    writeFile(tmp, checkpoint);
    if (!syncPath(tmp, false))
      throw std::runtime_error("cannot fsync checkpoint '" + tmp + "': " + std::strerror(errno));
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
      throw std::runtime_error("cannot rename checkpoint '" + tmp + "' to '" + path +
                               "': " + std::strerror(errno));
  } catch (...) {
    // Remove a partial temporary file (never a directory or anything else someone put there).
    struct stat st;
    if (::lstat(tmp.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink(tmp.c_str());
    throw;
  }
  syncPath(parentDir(path), true);  // make the rename durable; best effort (some FS refuse)
}

Checkpoint readCheckpoint(const std::string& path) {
  h5::silenceErrors();
  const std::string c = "checkpoint '" + path + "'";
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw std::runtime_error(c + " does not exist");
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    h5::lastError();
    throw std::runtime_error(c + " is not an HDF5 file (corrupt, or not a checkpoint)");
  }
  h5::Handle file = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                              "cannot open " + c + " (truncated or corrupt?)");
  const hid_t f = file.get();
  {
    h5::Handle a = h5::openAttribute(f, "format");
    if (!a || h5::readString(a.get(), true, c + " format") != FORMAT_NAME)
      throw std::runtime_error(c + " is not a granagg checkpoint (no format = \"" +
                               std::string(FORMAT_NAME) + "\")");
    h5::Handle v = h5::openAttribute(f, "format_version");
    if (!v) throw std::runtime_error(c + " has no format_version");
    const auto ver =
        h5::readNumericAttribute<std::int64_t>(v.get(), H5T_NATIVE_INT64, c + " format_version");
    if (ver.size() != 1 || ver[0] != FORMAT_VERSION)
      throw std::runtime_error(c + " has format_version " +
                               (ver.empty() ? std::string("?") : std::to_string(ver[0])) +
                               ", this granagg reads version " + std::to_string(FORMAT_VERSION));
  }
  auto group = [&](const char* name) {
    if (h5::objectType(f, name) != H5I_GROUP)
      throw std::runtime_error(c + " is missing group '/" + std::string(name) + "'");
    return h5::check(H5Gopen2(f, name, H5P_DEFAULT), c + ": cannot open /" + name);
  };
  auto scalar = [&](hid_t g, const std::string& gname, const char* name, hid_t mem_type,
                    void* out) {
    h5::Handle a = h5::openAttribute(g, name);
    if (!a) throw std::runtime_error(c + " is missing attribute '" + gname + "/" + name + "'");
    h5::Handle space = h5::check(H5Aget_space(a.get()), c);
    if (H5Sget_simple_extent_npoints(space.get()) != 1)
      throw std::runtime_error(c + ": attribute '" + gname + "/" + name + "' is not a scalar");
    h5::checkStatus(H5Aread(a.get(), mem_type, out),
                    c + ": cannot read '" + gname + "/" + name + "'");
  };

  Checkpoint cp;
  Frame& s = cp.state;
  Checkpoint& e = cp;
  std::int64_t n = 0;
  {
    h5::Handle g = group("state");
    std::int64_t step = 0;
    scalar(g.get(), "/state", "step", H5T_NATIVE_INT64, &step);
    s.step = step;
    scalar(g.get(), "/state", "time", H5T_NATIVE_DOUBLE, &s.time);
    scalar(g.get(), "/state", "box", H5T_NATIVE_DOUBLE, &s.box);
    scalar(g.get(), "/state", "N", H5T_NATIVE_INT64, &n);
    if (n <= 0)
      throw std::runtime_error(c + ": /state N = " + std::to_string(n) + " is not positive");
    auto array = [&](const char* name, hid_t mem_type, auto& out) {
      const std::string dc = c + ": dataset '/state/" + name + "'";
      if (h5::objectType(g.get(), name) != H5I_DATASET)
        throw std::runtime_error(c + " is missing dataset '/state/" + name + "'");
      h5::Handle d = h5::check(H5Dopen2(g.get(), name, H5P_DEFAULT), dc + ": cannot open");
      const auto dims = h5::datasetDims(d.get(), dc);
      if (dims.size() != 1 || dims[0] != static_cast<hsize_t>(n))
        throw std::runtime_error(
            dc + " has " +
            (dims.size() == 1 ? std::to_string(dims[0]) : std::string("a wrong shape")) +
            " entries, expected N = " + std::to_string(n));
      out.resize(static_cast<std::size_t>(n));
      h5::checkStatus(H5Dread(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
                      dc + ": cannot read (corrupt: checksum mismatch?)");
    };
    array("x", H5T_NATIVE_DOUBLE, s.x);
    array("y", H5T_NATIVE_DOUBLE, s.y);
    array("z", H5T_NATIVE_DOUBLE, s.z);
    array("vx", H5T_NATIVE_DOUBLE, s.vx);
    array("vy", H5T_NATIVE_DOUBLE, s.vy);
    array("vz", H5T_NATIVE_DOUBLE, s.vz);
    array("charge", H5T_NATIVE_DOUBLE, s.charge);
    array("ix", H5T_NATIVE_INT32, s.ix);
    array("iy", H5T_NATIVE_INT32, s.iy);
    array("iz", H5T_NATIVE_INT32, s.iz);
    array("fx", H5T_NATIVE_DOUBLE, e.forces.x);
    array("fy", H5T_NATIVE_DOUBLE, e.forces.y);
    array("fz", H5T_NATIVE_DOUBLE, e.forces.z);
  }
  {
    h5::Handle g = group("integrator");
    scalar(g.get(), "/integrator", "dt", H5T_NATIVE_DOUBLE, &e.dt);
  }
  {
    h5::Handle g = group("run");
    scalar(g.get(), "/run", "seed", H5T_NATIVE_UINT64, &e.run.seed);
    scalar(g.get(), "/run", "frames_written", H5T_NATIVE_UINT64, &e.run.frames_written);
    scalar(g.get(), "/run", "next_frame_index", H5T_NATIVE_UINT64, &e.run.next_frame_index);
    if (h5::objectType(g.get(), "config_toml") != H5I_DATASET)
      throw std::runtime_error(c + " is missing dataset '/run/config_toml'");
    h5::Handle d =
        h5::check(H5Dopen2(g.get(), "config_toml", H5P_DEFAULT), c + ": /run/config_toml");
    e.run.config_toml = h5::readString(d.get(), false, c + ": /run/config_toml");
  }
  {
    h5::Handle gs = group("scalars");
    auto readAll = [&](const char* sub, bool integer) {
      if (h5::objectType(gs.get(), sub) != H5I_GROUP)
        throw std::runtime_error(c + " is missing group '/scalars/" + std::string(sub) + "'");
      h5::Handle g = h5::check(H5Gopen2(gs.get(), sub, H5P_DEFAULT), c);
      const std::vector<std::string> names = h5::attributeNames(g.get(), c + ": /scalars/" + sub);
      const std::string gname = std::string("/scalars/") + sub;
      for (const auto& name : names) {
        if (integer) {
          std::int64_t v = 0;
          scalar(g.get(), gname, name.c_str(), H5T_NATIVE_INT64, &v);
          e.engine.ints[name] = v;
        } else {
          double v = 0;
          scalar(g.get(), gname, name.c_str(), H5T_NATIVE_DOUBLE, &v);
          e.engine.reals[name] = v;
        }
      }
    };
    readAll("int", true);
    readAll("real", false);
  }
  if (h5::objectType(f, "arrays") == H5I_GROUP) {
    h5::Handle g = h5::check(H5Gopen2(f, "arrays", H5P_DEFAULT), c + ": cannot open /arrays");
    for (const auto& name : h5::datasetNames(g.get(), c + ": /arrays")) {
      const std::string dc = c + ": dataset '/arrays/" + name + "'";
      h5::Handle d = h5::check(H5Dopen2(g.get(), name.c_str(), H5P_DEFAULT), dc + ": cannot open");
      const auto dims = h5::datasetDims(d.get(), dc);
      if (dims.size() != 1 || dims[0] != static_cast<hsize_t>(n))
        throw std::runtime_error(dc + " does not hold N = " + std::to_string(n) + " entries");
      std::vector<double>& out = e.engine.arrays[name];
      out.resize(static_cast<std::size_t>(n));
      h5::checkStatus(
          H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
          dc + ": cannot read (corrupt: checksum mismatch?)");
    }
  }
  return cp;
}

}  // namespace granagg::md
