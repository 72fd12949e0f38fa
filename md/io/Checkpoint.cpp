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
#include "common/FaultInjection.h"
#include "common/H5Journal.h"
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
  // Through the journaled driver (common/H5Journal.h) for its handling of a failed write: the file
  // freezes and HDF5 closes it cleanly. With HDF5's own driver a full disk made the close fail,
  // and HDF5 then crashed at exit on the half-closed file. Nothing is committed: a failed
  // checkpoint is a temporary file that is removed.
  h5::Handle fapl(static_cast<hid_t>(common::h5journal::fileAccess()));
  h5::Handle file = h5::check(H5Fcreate(file_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
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
        {"x", &s.x},         {"y", &s.y},        {"z", &s.z},           {"vx", &s.vx},
        {"vy", &s.vy},       {"vz", &s.vz},      {"charge", &s.charge}, {"fx", &e.forces.x},
        {"fy", &e.forces.y}, {"fz", &e.forces.z}};
    for (const auto& [name, v] : reals)
      writeArray(g.get(), name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v->data(), n, c);
    const std::pair<const char*, const std::vector<std::int32_t>*> ints[] = {
        {"ix", &s.ix}, {"iy", &s.iy}, {"iz", &s.iz}};
    for (const auto& [name, v] : ints)
      writeArray(g.get(), name, H5T_STD_I32LE, H5T_NATIVE_INT32, v->data(), n, c);
  }
  // The crash trials' hook (common/FaultInjection.h): half-way, the particles written, the rest
  // not. The temporary file is renamed only once complete, so the previous checkpoint stands.
  if (common::faultPoint("checkpoint"))
    throw std::runtime_error("cannot write " + c + ": " + std::strerror(ENOSPC) +
                             " (fault injected)");
  {
    h5::Handle g = h5::createGroup(f, "integrator", c);
    h5::writeAttribute(g.get(), "dt", e.dt, c);
  }
  {
    h5::Handle g = h5::createGroup(f, "run", c);
    writeU64(g.get(), "seed", e.run.seed, c);
    writeU64(g.get(), "frames_written", e.run.frames_written, c);
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
  // HDF5 does not report every failed write to its caller; the driver remembers the first
  common::h5journal::requireWritten(f);  // "writing '...checkpoint.h5.tmp' failed: the disk ..."
  if (!file.reset()) h5::fail("cannot close " + c);
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

namespace {

/// An open checkpoint file and the readers of its parts, whose errors name the file and the
/// object (`c`, "checkpoint '<path>'").
struct CheckpointFile {
  std::string c;
  h5::Handle file;

  /// Opens `path` and checks that it is a granagg checkpoint of this format version.
  explicit CheckpointFile(const std::string& path) : c("checkpoint '" + path + "'") {
    h5::silenceErrors();
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throw std::runtime_error(c + " does not exist");
    if (H5Fis_hdf5(path.c_str()) <= 0) {
      h5::lastError();
      throw std::runtime_error(c + " is not an HDF5 file (corrupt, or not a checkpoint)");
    }
    file = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                     "cannot open " + c + " (truncated or corrupt?)");
    h5::Handle a = h5::openAttribute(file.get(), "format");
    if (!a || h5::readString(a.get(), true, c + " format") != FORMAT_NAME)
      throw std::runtime_error(c + " is not a granagg checkpoint (no format = \"" +
                               std::string(FORMAT_NAME) + "\")");
    h5::Handle v = h5::openAttribute(file.get(), "format_version");
    if (!v) throw std::runtime_error(c + " has no format_version");
    const auto ver =
        h5::readNumericAttribute<std::int64_t>(v.get(), H5T_NATIVE_INT64, c + " format_version");
    if (ver.size() != 1 || ver[0] != FORMAT_VERSION)
      throw std::runtime_error(c + " has format_version " +
                               (ver.empty() ? std::string("?") : std::to_string(ver[0])) +
                               ", this granagg reads version " + std::to_string(FORMAT_VERSION));
  }

  h5::Handle group(hid_t parent, const std::string& gname, const char* name) const {
    if (h5::objectType(parent, name) != H5I_GROUP)
      throw std::runtime_error(c + " is missing group '" + gname + "/" + name + "'");
    return h5::check(H5Gopen2(parent, name, H5P_DEFAULT),
                     c + ": cannot open " + gname + "/" + name);
  }
  h5::Handle group(const char* name) const { return group(file.get(), "", name); }

  /// A scalar attribute `gname/name` of group g into `out` (of HDF5 memory type mem_type).
  void scalar(hid_t g, const std::string& gname, const char* name, hid_t mem_type,
              void* out) const {
    h5::Handle a = h5::openAttribute(g, name);
    if (!a) throw std::runtime_error(c + " is missing attribute '" + gname + "/" + name + "'");
    h5::Handle space = h5::check(H5Aget_space(a.get()), c);
    if (H5Sget_simple_extent_npoints(space.get()) != 1)
      throw std::runtime_error(c + ": attribute '" + gname + "/" + name + "' is not a scalar");
    h5::checkStatus(H5Aread(a.get(), mem_type, out),
                    c + ": cannot read '" + gname + "/" + name + "'");
  }

  /// The per-particle dataset `gname/name` of group g (n entries) into `out`.
  template <class T>
  void array(hid_t g, const std::string& gname, const std::string& name, hid_t mem_type,
             std::int64_t n, std::vector<T>& out) const {
    const std::string dc = c + ": dataset '" + gname + "/" + name + "'";
    if (h5::objectType(g, name.c_str()) != H5I_DATASET)
      throw std::runtime_error(c + " is missing dataset '" + gname + "/" + name + "'");
    h5::Handle d = h5::check(H5Dopen2(g, name.c_str(), H5P_DEFAULT), dc + ": cannot open");
    const auto dims = h5::datasetDims(d.get(), dc);
    if (dims.size() != 1 || dims[0] != static_cast<hsize_t>(n))
      throw std::runtime_error(
          dc + " has " +
          (dims.size() == 1 ? std::to_string(dims[0]) : std::string("a wrong shape")) +
          " entries, expected N = " + std::to_string(n));
    h5::checkStoredSize(d.get(), dc);  // N comes from the file: refuse a claim it does not back
    out.resize(static_cast<std::size_t>(n));
    h5::checkStatus(H5Dread(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
                    dc + ": cannot read (corrupt: checksum mismatch?)");
  }

  /// /state: the particles and the forces; returns N.
  std::int64_t readState(Checkpoint& cp) const {
    Frame& s = cp.state;
    h5::Handle g = group("state");
    std::int64_t step = 0, n = 0;
    scalar(g.get(), "/state", "step", H5T_NATIVE_INT64, &step);
    s.step = step;
    scalar(g.get(), "/state", "time", H5T_NATIVE_DOUBLE, &s.time);
    scalar(g.get(), "/state", "box", H5T_NATIVE_DOUBLE, &s.box);
    scalar(g.get(), "/state", "N", H5T_NATIVE_INT64, &n);
    if (n <= 0)
      throw std::runtime_error(c + ": /state N = " + std::to_string(n) + " is not positive");
    const hid_t d = H5T_NATIVE_DOUBLE, i32 = H5T_NATIVE_INT32;
    for (auto [name, out] : {std::pair{"x", &s.x},
                             {"y", &s.y},
                             {"z", &s.z},
                             {"vx", &s.vx},
                             {"vy", &s.vy},
                             {"vz", &s.vz},
                             {"charge", &s.charge}})
      array(g.get(), "/state", name, d, n, *out);
    for (auto [name, out] : {std::pair{"ix", &s.ix}, {"iy", &s.iy}, {"iz", &s.iz}})
      array(g.get(), "/state", name, i32, n, *out);
    for (auto [name, out] :
         {std::pair{"fx", &cp.forces.x}, {"fy", &cp.forces.y}, {"fz", &cp.forces.z}})
      array(g.get(), "/state", name, d, n, *out);
    return n;
  }

  /// /integrator and /run: the time step, the seed, the frame counters and the configuration.
  void readRun(Checkpoint& cp) const {
    {
      h5::Handle g = group("integrator");
      scalar(g.get(), "/integrator", "dt", H5T_NATIVE_DOUBLE, &cp.dt);
    }
    h5::Handle g = group("run");
    scalar(g.get(), "/run", "seed", H5T_NATIVE_UINT64, &cp.run.seed);
    scalar(g.get(), "/run", "frames_written", H5T_NATIVE_UINT64, &cp.run.frames_written);
    if (h5::objectType(g.get(), "config_toml") != H5I_DATASET)
      throw std::runtime_error(c + " is missing dataset '/run/config_toml'");
    h5::Handle d =
        h5::check(H5Dopen2(g.get(), "config_toml", H5P_DEFAULT), c + ": /run/config_toml");
    cp.run.config_toml = h5::readString(d.get(), false, c + ": /run/config_toml");
  }

  /// /scalars/int and /scalars/real: the engine's named scalars.
  void readScalars(Checkpoint& cp) const {
    h5::Handle gs = group("scalars");
    for (const bool integer : {true, false}) {
      const char* sub = integer ? "int" : "real";
      h5::Handle g = group(gs.get(), "/scalars", sub);
      const std::string gname = std::string("/scalars/") + sub;
      for (const auto& name : h5::attributeNames(g.get(), c + ": " + gname)) {
        if (integer) {
          std::int64_t v = 0;
          scalar(g.get(), gname, name.c_str(), H5T_NATIVE_INT64, &v);
          cp.engine.ints[name] = v;
        } else {
          double v = 0;
          scalar(g.get(), gname, name.c_str(), H5T_NATIVE_DOUBLE, &v);
          cp.engine.reals[name] = v;
        }
      }
    }
  }

  /// /arrays (optional): the engine's named per-particle arrays, N entries each.
  void readArrays(Checkpoint& cp, std::int64_t n) const {
    if (h5::objectType(file.get(), "arrays") != H5I_GROUP) return;
    h5::Handle g = group("arrays");
    for (const auto& name : h5::datasetNames(g.get(), c + ": /arrays"))
      array(g.get(), "/arrays", name, H5T_NATIVE_DOUBLE, n, cp.engine.arrays[name]);
  }
};

}  // namespace

Checkpoint readCheckpoint(const std::string& path) {
  const CheckpointFile file(path);
  Checkpoint cp;
  const std::int64_t n = file.readState(cp);
  file.readRun(cp);
  file.readScalars(cp);
  file.readArrays(cp, n);
  return cp;
}

}  // namespace granagg::md
