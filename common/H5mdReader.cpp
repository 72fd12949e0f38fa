#include "common/H5mdReader.h"

#include <sys/stat.h>
#include <algorithm>
#include <type_traits>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "common/Box.h"
#include "common/Csv.h"
#include "common/H5Journal.h"
#include "common/Hdf5.h"

namespace granagg::common {

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
  bool present = false, time_dependent = false;
  h5::Handle value;
  std::vector<hsize_t> dims;                              // of value
  std::vector<std::int64_t> steps;                        // time-dependent only, one per row
  bool same_rows = true;                                  // row k belongs to frame k
  std::unordered_map<std::int64_t, hsize_t> row_of_step;  // when it does not
};

}  // namespace

struct H5mdReader::Impl {
  h5::Handle file;  // declared first: closed last
  std::string path, group;
  std::size_t n = 0, frames = 0;
  bool keep_crossings = false;  // keepWrapCrossings()
  Element pos, vel, charge, image, edges;
  std::vector<std::int64_t> steps;  // of position
  std::vector<double> times;

  [[noreturn]] void error(std::size_t frame, const std::string& what) const {
    throw TrajectoryError(path, frame, what);
  }
  std::string where(const Element& e) const { return "particles/" + group + "/" + e.name; }
  std::string ctx(const std::string& object) const { return "'" + path + "' " + object; }

  /// Reads a step or time dataset of `rows` samples: an array, or the H5MD fixed-increment form
  /// (scalar increment, optional `offset` attribute).
  template <class T>
  std::vector<T> readGrid(hid_t grp, const std::string& name, hid_t mem_type, std::size_t rows,
                          const std::string& elem) const {
    const std::string c = ctx(elem + "/" + name);
    if (h5::objectType(grp, name) != H5I_DATASET) error(0, "missing dataset " + elem + "/" + name);
    h5::Handle d = h5::check(H5Dopen2(grp, name.c_str(), H5P_DEFAULT), c);
    const auto dims = h5::datasetDims(d.get(), c);
    if (dims.empty()) {
      const auto inc = h5::readAll<T>(d.get(), mem_type, c);
      T offset = 0;
      if (h5::Handle a = h5::openAttribute(d.get(), "offset")) {
        const auto o = h5::readNumericAttribute<T>(a.get(), mem_type, c + " offset");
        if (!o.empty()) offset = o[0];
      }
      if (inc.empty()) error(0, elem + "/" + name + " holds no increment");
      std::vector<T> out(rows);
      for (std::size_t k = 0; k < rows; ++k) {
        if constexpr (std::is_integral_v<T>) {
          // steps from a file: offset + k * increment must not overflow (undefined behaviour)
          T kinc = 0;
          if (__builtin_mul_overflow(static_cast<T>(k), inc[0], &kinc) ||
              __builtin_add_overflow(offset, kinc, &out[k]))
            error(0, elem + "/" + name + ": offset " + std::to_string(offset) + " + " +
                         std::to_string(k) + " x increment " + std::to_string(inc[0]) +
                         " overflows a 64-bit integer");
        } else {
          out[k] = offset + static_cast<T>(k) * inc[0];
        }
      }
      return out;
    }
    if (dims.size() != 1)
      error(0, elem + "/" + name + " has shape " + shapeText(dims) +
                   ", expected one value per sample");
    return h5::readAll<T>(d.get(), mem_type, c);
  }

  /// Opens element `name`; `required` makes its absence an error.
  Element openElement(hid_t part, const std::string& name, bool required) const {
    Element e;
    e.name = name;
    const H5I_type_t t = h5::objectType(part, name);
    if (t == H5I_BADID) {
      if (required) error(0, "missing " + where(e) + " (required by H5MD)");
      return e;
    }
    e.present = true;
    const std::string c = ctx(where(e));
    if (t == H5I_DATASET) {
      e.value = h5::check(H5Dopen2(part, name.c_str(), H5P_DEFAULT), c);
      h5::checkStoredSize(e.value.get(), c);  // before any frame buffer is sized from it
      e.dims = h5::datasetDims(e.value.get(), c);
      return e;
    }
    if (t != H5I_GROUP) error(0, where(e) + " is neither a group nor a dataset");
    e.time_dependent = true;
    h5::Handle g = h5::check(H5Gopen2(part, name.c_str(), H5P_DEFAULT), c);
    if (h5::objectType(g.get(), "value") != H5I_DATASET)
      error(0, "missing dataset " + where(e) + "/value");
    e.value = h5::check(H5Dopen2(g.get(), "value", H5P_DEFAULT), c + "/value");
    h5::checkStoredSize(e.value.get(), c + "/value");
    e.dims = h5::datasetDims(e.value.get(), c + "/value");
    if (e.dims.empty()) error(0, where(e) + "/value is a scalar, expected a time series");
    e.steps = readGrid<std::int64_t>(g.get(), "step", H5T_NATIVE_INT64, e.dims[0], where(e));
    return e;
  }

  /// Checks value dims: time-dependent [rows][inner...] or fixed [inner...].
  void checkShape(const Element& e, const std::vector<hsize_t>& inner,
                  const std::string& expected) const {
    if (!e.present) return;
    std::vector<hsize_t> got = e.dims;
    if (e.time_dependent) got.erase(got.begin());
    if (got != inner)
      error(0, where(e) + (e.time_dependent ? "/value" : "") + " has shape " + shapeText(e.dims) +
                   ", expected " + (e.time_dependent ? "[frames," : "[") + expected + "]");
  }

  /// Matches a time-dependent element's rows to position's frames (by step when they differ).
  void alignRows(Element& e) const {
    if (!e.present || !e.time_dependent) return;
    const std::size_t common_rows = std::min(e.steps.size(), steps.size());
    e.same_rows = std::equal(e.steps.begin(), e.steps.begin() + common_rows, steps.begin());
    if (!e.same_rows)
      for (hsize_t r = 0; r < e.steps.size(); ++r) e.row_of_step.emplace(e.steps[r], r);
  }

  /// Row of element e for frame k, or -1 when e has no sample at that step.
  long long rowFor(const Element& e, std::size_t k) const {
    if (e.same_rows) return static_cast<long long>(k);
    const auto it = e.row_of_step.find(steps[k]);
    return it == e.row_of_step.end() ? -1 : static_cast<long long>(it->second);
  }

  /// Reads frame k of element e (one row of its value, or the whole fixed dataset) into out;
  /// false when e has no sample at that frame's step.
  bool readElement(const Element& e, std::size_t k, hid_t mem_type, void* out) const {
    const std::string c = ctx(where(e) + (e.time_dependent ? "/value" : ""));
    if (!e.time_dependent) {
      h5::checkStatus(H5Dread(e.value.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out), c);
      return true;
    }
    const long long row = rowFor(e, k);
    if (row < 0) return false;
    // Rows are re-checked on every read: a file still being written may have grown.
    const auto d = h5::datasetDims(e.value.get(), c);
    if (static_cast<std::size_t>(row) >= d[0])
      error(k, where(e) + "/value has only " + std::to_string(d[0]) + " rows (truncated write?)");
    h5::readRows(e.value.get(), static_cast<hsize_t>(row), 1, mem_type, out, c);
    return true;
  }

  double boxEdge(std::size_t k) const {
    const bool matrix = edges.dims.size() == (edges.time_dependent ? 3u : 2u);
    double e[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    if (!readElement(edges, k, H5T_NATIVE_DOUBLE, e))
      error(k, where(edges) + " has no value at step " + std::to_string(steps[k]));
    double L[3];
    if (matrix) {
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          if (a != b && e[3 * a + b] != 0.0)
            error(k, "the box is triclinic (" + where(edges) +
                         " has off-diagonal entries); only cubic boxes are supported");
      for (int a = 0; a < 3; ++a) L[a] = e[4 * a];
    } else {
      for (int a = 0; a < 3; ++a) L[a] = e[a];
    }
    for (double l : L)
      if (!(l > 0.0) || !std::isfinite(l))
        error(k,
              "box edge " + formatReal(l) + " in " + where(edges) + " is not positive and finite");
    // Cubic up to the rounding of single-precision writers.
    if (std::fabs(L[1] - L[0]) > 1e-6 * L[0] || std::fabs(L[2] - L[0]) > 1e-6 * L[0])
      error(k, "the box is not cubic (" + formatReal(L[0]) + " x " + formatReal(L[1]) + " x " +
                   formatReal(L[2]) + "); only cubic boxes are supported");
    return L[0];
  }

  void requireFrame(std::size_t k) const {
    if (k >= frames)
      error(k, "frame " + std::to_string(k) + " requested, the file has " + std::to_string(frames) +
                   " complete frames");
  }

  void open(const std::string& requested_group);
  /// The checks of an open file, shared by open() and the file-image constructor.
  void openGroups(const std::string& requested_group);
  void openBox(hid_t part);
};

void H5mdReader::Impl::open(const std::string& requested_group) {
  h5::silenceErrors();
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) error(0, "the file does not exist");
  // A writer killed half-way through a frame leaves its undo journal: roll back to the last
  // complete frame first, as `granagg md --restart` would (a live writer's file is refused).
  if (h5journal::pending(path)) {
    try {
      const std::string note = h5journal::recover(path).summary(path);
      if (!note.empty()) std::fprintf(stderr, "granagg: %s\n", note.c_str());
    } catch (const std::runtime_error& e) {
      error(0, e.what());
    }
  }
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    h5::lastError();
    error(0, "not an HDF5 file (so not an H5MD trajectory)");
  }
  file = h5::Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!file) {
    const std::string msg = h5::lastError();
    error(0, "cannot open the HDF5 file (" + (msg.empty() ? std::string("unknown error") : msg) +
                 "); a file cut short by a crash or an interrupted copy cannot be opened by HDF5 "
                 "at all");
  }
  openGroups(requested_group);
}

void H5mdReader::Impl::openGroups(const std::string& requested_group) {
  const hid_t f = file.get();
  if (h5::objectType(f, "/h5md") == H5I_GROUP) {
    h5::Handle g = h5::check(H5Gopen2(f, "/h5md", H5P_DEFAULT), ctx("/h5md"));
    if (h5::Handle a = h5::openAttribute(g.get(), "version")) {
      const auto v =
          h5::readNumericAttribute<std::int64_t>(a.get(), H5T_NATIVE_INT64, ctx("/h5md version"));
      if (v.size() != 2 || v[0] != 1)
        error(0, "unsupported H5MD version (expected 1.x, /h5md version has " +
                     std::to_string(v.size()) + " entries, first " +
                     (v.empty() ? std::string("?") : std::to_string(v[0])) + ")");
    }
  }
  if (h5::objectType(f, "/particles") != H5I_GROUP)
    error(0, "no /particles group: not an H5MD trajectory");
  h5::Handle particles = h5::check(H5Gopen2(f, "/particles", H5P_DEFAULT), ctx("/particles"));
  const auto groups = h5::children(particles.get());
  if (groups.empty()) error(0, "/particles holds no particle group");
  if (requested_group.empty()) {
    const bool has_all =
        std::find(groups.begin(), groups.end(), H5MD_PARTICLE_GROUP) != groups.end();
    group = has_all ? H5MD_PARTICLE_GROUP : groups.front();
  } else {
    group = requested_group;
    if (std::find(groups.begin(), groups.end(), group) == groups.end()) {
      std::string list;
      for (const auto& g : groups) list += (list.empty() ? "" : ", ") + g;
      error(0, "no particle group '/particles/" + group + "' (available: " + list + ")");
    }
  }
  h5::Handle part =
      h5::check(H5Gopen2(particles.get(), group.c_str(), H5P_DEFAULT), ctx("/particles/" + group));
  const hid_t p = part.get();

  pos = openElement(p, "position", true);
  if (!pos.time_dependent)
    error(0, where(pos) + " must be a time-dependent group {value, step, time}");
  if (pos.dims.size() != 3 || pos.dims[2] != 3)
    error(0, where(pos) + "/value has shape " + shapeText(pos.dims) + ", expected [frames,N,3]");
  n = pos.dims[1];
  if (n == 0) error(0, "no particles in " + where(pos));
  steps = pos.steps;
  {
    h5::Handle g = h5::check(H5Gopen2(p, "position", H5P_DEFAULT), ctx(where(pos)));
    if (h5::objectType(g.get(), "time") == H5I_BADID)
      times.assign(steps.begin(), steps.end());  // H5MD makes time optional: the steps stand in
    else
      times = readGrid<double>(g.get(), "time", H5T_NATIVE_DOUBLE, pos.dims[0], where(pos));
  }
  // A frame exists once its step and time rows exist (writers extend them last).
  frames = std::min<std::size_t>({pos.dims[0], steps.size(), times.size()});

  openBox(p);
  const hsize_t N = n;
  vel = openElement(p, "velocity", false);
  checkShape(vel, {N, 3}, "N=" + std::to_string(N) + ",3");
  charge = openElement(p, "charge", false);
  checkShape(charge, {N}, "N=" + std::to_string(N));
  image = openElement(p, "image", false);
  checkShape(image, {N, 3}, "N=" + std::to_string(N) + ",3");
  for (Element* e : {&vel, &charge, &image, &edges}) alignRows(*e);
}

void H5mdReader::Impl::openBox(hid_t part) {
  const std::string b = "particles/" + group + "/box";
  if (h5::objectType(part, "box") != H5I_GROUP) error(0, "missing " + b + " (required by H5MD)");
  h5::Handle box = h5::check(H5Gopen2(part, "box", H5P_DEFAULT), ctx(b));
  if (h5::Handle dim = h5::openAttribute(box.get(), "dimension")) {
    const auto d =
        h5::readNumericAttribute<std::int64_t>(dim.get(), H5T_NATIVE_INT64, ctx(b + " dimension"));
    if (d.size() != 1 || d[0] != 3)
      error(0, b + " dimension is " + (d.empty() ? std::string("empty") : std::to_string(d[0])) +
                   ", only 3 is supported");
  }
  if (h5::Handle bnd = h5::openAttribute(box.get(), "boundary")) {
    const auto v = h5::readStringArrayAttribute(bnd.get(), ctx(b + " boundary"));
    if (v.size() != 3)
      error(0, b + " boundary has " + std::to_string(v.size()) + " entries, expected 3");
    for (const auto& s : v)
      if (s != "periodic")
        error(0, b + " boundary is '" + s + "'; only periodic boxes are supported");
  }
  edges = openElement(box.get(), "edges", true);
  edges.name = "box/edges";
  const std::size_t rank = edges.dims.size() - (edges.time_dependent ? 1 : 0);
  const std::vector<hsize_t> inner(edges.dims.end() - static_cast<std::ptrdiff_t>(rank),
                                   edges.dims.end());
  if (!(inner == std::vector<hsize_t>{3} || inner == std::vector<hsize_t>{3, 3}))
    error(0, where(edges) + " has shape " + shapeText(edges.dims) +
                 ", expected [3] or [3,3] per frame");
}

H5mdReader::H5mdReader(const std::string& path, const std::string& particle_group)
    : m_impl(std::make_unique<Impl>()) {
  m_impl->path = path;
  m_impl->open(particle_group);
}

H5mdReader H5mdReader::fromImage(const void* data, std::size_t size, const std::string& name,
                                  const std::string& particle_group) {
  h5::silenceErrors();
  H5mdReader r;
  Impl& m = *r.m_impl;
  m.path = name;
  // HDF5's file-image API (what H5LTopen_file_image does): the core driver over a copy of the
  // bytes, never written back.
  h5::Handle fapl = h5::check(H5Pcreate(H5P_FILE_ACCESS), m.ctx("file access properties"));
  h5::checkStatus(H5Pset_fapl_core(fapl.get(), 1 << 16, 0), m.ctx("core driver"));
  h5::checkStatus(H5Pset_file_image(fapl.get(), const_cast<void*>(data), size),
                  m.ctx("file image"));
  m.file = h5::Handle(H5Fopen(name.c_str(), H5F_ACC_RDONLY, fapl.get()));
  if (!m.file) {
    const std::string msg = h5::lastError();
    m.error(0, "cannot open the HDF5 file image (" +
                   (msg.empty() ? std::string("unknown error") : msg) + ")");
  }
  m.openGroups(particle_group);
  return r;
}

H5mdReader::H5mdReader() : m_impl(std::make_unique<Impl>()) {}

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
  return m_impl->steps[i];
}

double H5mdReader::time(std::size_t i) const {
  m_impl->requireFrame(i);
  return m_impl->times[i];
}

double H5mdReader::box(std::size_t i) const {
  m_impl->requireFrame(i);
  return m_impl->boxEdge(i);
}

void H5mdReader::keepWrapCrossings(bool keep) { m_impl->keep_crossings = keep; }

void H5mdReader::readFrame(std::size_t k, TrajectoryFrame& f) const {
  const Impl& m = *m_impl;
  m.requireFrame(k);
  const std::size_t n = m.n;
  f.index = k;
  f.step = m.steps[k];
  f.time = m.times[k];
  try {
    f.box = m.boxEdge(k);
    f.position.resize(3 * n);
    m.readElement(m.pos, k, H5T_NATIVE_DOUBLE, f.position.data());
    f.image.assign(m.image.present ? 3 * n : 0, 0);
    if (m.image.present && !m.readElement(m.image, k, H5T_NATIVE_INT32, f.image.data()))
      f.image.clear();
    f.velocity.resize(m.vel.present ? 3 * n : 0);
    if (m.vel.present && !m.readElement(m.vel, k, H5T_NATIVE_DOUBLE, f.velocity.data()))
      f.velocity.clear();
    f.charge.resize(m.charge.present ? n : 0);
    if (m.charge.present && !m.readElement(m.charge, k, H5T_NATIVE_DOUBLE, f.charge.data()))
      f.charge.clear();
  } catch (const TrajectoryError&) {
    throw;
  } catch (const std::exception& e) {  // HDF5 read errors (common/Hdf5.h): name the frame
    m.error(k, e.what());
  }
  f.id.resize(n);
  for (std::size_t i = 0; i < n; ++i) f.id[i] = static_cast<std::int64_t>(i);
  // Wrap into [0, L): other engines store [-L/2, L/2) or unwrapped positions; the shift goes into
  // the image count so that unwrapped positions stay the same. Our own positions are inside and
  // stay bit for bit.
  const bool had_images = !f.image.empty();
  if (!had_images) f.image.assign(3 * n, 0);
  for (std::size_t j = 0; j < 3 * n; ++j)
    if (!wrapCoordinate(f.position[j], f.image[j], f.box))
      m.error(k, "particle " + std::to_string(j / 3) + " has position " + "xyz"[j % 3] + " = " +
                     formatReal(f.position[j]) +
                     " (not finite, or more than 2^31 box lengths away)");
  // Without an image element, image counts exist only if asked for: the crossings of this frame
  // alone cannot be told from the wraps of a wrapped file (an MSD across frames would jump).
  if (!had_images && !m.keep_crossings) f.image.clear();
}

TrajectoryFrame H5mdReader::readFrame(std::size_t i) const {
  TrajectoryFrame f;
  readFrame(i, f);
  return f;
}

std::vector<std::pair<std::string, std::string>> H5mdReader::parameters() const {
  const Impl& m = *m_impl;
  std::vector<std::pair<std::string, std::string>> out;
  if (h5::objectType(m.file.get(), "/parameters") != H5I_GROUP) return out;
  h5::Handle g =
      h5::check(H5Gopen2(m.file.get(), "/parameters", H5P_DEFAULT), m.ctx("/parameters"));
  for (const auto& name : h5::attributeNames(g.get(), m.ctx("/parameters"))) {
    const std::string c = m.ctx("/parameters attribute '" + name + "'");
    std::string text;
    try {
      h5::Handle a = h5::check(H5Aopen(g.get(), name.c_str(), H5P_DEFAULT), c);
      h5::Handle t = h5::check(H5Aget_type(a.get()), c);
      const H5T_class_t cls = H5Tget_class(t.get());
      if (cls == H5T_STRING) {
        const auto v = h5::readStringArrayAttribute(a.get(), c);
        for (std::size_t k = 0; k < v.size(); ++k) text += (k ? "," : "") + v[k];
      } else if (cls == H5T_INTEGER) {
        const auto v = h5::readNumericAttribute<std::int64_t>(a.get(), H5T_NATIVE_INT64, c);
        for (std::size_t k = 0; k < v.size(); ++k) text += (k ? "," : "") + std::to_string(v[k]);
      } else if (cls == H5T_FLOAT) {
        const auto v = h5::readNumericAttribute<double>(a.get(), H5T_NATIVE_DOUBLE, c);
        for (std::size_t k = 0; k < v.size(); ++k) text += (k ? "," : "") + formatReal(v[k]);
      } else {
        continue;  // compound or other exotic types: not a parameter we can show as text
      }
    } catch (const std::runtime_error&) {
      H5Eclear2(H5E_DEFAULT);
      continue;  // an unreadable parameter is not fatal: readers look up a few keys only
    }
    out.emplace_back(name, text);
  }
  return out;
}

std::string H5mdReader::configToml() const {
  const Impl& m = *m_impl;
  const std::string p = std::string("/parameters/") + H5MD_CONFIG_DATASET;
  if (h5::objectType(m.file.get(), p) != H5I_DATASET) return "";
  h5::Handle d = h5::check(H5Dopen2(m.file.get(), p.c_str(), H5P_DEFAULT), m.ctx(p));
  return h5::readString(d.get(), false, m.ctx(p));
}

std::pair<std::string, std::string> H5mdReader::creator() const {
  const Impl& m = *m_impl;
  std::pair<std::string, std::string> out;
  if (h5::objectType(m.file.get(), "/h5md/creator") != H5I_GROUP) return out;
  h5::Handle g =
      h5::check(H5Gopen2(m.file.get(), "/h5md/creator", H5P_DEFAULT), m.ctx("/h5md/creator"));
  if (h5::Handle a = h5::openAttribute(g.get(), "name"))
    out.first = h5::readString(a.get(), true, m.ctx("creator name"));
  if (h5::Handle a = h5::openAttribute(g.get(), "version"))
    out.second = h5::readString(a.get(), true, m.ctx("creator version"));
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
    h5::Handle g = h5::check(H5Gopen2(m.file.get(), root, H5P_DEFAULT), m.ctx(root));
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
    h5::Handle g = h5::check(H5Gopen2(m.file.get(), base.c_str(), H5P_DEFAULT), m.ctx(base));
    h5::Handle v = h5::check(H5Dopen2(g.get(), "value", H5P_DEFAULT), m.ctx(base + "/value"));
    const auto dims = h5::datasetDims(v.get(), m.ctx(base + "/value"));
    if (dims.size() != 1)
      m.error(0, base + "/value has shape " + shapeText(dims) +
                     ", expected a scalar time series [samples]");
    ObservableSeries s;
    s.name = name;
    s.value = h5::readAll<double>(v.get(), H5T_NATIVE_DOUBLE, m.ctx(base + "/value"));
    s.step = m.readGrid<std::int64_t>(g.get(), "step", H5T_NATIVE_INT64, s.value.size(), base);
    s.time = m.readGrid<double>(g.get(), "time", H5T_NATIVE_DOUBLE, s.value.size(), base);
    // complete samples only (step/time are written last)
    const std::size_t rows = std::min({s.value.size(), s.step.size(), s.time.size()});
    s.value.resize(rows);
    s.step.resize(rows);
    s.time.resize(rows);
    return s;
  }
  m.error(0, "no observable named '" + name + "'");
}

}  // namespace granagg::common
