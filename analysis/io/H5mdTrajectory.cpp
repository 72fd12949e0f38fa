#include "analysis/io/H5mdTrajectory.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "common/Box.h"
#include "common/Csv.h"
#include "common/Hdf5.h"

namespace granagg::analysis {
namespace h5 = common::h5;  // (common/Hdf5.h)

namespace {

/// One element of the particle group: time-dependent {value, step, time} or a fixed dataset.
struct Element {
  std::string name;
  bool present = false, time_dependent = false;
  h5::Handle value;
  std::vector<hsize_t> shape;                             // of value
  std::vector<std::int64_t> steps;                        // one per row (time-dependent only)
  std::unordered_map<std::int64_t, hsize_t> row_of_step;  // when rows do not follow position's
  bool same_rows = true;                                  // row k belongs to frame k
};

}  // namespace

struct H5mdTrajectory::Impl {
  h5::Handle file;  // declared first: closed last
  std::string path, group;
  std::size_t n = 0, frames = 0, cursor = 0;
  Element pos, img, vel, chg, edges;
  std::vector<std::int64_t> steps;
  std::vector<double> times;
  std::vector<double> fixed_edges;  // time-independent box
  std::map<std::string, std::string> params;

  [[noreturn]] void error(std::size_t frame, const std::string& what) const {
    throw TrajectoryError(path, frame, what);
  }
  std::string where(const std::string& e) const { return "/particles/" + group + "/" + e; }

  template <class T>
  std::vector<T> readGrid(hid_t grp, const std::string& elem, const char* name, hid_t mem_type,
                          std::size_t rows) {
    const std::string c = "'" + path + "' " + where(elem) + "/" + name;
    if (h5::objectType(grp, name) != H5I_DATASET)
      error(0, "missing dataset " + where(elem) + "/" + name + " (required by H5MD)");
    h5::Handle d = h5::check(H5Dopen2(grp, name, H5P_DEFAULT), c);
    const auto dims = h5::datasetDims(d.get(), c);
    if (dims.empty()) {  // H5MD fixed increment: value k = offset + k * increment
      const auto inc = h5::readAll<T>(d.get(), mem_type, c);
      T offset = 0;
      if (H5Aexists(d.get(), "offset") > 0) {
        h5::Handle a(H5Aopen(d.get(), "offset", H5P_DEFAULT));
        if (a) H5Aread(a.get(), mem_type, &offset);
      }
      H5Eclear2(H5E_DEFAULT);
      std::vector<T> out(rows);
      for (std::size_t k = 0; k < rows; ++k) out[k] = offset + static_cast<T>(k) * inc.at(0);
      return out;
    }
    if (dims.size() != 1) error(0, where(elem) + "/" + name + " must hold one value per frame");
    return h5::readAll<T>(d.get(), mem_type, c);
  }

  Element openElement(hid_t part, const std::string& name, bool required) {
    Element e;
    e.name = name;
    const H5I_type_t t = h5::objectType(part, name);
    if (t == H5I_BADID) {
      if (required) error(0, "missing " + where(name) + " (required)");
      return e;
    }
    const std::string c = "'" + path + "' " + where(name);
    e.present = true;
    if (t == H5I_DATASET) {
      e.value = h5::check(H5Dopen2(part, name.c_str(), H5P_DEFAULT), c);
      e.shape = h5::datasetDims(e.value.get(), c);
      return e;
    }
    h5::Handle g = h5::check(H5Gopen2(part, name.c_str(), H5P_DEFAULT), c);
    if (h5::objectType(g.get(), "value") != H5I_DATASET)
      error(0, "missing dataset " + where(name) + "/value");
    e.time_dependent = true;
    e.value = h5::check(H5Dopen2(g.get(), "value", H5P_DEFAULT), c + "/value");
    e.shape = h5::datasetDims(e.value.get(), c + "/value");
    if (e.shape.empty()) error(0, where(name) + "/value is a scalar, expected a time series");
    e.steps = readGrid<std::int64_t>(g.get(), name, "step", H5T_NATIVE_INT64, e.shape[0]);
    return e;
  }

  void open(const std::string& requested_group) {
    h5::silenceErrors();
    file = h5::Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
    if (!file) {
      const std::string msg = h5::lastError();
      error(0, "cannot open the HDF5 file (" +
                   (msg.empty() ? std::string("unknown HDF5 error") : msg) +
                   "); a file cut short by a crash or an interrupted copy cannot be opened by HDF5 "
                   "at all");
    }
    if (h5::objectType(file.get(), "/particles") != H5I_GROUP)
      error(0, "no /particles group: not an H5MD trajectory");
    h5::Handle particles = h5::check(H5Gopen2(file.get(), "/particles", H5P_DEFAULT), path);
    const auto groups = h5::children(particles.get());
    if (groups.empty()) error(0, "/particles holds no particle group");
    if (!requested_group.empty()) {
      if (std::find(groups.begin(), groups.end(), requested_group) == groups.end())
        error(0, "no particle group /particles/" + requested_group);
      group = requested_group;
    } else {
      group =
          std::find(groups.begin(), groups.end(), "all") != groups.end() ? "all" : groups.front();
    }
    h5::Handle part = h5::check(H5Gopen2(particles.get(), group.c_str(), H5P_DEFAULT), path);
    pos = openElement(part.get(), "position", true);
    if (!pos.time_dependent || pos.shape.size() != 3 || pos.shape[2] != 3)
      error(0, where("position") + "/value must have shape [frames, N, 3]");
    n = pos.shape[1];
    if (n == 0) error(0, "no particles in " + where("position"));
    {
      const std::string c = "'" + path + "' " + where("position");
      h5::Handle g = h5::check(H5Gopen2(part.get(), "position", H5P_DEFAULT), c);
      const std::size_t rows = pos.shape[0];
      steps = readGrid<std::int64_t>(g.get(), "position", "step", H5T_NATIVE_INT64, rows);
      if (h5::objectType(g.get(), "time") == H5I_BADID) {
        times.assign(steps.begin(), steps.end());  // H5MD makes time optional: fall back to steps
      } else {
        times = readGrid<double>(g.get(), "position", "time", H5T_NATIVE_DOUBLE, rows);
      }
      // A frame exists once its step and time rows exist (writers add them last).
      frames = std::min({rows, steps.size(), times.size()});
    }
    if (h5::objectType(part.get(), "box") != H5I_GROUP)
      error(0, "missing " + where("box") + " (required by H5MD)");
    {
      h5::Handle box = h5::check(H5Gopen2(part.get(), "box", H5P_DEFAULT), path);
      if (H5Aexists(box.get(), "boundary") > 0) {
        // fixed-length string array: check that no entry says "none"
        h5::Handle a(H5Aopen(box.get(), "boundary", H5P_DEFAULT));
        h5::Handle type(H5Aget_type(a.get()));
        if (H5Tget_class(type.get()) == H5T_STRING && H5Tis_variable_str(type.get()) <= 0) {
          const std::size_t len = H5Tget_size(type.get());
          std::vector<char> buf(len * 3 + 1, '\0');
          if (H5Aread(a.get(), type.get(), buf.data()) >= 0 &&
              std::string(buf.data(), buf.size()).find("none") != std::string::npos)
            error(0,
                  where("box") + " has non-periodic boundaries; the analysis needs a periodic box");
        }
      }
      H5Eclear2(H5E_DEFAULT);
      edges = openElement(box.get(), "edges", false);
      edges.name = "box/edges";
      if (!edges.present) error(0, "missing " + where("box/edges"));
      if (!edges.time_dependent) {
        fixed_edges =
            h5::readAll<double>(edges.value.get(), H5T_NATIVE_DOUBLE, path + " box/edges");
        if (fixed_edges.size() != 3 && fixed_edges.size() != 9)
          error(0, where("box/edges") + " must hold 3 or 3x3 values");
      }
    }
    img = openElement(part.get(), "image", false);
    vel = openElement(part.get(), "velocity", false);
    chg = openElement(part.get(), "charge", false);
    for (Element* e : {&img, &vel, &edges, &chg}) {
      if (!e->present || !e->time_dependent) continue;
      const std::size_t common = std::min(e->steps.size(), steps.size());
      e->same_rows = std::equal(e->steps.begin(), e->steps.begin() + common, steps.begin());
      if (!e->same_rows)
        for (hsize_t r = 0; r < e->steps.size(); ++r) e->row_of_step[e->steps[r]] = r;
    }
    if (chg.present && !chg.time_dependent && (chg.shape.size() != 1 || chg.shape[0] != n))
      error(0, where("charge") + " (time-independent) must have shape [N]");
    readParameters();
  }

  void readParameters() {
    if (h5::objectType(file.get(), "/parameters") != H5I_GROUP) return;
    h5::Handle g = h5::check(H5Gopen2(file.get(), "/parameters", H5P_DEFAULT), path);
    for (const auto& name : h5::attributeNames(g.get(), path + ": /parameters")) {
      try {
        h5::Handle a(H5Aopen(g.get(), name.c_str(), H5P_DEFAULT));
        h5::Handle type(H5Aget_type(a.get()));
        const H5T_class_t cls = H5Tget_class(type.get());
        if (cls == H5T_STRING) {
          params[name] = h5::readStringAttribute(g.get(), name, path);
        } else if (cls == H5T_INTEGER || cls == H5T_FLOAT) {
          h5::Handle space(H5Aget_space(a.get()));
          if (H5Sget_simple_extent_npoints(space.get()) == 1) {
            double v = 0;
            if (H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v) >= 0) params[name] = common::formatReal(v);
          }
        }
      } catch (const std::exception&) {
        // an unreadable parameter is not fatal: the analysis only looks up a few keys
      }
      H5Eclear2(H5E_DEFAULT);
    }
  }

  /// Row of element e for frame k, or -1 when e has no sample at that step.
  long long rowFor(const Element& e, std::size_t k) const {
    if (e.same_rows) return static_cast<long long>(k);
    auto it = e.row_of_step.find(steps[k]);
    return it == e.row_of_step.end() ? -1 : static_cast<long long>(it->second);
  }

  template <class T>
  void readElement(const Element& e, std::size_t k, hid_t mem_type, std::vector<T>& out,
                   std::size_t per_particle) {
    const std::string c = where(e.name);
    if (!e.present) {
      out.clear();
      return;
    }
    if (!e.time_dependent) {
      out = h5::readAll<T>(e.value.get(), mem_type, c);
      return;
    }
    const std::size_t expect = per_particle == 1 ? 2 : 3;
    if (e.shape.size() != expect || e.shape[1] != n || (per_particle == 3 && e.shape[2] != 3))
      error(k, c + "/value must have shape [frames, " + std::to_string(n) +
                   (per_particle == 3 ? ", 3]" : "]"));
    const long long row = rowFor(e, k);
    if (row < 0) {
      out.clear();
      return;
    }
    // Rows are re-checked on every read: a file still being written may have grown.
    const auto d = h5::datasetDims(e.value.get(), c);
    if (static_cast<std::size_t>(row) >= d[0])
      error(k, c + "/value has only " + std::to_string(d[0]) + " rows (truncated write?)");
    out.resize(n * per_particle);
    h5::readRows(e.value.get(), static_cast<hsize_t>(row), 1, mem_type, out.data(), c + "/value");
  }

  void read(std::size_t k, Frame& f) {
    f.index = k;
    f.step = steps[k];
    f.time = times[k];
    try {
      // box
      std::vector<double> ed;
      if (edges.time_dependent) {
        const long long row = rowFor(edges, k);
        std::size_t inner = 1;
        for (std::size_t d = 1; d < edges.shape.size(); ++d) inner *= edges.shape[d];
        if (row >= 0 && (inner == 3 || inner == 9)) {
          const auto d = h5::datasetDims(edges.value.get(), where("box/edges"));
          if (static_cast<std::size_t>(row) >= d[0])
            error(k, where("box/edges") + "/value has only " + std::to_string(d[0]) +
                         " rows (truncated write?)");
          ed.resize(inner);
          h5::readRows(edges.value.get(), static_cast<hsize_t>(row), 1, H5T_NATIVE_DOUBLE,
                       ed.data(), where("box/edges"));
        } else if (row >= 0) {
          error(k, where("box/edges") + "/value must hold 3 or 3x3 values per frame");
        }
      } else {
        ed = fixed_edges;
      }
      if (ed.empty())
        error(k, where("box/edges") + " has no value at step " + std::to_string(steps[k]));
      double L[3];
      if (ed.size() == 9) {
        for (int d = 0; d < 3; ++d) L[d] = ed[4 * d];
        if (ed[1] != 0 || ed[2] != 0 || ed[3] != 0 || ed[5] != 0 || ed[6] != 0 || ed[7] != 0)
          error(k, "triclinic boxes are not supported");
      } else if (ed.size() == 3) {
        for (int d = 0; d < 3; ++d) L[d] = ed[d];
      } else {
        error(k, where("box/edges") + " must hold 3 or 3x3 values per frame");
      }
      if (!(L[0] > 0) || !std::isfinite(L[0]))
        error(k, "box edge is not positive: " + common::formatReal(L[0]));
      if (std::fabs(L[1] - L[0]) > 1e-9 * L[0] || std::fabs(L[2] - L[0]) > 1e-9 * L[0])
        error(k, "the box is not cubic (" + common::formatReal(L[0]) + " x " +
                     common::formatReal(L[1]) + " x " + common::formatReal(L[2]) +
                     "); only cubic boxes are supported");
      f.box = L[0];
      readElement(pos, k, H5T_NATIVE_DOUBLE, f.position, 3);
      readElement(img, k, H5T_NATIVE_INT32, f.image, 3);
      readElement(vel, k, H5T_NATIVE_DOUBLE, f.velocity, 3);
      readElement(chg, k, H5T_NATIVE_DOUBLE, f.charge, 1);
    } catch (const TrajectoryError&) {
      throw;
    } catch (const std::exception& e) {
      error(k, e.what());
    }
    f.id.resize(n);
    for (std::size_t i = 0; i < n; ++i) f.id[i] = static_cast<std::int64_t>(i);
    // Wrap into [0, L): other engines store [-L/2, L/2) or slightly outside positions; the
    // shift goes into the image count so that unwrapped positions stay the same.
    const common::Box box{f.box};
    const bool had_images = !f.image.empty();
    if (!had_images) f.image.assign(3 * n, 0);
    for (std::size_t j = 0; j < 3 * n; ++j) {
      double x = f.position[j];
      if (!std::isfinite(x))
        error(k, "particle " + std::to_string(j / 3) + " has a non-finite position");
      f.image[j] += box.wrap(x);
      f.position[j] = x;
    }
    if (!had_images) f.image.clear();  // without stored images unwrapping is impossible anyway
  }
};

H5mdTrajectory::H5mdTrajectory(const std::string& path, const std::string& group)
    : m_impl(std::make_unique<Impl>()) {
  m_impl->path = path;
  m_impl->open(group);
}
H5mdTrajectory::~H5mdTrajectory() = default;

bool H5mdTrajectory::next(Frame& f) {
  Impl& m = *m_impl;
  if (m.cursor >= m.frames) return false;
  m.read(m.cursor, f);
  ++m.cursor;
  return true;
}

std::size_t H5mdTrajectory::frameCountHint() const { return m_impl->frames; }
const std::map<std::string, std::string>& H5mdTrajectory::parameters() const {
  return m_impl->params;
}
const std::string& H5mdTrajectory::path() const { return m_impl->path; }
std::size_t H5mdTrajectory::size() const { return m_impl->n; }

}  // namespace granagg::analysis
