#include "md/io/InitialState.h"

#include <sys/stat.h>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <vector>

#include "common/Csv.h"
#include "common/Strings.h"
#include "md/io/H5mdReader.h"
#include "md/io/Hdf5Util.h"

namespace granagg::md {

bool wrapCoordinate(double& x, std::int32_t& image, double box) {
  if (!std::isfinite(x)) return false;
  if (x >= 0.0 && x < box) return true;  // already wrapped: leave it bit for bit
  const double shift = std::floor(x / box);
  const double img = static_cast<double>(image) + shift;
  // +-1 headroom for the round-off corrections below
  if (!(std::fabs(img) < static_cast<double>(std::numeric_limits<std::int32_t>::max()) - 1.0))
    return false;
  double w = x - shift * box;
  std::int64_t im = static_cast<std::int64_t>(img);
  // x / box may round across an integer: bring w back into [0, box). A tiny negative w becomes
  // box after adding box and is then mapped to 0 (the nearest wrapped value).
  if (w < 0.0) {
    w += box;
    --im;
  }
  if (w >= box) {
    w -= box;
    ++im;
  }
  if (w < 0.0) w = 0.0;
  x = w;
  image = static_cast<std::int32_t>(im);
  return true;
}

void wrapIntoBox(Frame& f) {
  const std::size_t n = f.size();
  if (!(f.box > 0.0) || !std::isfinite(f.box))
    throw std::invalid_argument("wrapIntoBox: the box edge must be positive and finite, got " +
                                common::formatReal(f.box));
  if (f.y.size() != n || f.z.size() != n)
    throw std::invalid_argument("wrapIntoBox: x, y and z have different lengths");
  for (auto* img : {&f.ix, &f.iy, &f.iz}) {
    if (img->empty()) img->assign(n, 0);
    if (img->size() != n)
      throw std::invalid_argument("wrapIntoBox: image arrays and positions have different lengths");
  }
  std::vector<double>* c[3] = {&f.x, &f.y, &f.z};
  std::vector<std::int32_t>* im[3] = {&f.ix, &f.iy, &f.iz};
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      if (!wrapCoordinate((*c[d])[i], (*im[d])[i], f.box))
        throw std::invalid_argument("particle " + std::to_string(i) + ": position " + "xyz"[d] +
                                    " = " + common::formatReal((*c[d])[i]) +
                                    " is not finite (or lies more than 2^31 box lengths away)");
}

namespace {

/// Line numbers (1-based) of the data rows of a CSV file, following common::readCsv's rules:
/// blank and '#' lines are skipped, the first remaining line is the header.
std::vector<std::size_t> csvRowLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::size_t> lines;
  std::string line;
  std::size_t lineno = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++lineno;
    const std::string s = common::trim(line);
    if (s.empty() || s[0] == '#') continue;
    if (!header) {
      header = true;
      continue;
    }
    lines.push_back(lineno);
  }
  return lines;
}

void checkMinimumSize(std::size_t n, const std::string& path) {
  if (n < 2)
    throw std::invalid_argument("initial state '" + path + "' has " + std::to_string(n) +
                                " particle(s); at least 2 are needed");
}

}  // namespace

Frame readInitialStateCsv(const std::string& path, double box) {
  if (!(box > 0.0) || !std::isfinite(box))
    throw std::invalid_argument("initial state '" + path +
                                "': the box edge must be positive and finite, got " +
                                common::formatReal(box));
  const common::CsvTable t = common::readCsv(path);  // names file:line for malformed numbers
  static const char* REQUIRED[] = {"x", "y", "z", "vx", "vy", "vz"};
  for (std::size_t k = 0; k < t.columns.size(); ++k) {
    const std::string& name = t.columns[k];
    bool known = name == "q";
    for (const char* r : REQUIRED) known |= (name == r);
    if (!known)
      throw std::invalid_argument(path + ": unknown column '" + name +
                                  "' (allowed: x,y,z,vx,vy,vz and optional q)");
    for (std::size_t j = 0; j < k; ++j)
      if (t.columns[j] == name)
        throw std::invalid_argument(path + ": column '" + name + "' appears twice");
  }
  std::size_t col[6];
  for (int k = 0; k < 6; ++k) col[k] = t.column(REQUIRED[k]);  // throws naming the missing column
  bool has_q = false;
  std::size_t qcol = 0;
  for (std::size_t k = 0; k < t.columns.size(); ++k)
    if (t.columns[k] == "q") {
      has_q = true;
      qcol = k;
    }
  const std::size_t n = t.rows.size();
  checkMinimumSize(n, path);
  const std::vector<std::size_t> lines = csvRowLines(path);
  auto lineOf = [&](std::size_t i) {
    return i < lines.size() ? std::to_string(lines[i]) : std::string("?");
  };

  Frame f;
  f.box = box;
  for (auto* v : {&f.x, &f.y, &f.z, &f.vx, &f.vy, &f.vz, &f.charge}) v->resize(n);
  std::vector<double>* dst[6] = {&f.x, &f.y, &f.z, &f.vx, &f.vy, &f.vz};
  for (std::size_t i = 0; i < n; ++i) {
    const auto& row = t.rows[i];
    for (int k = 0; k < 6; ++k) {
      const double v = row[col[k]];
      if (!std::isfinite(v))
        throw std::invalid_argument(path + ":" + lineOf(i) + ": particle " + std::to_string(i) +
                                    ": " + REQUIRED[k] + " = " + common::formatReal(v) +
                                    " is not finite");
      (*dst[k])[i] = v;
    }
    const double q = has_q ? row[qcol] : 0.0;
    if (!std::isfinite(q))
      throw std::invalid_argument(path + ":" + lineOf(i) + ": particle " + std::to_string(i) +
                                  ": q = " + common::formatReal(q) + " is not finite");
    f.charge[i] = q;
  }
  try {
    wrapIntoBox(f);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return f;
}

Frame readInitialStateH5md(const std::string& path, long frame, const std::string& particle_group) {
  H5mdReader r(path, particle_group);
  const long nf = static_cast<long>(r.frames());
  if (nf == 0) throw std::invalid_argument("initial state '" + path + "' holds no complete frame");
  const long idx = frame < 0 ? nf + frame : frame;
  if (idx < 0 || idx >= nf)
    throw std::invalid_argument("initial state '" + path + "': frame " + std::to_string(frame) +
                                " requested, the file has " + std::to_string(nf) + " frames");
  if (!r.hasVelocity())
    throw std::invalid_argument("initial state '" + path + "' has no velocities (particles/" +
                                r.particleGroup() + "/velocity); an initial state needs them");
  Frame f = r.readFrame(static_cast<std::size_t>(idx));  // positions wrapped, images filled
  checkMinimumSize(f.size(), path);
  const std::vector<double>* arrays[4] = {&f.vx, &f.vy, &f.vz, &f.charge};
  const char* names[4] = {"vx", "vy", "vz", "charge"};
  for (int k = 0; k < 4; ++k)
    for (std::size_t i = 0; i < arrays[k]->size(); ++i)
      if (!std::isfinite((*arrays[k])[i]))
        throw std::invalid_argument("initial state '" + path + "' frame " + std::to_string(idx) +
                                    ": particle " + std::to_string(i) + ": " + names[k] + " = " +
                                    common::formatReal((*arrays[k])[i]) + " is not finite");
  return f;
}

Frame readInitialState(const std::string& path, double box_if_csv) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    throw std::invalid_argument("initial state file '" + path + "' does not exist");
  if (S_ISDIR(st.st_mode))
    throw std::invalid_argument("initial state '" + path + "' is a directory, not a file");
  h5::silenceErrors();
  const htri_t is_h5 = H5Fis_hdf5(path.c_str());
  h5::lastError();  // clear whatever H5Fis_hdf5 left on the stack
  if (is_h5 > 0) return readInitialStateH5md(path);
  return readInitialStateCsv(path, box_if_csv);
}

}  // namespace granagg::md
