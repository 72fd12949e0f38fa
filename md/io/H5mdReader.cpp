#include "md/io/H5mdReader.h"

#include <sys/stat.h>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/Csv.h"
#include "common/Hdf5.h"
#include "md/io/H5mdWriter.h"
#include "md/io/InitialState.h"

namespace granagg::md {
namespace h5 = common::h5;  // (common/Hdf5.h)

namespace {

std::string shapeText(const std::vector<hsize_t>& d) {
  std::string s = "[";
  for (std::size_t k = 0; k < d.size(); ++k) s += (k ? "," : "") + std::to_string(d[k]);
  return s + "]";
}

/// One H5MD element of the particle group: a time-dependent group {value, step, time} or a
/// fixed dataset.
struct Element {
  std::string name;  // path below the particle group, e.g. "velocity"
  bool present = false;
  bool time_dependent = false;
  h5::Handle value;
  std::vector<hsize_t> dims;
  std::vector<std::int64_t> steps;  // time-dependent only, one per row
  std::vector<double> times;
};

}  // namespace

struct H5mdReader::Impl {
  h5::Handle file;  // first: closed last
  std::string path, group;
  std::size_t n = 0, frames = 0;
  Element pos, vel, charge, image, edges;

  std::string ctx() const { return "H5MD file '" + path + "'"; }
  std::string where(const Element& e) const { return "particles/" + group + "/" + e.name; }

  [[noreturn]] void error(const std::string& what) const {
    throw std::runtime_error(ctx() + ": " + what);
  }

  /// Reads a step or time dataset of `rows` samples, either an array or the H5MD fixed-increment
  /// form (scalar increment with an optional `offset` attribute).
  template <class T>
  std::vector<T> readGrid(hid_t grp, const std::string& name, hid_t mem_type, std::size_t rows,
                          const std::string& elem) const {
    const std::string c = ctx() + ": " + elem + "/" + name;
    if (h5::objectType(grp, name) != H5I_DATASET) error("missing dataset " + elem + "/" + name);
    h5::Handle d = h5::check(H5Dopen2(grp, name.c_str(), H5P_DEFAULT), c + ": cannot open");
    const auto dims = h5::datasetDims(d.get(), c);
    if (dims.empty()) {
      const auto inc = h5::readAll<T>(d.get(), mem_type, c);
      T offset = 0;
      h5::Handle a = h5::openAttribute(d.get(), "offset");
      if (a) {
        const auto o = h5::readNumericAttribute<T>(a.get(), mem_type, c + " offset");
        if (!o.empty()) offset = o[0];
      }
      std::vector<T> out(rows);
      for (std::size_t k = 0; k < rows; ++k) out[k] = offset + static_cast<T>(k) * inc.at(0);
      return out;
    }
    if (dims.size() != 1)
      error(elem + "/" + name + " has shape " + shapeText(dims) +
            ", expected one value per sample");
    return h5::readAll<T>(d.get(), mem_type, c);
  }

  /// Opens element `name`; `required` makes its absence an error.
  Element openElement(hid_t part, const std::string& name, bool required) const {
    Element e;
    e.name = name;
    const H5I_type_t t = h5::objectType(part, name);
    if (t == H5I_BADID) {
      if (required) error("missing " + where(e) + " (required by H5MD)");
      return e;
    }
    e.present = true;
    const std::string c = ctx() + ": " + where(e);
    if (t == H5I_DATASET) {
      e.value = h5::check(H5Dopen2(part, name.c_str(), H5P_DEFAULT), c + ": cannot open");
      e.dims = h5::datasetDims(e.value.get(), c);
      return e;
    }
    if (t != H5I_GROUP) error(where(e) + " is neither a group nor a dataset");
    e.time_dependent = true;
    h5::Handle g = h5::check(H5Gopen2(part, name.c_str(), H5P_DEFAULT), c + ": cannot open");
    if (h5::objectType(g.get(), "value") != H5I_DATASET)
      error("missing dataset " + where(e) + "/value");
    e.value = h5::check(H5Dopen2(g.get(), "value", H5P_DEFAULT), c + "/value: cannot open");
    e.dims = h5::datasetDims(e.value.get(), c + "/value");
    if (e.dims.empty()) error(where(e) + "/value is a scalar, expected a time series");
    e.steps = readGrid<std::int64_t>(g.get(), "step", H5T_NATIVE_INT64, e.dims[0], where(e));
    if (h5::exists(g.get(), "time"))
      e.times = readGrid<double>(g.get(), "time", H5T_NATIVE_DOUBLE, e.dims[0], where(e));
    else if (required)
      error("missing dataset " + where(e) + "/time");
    return e;
  }

  /// Checks value dims: time-dependent [rows][inner...] or fixed [inner...].
  void checkShape(const Element& e, const std::vector<hsize_t>& inner,
                  const std::string& expected) const {
    if (!e.present) return;
    std::vector<hsize_t> got = e.dims;
    std::string suffix = e.time_dependent ? "/value" : "";
    if (e.time_dependent) {
      if (got.empty()) error(where(e) + suffix + " is empty");
      got.erase(got.begin());
    }
    if (got != inner)
      error(where(e) + suffix + " has shape " + shapeText(e.dims) + ", expected " +
            (e.time_dependent ? "[frames," : "[") + expected + "]");
  }

  /// Row of element e holding frame i of position (same index when the grids agree, else by step).
  hsize_t rowFor(const Element& e, std::size_t i) const {
    const std::int64_t s = pos.steps[i];
    const std::size_t rows = std::min<std::size_t>(e.dims[0], e.steps.size());
    if (i < rows && e.steps[i] == s) return i;
    auto it =
        std::lower_bound(e.steps.begin(), e.steps.begin() + static_cast<std::ptrdiff_t>(rows), s);
    if (it == e.steps.begin() + static_cast<std::ptrdiff_t>(rows) || *it != s) {
      it = std::find(e.steps.begin(), e.steps.begin() + static_cast<std::ptrdiff_t>(rows),
                     s);  // unsorted steps
      if (it == e.steps.begin() + static_cast<std::ptrdiff_t>(rows))
        error(where(e) + " has no sample at step " + std::to_string(s) + " (frame " +
              std::to_string(i) + ")");
    }
    return static_cast<hsize_t>(it - e.steps.begin());
  }

  /// Reads the data of element e for frame i into out (count values of mem_type).
  void readElement(const Element& e, std::size_t i, hid_t mem_type, void* out) const {
    const std::string c = ctx() + " frame " + std::to_string(i) + ": " + where(e) +
                          (e.time_dependent ? "/value" : "");
    if (e.time_dependent) {
      h5::readRows(e.value.get(), rowFor(e, i), 1, mem_type, out, c);
    } else {
      h5::checkStatus(H5Dread(e.value.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out),
                      c + ": cannot read");
    }
  }

  double boxEdge(std::size_t i) const {
    const bool matrix = edges.dims.size() == (edges.time_dependent ? 3u : 2u);
    double e[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    readElement(edges, i, H5T_NATIVE_DOUBLE, e);
    double L[3];
    if (matrix) {
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          if (a != b && e[3 * a + b] != 0.0)
            error("frame " + std::to_string(i) + ": the box is triclinic (" + where(edges) +
                  " has off-diagonal entries); only cubic boxes are supported");
      for (int a = 0; a < 3; ++a) L[a] = e[4 * a];
    } else {
      for (int a = 0; a < 3; ++a) L[a] = e[a];
    }
    for (double l : L)
      if (!(l > 0.0) || !std::isfinite(l))
        error("frame " + std::to_string(i) + ": box edge " + common::formatReal(l) + " in " +
              where(edges) + " is not positive and finite");
    // Cubic up to the rounding of single-precision writers.
    if (std::fabs(L[1] - L[0]) > 1e-6 * L[0] || std::fabs(L[2] - L[0]) > 1e-6 * L[0])
      error("frame " + std::to_string(i) + ": the box is not cubic (" + common::formatReal(L[0]) +
            ", " + common::formatReal(L[1]) + ", " + common::formatReal(L[2]) +
            "); only cubic boxes are supported");
    return L[0];
  }

  void requireFrame(std::size_t i) const {
    if (i >= frames)
      error("frame " + std::to_string(i) + " requested, the file has " + std::to_string(frames) +
            " complete frames");
  }
};

H5mdReader::H5mdReader(const std::string& path, const std::string& particle_group)
    : m_impl(std::make_unique<Impl>()) {
  Impl& m = *m_impl;
  m.path = path;
  h5::silenceErrors();
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    throw std::runtime_error("H5MD file '" + path + "' does not exist");
  const htri_t is_h5 = H5Fis_hdf5(path.c_str());
  if (is_h5 <= 0) {
    h5::lastError();
    throw std::runtime_error("'" + path + "' is not an HDF5 file (so not an H5MD trajectory)");
  }
  m.file = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                     "cannot open H5MD file '" + path + "' (truncated or corrupt?)");
  const hid_t f = m.file.get();
  if (h5::objectType(f, "/h5md") != H5I_GROUP) m.error("no /h5md group (not an H5MD file)");
  {
    h5::Handle g = h5::check(H5Gopen2(f, "/h5md", H5P_DEFAULT), m.ctx() + ": /h5md");
    h5::Handle a = h5::openAttribute(g.get(), "version");
    if (!a) m.error("/h5md has no 'version' attribute");
    const auto v = h5::readNumericAttribute<std::int64_t>(a.get(), H5T_NATIVE_INT64,
                                                          m.ctx() + ": /h5md version");
    if (v.size() != 2 || v[0] != 1)
      m.error("unsupported H5MD version (expected 1.x, /h5md version has " +
              std::to_string(v.size()) + " entries, first " +
              (v.empty() ? std::string("?") : std::to_string(v[0])) + ")");
  }
  if (h5::objectType(f, "/particles") != H5I_GROUP) m.error("no /particles group");
  h5::Handle particles =
      h5::check(H5Gopen2(f, "/particles", H5P_DEFAULT), m.ctx() + ": /particles");
  const auto groups = h5::children(particles.get());
  if (particle_group.empty()) {
    if (groups.empty()) m.error("/particles holds no particle group");
    m.group = groups.front();
  } else {
    m.group = particle_group;
    if (std::find(groups.begin(), groups.end(), particle_group) == groups.end()) {
      std::string list;
      for (const auto& g : groups) list += (list.empty() ? "" : ", ") + g;
      m.error("no particle group '/particles/" + particle_group +
              "' (available: " + (list.empty() ? "none" : list) + ")");
    }
  }
  h5::Handle part = h5::check(H5Gopen2(particles.get(), m.group.c_str(), H5P_DEFAULT),
                              m.ctx() + ": cannot open /particles/" + m.group);
  const hid_t p = part.get();

  m.pos = m.openElement(p, "position", true);
  if (!m.pos.time_dependent)
    m.error(m.where(m.pos) + " must be a time-dependent group {value, step, time}");
  if (m.pos.dims.size() != 3 || m.pos.dims[2] != 3)
    m.error(m.where(m.pos) + "/value has shape " + shapeText(m.pos.dims) +
            ", expected [frames,N,3]");
  m.n = m.pos.dims[1];
  m.frames = std::min<std::size_t>(
      {static_cast<std::size_t>(m.pos.dims[0]), m.pos.steps.size(), m.pos.times.size()});

  // box: attributes dimension and boundary, element edges
  if (h5::objectType(p, "box") != H5I_GROUP)
    m.error("missing group particles/" + m.group + "/box (required by H5MD)");
  {
    h5::Handle box = h5::check(H5Gopen2(p, "box", H5P_DEFAULT), m.ctx() + ": box");
    const std::string bc = m.ctx() + ": particles/" + m.group + "/box";
    h5::Handle dim = h5::openAttribute(box.get(), "dimension");
    if (!dim) m.error("particles/" + m.group + "/box has no 'dimension' attribute");
    const auto d =
        h5::readNumericAttribute<std::int64_t>(dim.get(), H5T_NATIVE_INT64, bc + " dimension");
    if (d.size() != 1 || d[0] != 3)
      m.error("particles/" + m.group + "/box dimension is " +
              (d.empty() ? std::string("empty") : std::to_string(d[0])) + ", only 3 is supported");
    h5::Handle bnd = h5::openAttribute(box.get(), "boundary");
    if (!bnd) m.error("particles/" + m.group + "/box has no 'boundary' attribute");
    const auto b = h5::readStringArrayAttribute(bnd.get(), bc + " boundary");
    if (b.size() != 3)
      m.error("particles/" + m.group + "/box boundary has " + std::to_string(b.size()) +
              " entries, expected 3");
    for (const auto& s : b)
      if (s != "periodic")
        m.error("particles/" + m.group + "/box boundary is '" + s +
                "'; only periodic boxes are supported");
    m.edges = m.openElement(box.get(), "edges", true);
    m.edges.name = "box/edges";
    const std::size_t rank = m.edges.dims.size() - (m.edges.time_dependent ? 1 : 0);
    const std::vector<hsize_t> inner(m.edges.dims.end() - static_cast<std::ptrdiff_t>(rank),
                                     m.edges.dims.end());
    if (!(inner == std::vector<hsize_t>{3} || inner == std::vector<hsize_t>{3, 3}))
      m.error(m.where(m.edges) + " has shape " + shapeText(m.edges.dims) +
              ", expected [3] or [3,3] per frame");
  }

  const hsize_t N = m.n;
  m.vel = m.openElement(p, "velocity", false);
  m.checkShape(m.vel, {N, 3}, "N=" + std::to_string(N) + ",3");
  m.charge = m.openElement(p, "charge", false);
  m.checkShape(m.charge, {N}, "N=" + std::to_string(N));
  m.image = m.openElement(p, "image", false);
  m.checkShape(m.image, {N, 3}, "N=" + std::to_string(N) + ",3");
}

H5mdReader::~H5mdReader() = default;
H5mdReader::H5mdReader(H5mdReader&&) noexcept = default;
H5mdReader& H5mdReader::operator=(H5mdReader&&) noexcept = default;

const std::string& H5mdReader::path() const { return m_impl->path; }
const std::string& H5mdReader::particleGroup() const { return m_impl->group; }
std::size_t H5mdReader::size() const { return m_impl->n; }
std::size_t H5mdReader::frames() const { return m_impl->frames; }
bool H5mdReader::hasVelocity() const { return m_impl->vel.present; }
bool H5mdReader::hasCharge() const { return m_impl->charge.present; }
bool H5mdReader::hasImage() const { return m_impl->image.present; }

std::int64_t H5mdReader::step(std::size_t i) const {
  m_impl->requireFrame(i);
  return m_impl->pos.steps[i];
}

double H5mdReader::time(std::size_t i) const {
  m_impl->requireFrame(i);
  return m_impl->pos.times[i];
}

double H5mdReader::box(std::size_t i) const {
  m_impl->requireFrame(i);
  return m_impl->boxEdge(i);
}

Frame H5mdReader::readFrame(std::size_t i) const {
  const Impl& m = *m_impl;
  m.requireFrame(i);
  const std::size_t N = m.n;
  Frame f;
  f.step = m.pos.steps[i];
  f.time = m.pos.times[i];
  f.box = m.boxEdge(i);
  std::vector<double> buf(3 * N);
  auto split = [&](std::vector<double>& a, std::vector<double>& b, std::vector<double>& c) {
    a.resize(N);
    b.resize(N);
    c.resize(N);
    for (std::size_t k = 0; k < N; ++k) {
      a[k] = buf[3 * k];
      b[k] = buf[3 * k + 1];
      c[k] = buf[3 * k + 2];
    }
  };
  m.readElement(m.pos, i, H5T_NATIVE_DOUBLE, buf.data());
  split(f.x, f.y, f.z);
  if (m.vel.present) {
    m.readElement(m.vel, i, H5T_NATIVE_DOUBLE, buf.data());
    split(f.vx, f.vy, f.vz);
  }
  f.charge.assign(N, 0.0);
  if (m.charge.present) m.readElement(m.charge, i, H5T_NATIVE_DOUBLE, f.charge.data());
  f.ix.assign(N, 0);
  f.iy.assign(N, 0);
  f.iz.assign(N, 0);
  if (m.image.present) {
    std::vector<std::int32_t> ib(3 * N);
    m.readElement(m.image, i, H5T_NATIVE_INT32, ib.data());
    for (std::size_t k = 0; k < N; ++k) {
      f.ix[k] = ib[3 * k];
      f.iy[k] = ib[3 * k + 1];
      f.iz[k] = ib[3 * k + 2];
    }
  }
  try {
    wrapIntoBox(f);
  } catch (const std::invalid_argument& e) {
    m.error("frame " + std::to_string(i) + ": " + e.what());
  }
  return f;
}

std::vector<std::pair<std::string, std::string>> H5mdReader::parameters() const {
  const Impl& m = *m_impl;
  std::vector<std::pair<std::string, std::string>> out;
  if (h5::objectType(m.file.get(), "/parameters") != H5I_GROUP) return out;
  h5::Handle g =
      h5::check(H5Gopen2(m.file.get(), "/parameters", H5P_DEFAULT), m.ctx() + ": /parameters");
  const std::vector<std::string> names = h5::attributeNames(g.get(), m.ctx() + ": /parameters");
  for (const auto& name : names) {
    const std::string c = m.ctx() + ": /parameters attribute '" + name + "'";
    h5::Handle a = h5::check(H5Aopen(g.get(), name.c_str(), H5P_DEFAULT), c);
    h5::Handle t = h5::check(H5Aget_type(a.get()), c);
    const H5T_class_t cls = H5Tget_class(t.get());
    std::string text;
    if (cls == H5T_STRING) {
      const auto v = h5::readStringArrayAttribute(a.get(), c);
      for (std::size_t k = 0; k < v.size(); ++k) text += (k ? "," : "") + v[k];
    } else if (cls == H5T_INTEGER) {
      const auto v = h5::readNumericAttribute<std::int64_t>(a.get(), H5T_NATIVE_INT64, c);
      for (std::size_t k = 0; k < v.size(); ++k) text += (k ? "," : "") + std::to_string(v[k]);
    } else if (cls == H5T_FLOAT) {
      const auto v = h5::readNumericAttribute<double>(a.get(), H5T_NATIVE_DOUBLE, c);
      for (std::size_t k = 0; k < v.size(); ++k) text += (k ? "," : "") + common::formatReal(v[k]);
    } else {
      continue;  // compound or other exotic types: not a parameter we can show as text
    }
    out.emplace_back(name, text);
  }
  return out;
}

std::string H5mdReader::configToml() const {
  const Impl& m = *m_impl;
  const std::string p = std::string("/parameters/") + H5MD_CONFIG_DATASET;
  if (h5::objectType(m.file.get(), p) != H5I_DATASET) return "";
  h5::Handle d = h5::check(H5Dopen2(m.file.get(), p.c_str(), H5P_DEFAULT), m.ctx() + ": " + p);
  return h5::readString(d.get(), false, m.ctx() + ": " + p);
}

std::pair<std::string, std::string> H5mdReader::creator() const {
  const Impl& m = *m_impl;
  std::pair<std::string, std::string> out;
  if (h5::objectType(m.file.get(), "/h5md/creator") != H5I_GROUP) return out;
  h5::Handle g =
      h5::check(H5Gopen2(m.file.get(), "/h5md/creator", H5P_DEFAULT), m.ctx() + ": /h5md/creator");
  if (h5::Handle a = h5::openAttribute(g.get(), "name"))
    out.first = h5::readString(a.get(), true, m.ctx() + ": creator name");
  if (h5::Handle a = h5::openAttribute(g.get(), "version"))
    out.second = h5::readString(a.get(), true, m.ctx() + ": creator version");
  return out;
}

namespace {
const char* OBSERVABLE_ROOTS[] = {H5MD_OBSERVABLES_GROUP, "/observables"};
}

std::vector<std::string> H5mdReader::observableNames() const {
  const Impl& m = *m_impl;
  std::vector<std::string> out;
  for (const char* root : OBSERVABLE_ROOTS) {
    if (h5::objectType(m.file.get(), root) != H5I_GROUP) continue;
    h5::Handle g = h5::check(H5Gopen2(m.file.get(), root, H5P_DEFAULT), m.ctx() + ": " + root);
    for (const auto& name : h5::children(g.get())) {
      if (h5::objectType(g.get(), name + "/value") != H5I_DATASET) continue;
      if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
    }
  }
  return out;
}

ObservableSeries H5mdReader::readObservable(const std::string& name) const {
  const Impl& m = *m_impl;
  for (const char* root : OBSERVABLE_ROOTS) {
    const std::string base = std::string(root) + "/" + name;
    if (name.empty() || h5::objectType(m.file.get(), base + "/value") != H5I_DATASET) continue;
    h5::Handle g =
        h5::check(H5Gopen2(m.file.get(), base.c_str(), H5P_DEFAULT), m.ctx() + ": " + base);
    h5::Handle v =
        h5::check(H5Dopen2(g.get(), "value", H5P_DEFAULT), m.ctx() + ": " + base + "/value");
    const auto dims = h5::datasetDims(v.get(), m.ctx() + ": " + base + "/value");
    if (dims.size() != 1)
      m.error(base + "/value has shape " + shapeText(dims) +
              ", expected a scalar time series [samples]");
    ObservableSeries s;
    s.name = name;
    s.value = h5::readAll<double>(v.get(), H5T_NATIVE_DOUBLE, m.ctx() + ": " + base + "/value");
    s.step = m.readGrid<std::int64_t>(g.get(), "step", H5T_NATIVE_INT64, s.value.size(), base);
    s.time = m.readGrid<double>(g.get(), "time", H5T_NATIVE_DOUBLE, s.value.size(), base);
    // complete samples only (step/time are written last)
    const std::size_t rows = std::min({s.value.size(), s.step.size(), s.time.size()});
    s.value.resize(rows);
    s.step.resize(rows);
    s.time.resize(rows);
    return s;
  }
  m.error("no observable named '" + name + "'");
}

}  // namespace granagg::md
