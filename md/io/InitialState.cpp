#include "md/io/InitialState.h"

#include <sys/stat.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/Box.h"
#include "common/Csv.h"
#include "common/H5mdReader.h"
#include "common/Hdf5.h"
#include "common/Strings.h"
#include "md/config/ConfigParser.h"
#include "md/rng/RngStreams.h"

namespace granagg::md {
namespace h5 = common::h5;  // (common/Hdf5.h)

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

namespace {

/// The particles of a CSV initial state as written (box 0, positions not wrapped).
Frame readCsvParticles(const std::string& path) {
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
  return f;
}

/// Puts a file's particles in a box of edge `box` (wrapIntoBox), naming the file in errors.
void placeInBox(Frame& f, double box, const std::string& path) {
  f.box = box;
  try {
    wrapIntoBox(f);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

}  // namespace

Frame readInitialStateCsv(const std::string& path, double box) {
  if (!(box > 0.0) || !std::isfinite(box))
    throw std::invalid_argument("initial state '" + path +
                                "': the box edge must be positive and finite, got " +
                                common::formatReal(box));
  Frame f = readCsvParticles(path);
  placeInBox(f, box, path);
  return f;
}

namespace {

/// One line of a LAMMPS data file: its number, its words (comment removed) and the comment.
struct DataLine {
  std::size_t number = 0;
  std::vector<std::string> words;
  std::string comment;
};

std::vector<std::string> words(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

}  // namespace

bool isLammpsData(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  for (int k = 0; k < 50 && std::getline(in, line); ++k) {
    if (k == 0) continue;  // the title line may say anything
    const auto w = words(line.substr(0, line.find('#')));
    if (w.size() == 2 && w[1] == "atoms" &&
        w[0].find_first_not_of("0123456789") == std::string::npos)
      return true;
  }
  return false;
}

namespace {

/// A LAMMPS data file split into its header lines and its sections by name, with the parsers of
/// its numbers, whose errors name the file and the line.
struct DataFile {
  std::string path;
  std::vector<DataLine> header;                           // up to the first section keyword
  std::map<std::string, std::vector<DataLine>> sections;  // section name -> its lines
  std::map<std::string, DataLine> keyword;                // section name -> its keyword line

  explicit DataFile(const std::string& file) : path(file) {
    std::ifstream in(path);
    if (!in) throw std::invalid_argument("initial state file '" + path + "' cannot be read");
    std::string current, line;
    for (std::size_t n = 1; std::getline(in, line); ++n) {
      if (n == 1) continue;  // title
      const std::size_t hash = line.find('#');
      DataLine d{n, words(line.substr(0, hash)),
                 hash == std::string::npos ? "" : common::trim(line.substr(hash + 1))};
      if (d.words.empty()) continue;
      if (std::isalpha(static_cast<unsigned char>(d.words[0][0]))) {  // a section keyword
        current = common::join(d.words, " ");
        if (keyword.count(current))
          throw std::invalid_argument(path + ":" + std::to_string(n) + ": section '" + current +
                                      "' appears twice");
        keyword[current] = d;
        sections[current];
        continue;
      }
      (current.empty() ? header : sections[current]).push_back(d);
    }
  }
  std::string at(const DataLine& d) const { return path + ":" + std::to_string(d.number) + ": "; }
  double real(const DataLine& d, std::size_t k, const char* what) const {
    double v = 0.0;
    if (!common::parseReal(d.words[k], v) || !std::isfinite(v))
      throw std::invalid_argument(at(d) + what + " '" + d.words[k] + "' is not a finite number");
    return v;
  }
  long long integer(const DataLine& d, std::size_t k, const char* what) const {
    const std::string& w = d.words[k];
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(w.c_str(), &end, 10);
    if (w.empty() || *end != '\0' || errno == ERANGE)
      throw std::invalid_argument(at(d) + what + " '" + w + "' is not an integer");
    return v;
  }
  /// The lines of a section; empty if the file has none.
  const std::vector<DataLine>& section(const std::string& name) const {
    static const std::vector<DataLine> none;
    const auto it = sections.find(name);
    return it == sections.end() ? none : it->second;
  }
};

/// The header's atom count and box: the lower corner and the edge of a cubic box.
struct DataHeader {
  long long atoms = -1;
  double lo[3] = {0, 0, 0};
  double L = 0.0;
};

DataHeader readHeader(const DataFile& file) {
  DataHeader h;
  double hi[3] = {0, 0, 0};
  bool has_box[3] = {false, false, false};
  for (const DataLine& d : file.header) {
    const auto& w = d.words;
    if (w.size() == 2 && w[1] == "atoms") {
      h.atoms = file.integer(d, 0, "atom count");
    } else if (w.size() == 6 && w[3] == "xy") {
      throw std::invalid_argument(file.at(d) +
                                  "a triclinic box (xy xz yz); granagg's box is cubic");
    } else if (w.size() == 4 && w[2].size() == 3 && w[2].compare(1, 2, "lo") == 0 &&
               w[3].size() == 3 && w[3].compare(1, 2, "hi") == 0 && w[2][0] == w[3][0] &&
               w[2][0] >= 'x' && w[2][0] <= 'z') {  // "xlo xhi"
      const int a = w[2][0] - 'x';
      h.lo[a] = file.real(d, 0, "box bound");
      hi[a] = file.real(d, 1, "box bound");
      has_box[a] = true;
    }
  }
  const std::string& path = file.path;
  if (h.atoms < 0) throw std::invalid_argument(path + ": no 'N atoms' line in the header");
  for (int a = 0; a < 3; ++a)
    if (!has_box[a])
      throw std::invalid_argument(path + ": no '" + std::string(1, "xyz"[a]) + "lo " + "xyz"[a] +
                                  "hi' line in the header");
  h.L = hi[0] - h.lo[0];
  for (int a = 0; a < 3; ++a)
    if (!(hi[a] - h.lo[a] > 0.0) || std::fabs((hi[a] - h.lo[a]) - h.L) > 1e-12 * h.L)
      throw std::invalid_argument(path + ": the box must be cubic with positive edges (got " +
                                  common::formatReal(hi[0] - h.lo[0]) + " x " +
                                  common::formatReal(hi[1] - h.lo[1]) + " x " +
                                  common::formatReal(hi[2] - h.lo[2]) + ")");
  return h;
}

/// An atom style granagg reads: its columns, and the columns of x and of diameter, density and
/// q (-1: absent).
struct AtomStyle {
  const char* name;
  std::size_t columns;
  int x, diameter, density, q;
};

/// The Atoms section's style: named after `Atoms #`, else told by the column count (with or
/// without image flags). `images`: the lines end in three image flags.
const AtomStyle& atomStyle(const DataFile& file, bool& images) {
  static const AtomStyle STYLES[] = {{"sphere", 7, 4, 2, 3, -1},
                                     {"charge", 6, 3, -1, -1, 2},
                                     {"atomic", 5, 2, -1, -1, -1},
                                     {"hybrid", 8, 2, 5, 6, 7}};
  const DataLine& kw = file.keyword.at("Atoms");
  const DataLine& first = file.section("Atoms").front();
  const std::string named = words(kw.comment).empty() ? std::string() : words(kw.comment)[0];
  const std::size_t ncol = first.words.size();
  const AtomStyle* style = nullptr;
  for (const AtomStyle& s : STYLES)
    if (named.empty() ? (ncol == s.columns || ncol == s.columns + 3) : named == s.name) style = &s;
  if (!style)
    throw std::invalid_argument(
        file.at(kw) + (named.empty()
                           ? "atom style not named and " + std::to_string(ncol) +
                                 " columns fit none of sphere, charge, atomic, hybrid sphere charge"
                           : "atom style '" + named +
                                 "' is not read (sphere, charge, atomic, hybrid sphere charge)"));
  images = ncol == style->columns + 3;
  if (ncol != style->columns && !images)
    throw std::invalid_argument(file.at(first) + "atom style " + style->name + " has " +
                                std::to_string(style->columns) + " columns (+3 image flags), " +
                                "this line " + std::to_string(ncol));
  return *style;
}

/// Checks every Atoms line against the first's column count and granagg's particles (diameter
/// 1, mass 1: from the sphere style's diameter and density, else from the Masses section) and
/// returns each atom id's line index, ids unique.
std::map<long long, std::size_t> checkAtoms(const DataFile& file, const AtomStyle& style) {
  std::map<long long, double> mass;  // per type (charge, atomic: the Masses section)
  for (const DataLine& d : file.section("Masses")) {
    if (d.words.size() < 2)
      throw std::invalid_argument(file.at(d) + "a Masses line is 'type mass'");
    mass[file.integer(d, 0, "atom type")] = file.real(d, 1, "mass");
  }
  constexpr double UNIT_DENSITY = 6.0 / M_PI;  // mass 1 at diameter 1
  const auto& atoms = file.section("Atoms");
  const std::size_t ncol = atoms.front().words.size();
  std::map<long long, std::size_t> by_id;  // id -> line index in `atoms`
  for (std::size_t i = 0; i < atoms.size(); ++i) {
    const DataLine& d = atoms[i];
    if (d.words.size() != ncol)
      throw std::invalid_argument(file.at(d) + "expected " + std::to_string(ncol) +
                                  " columns as on the first Atoms line, got " +
                                  std::to_string(d.words.size()));
    const long long id = file.integer(d, 0, "atom id");
    if (!by_id.emplace(id, i).second)
      throw std::invalid_argument(file.at(d) + "atom id " + std::to_string(id) + " appears twice");
    const long long type = file.integer(d, 1, "atom type");
    if (style.diameter >= 0) {
      const double dia = file.real(d, style.diameter, "diameter"),
                   rho = file.real(d, style.density, "density");
      if (std::fabs(dia - 1.0) > 1e-9)
        throw std::invalid_argument(file.at(d) + "atom " + std::to_string(id) + ": diameter " +
                                    common::formatReal(dia) +
                                    " (granagg's particles have diameter 1)");
      if (std::fabs(rho / UNIT_DENSITY - 1.0) > 1e-6)
        throw std::invalid_argument(file.at(d) + "atom " + std::to_string(id) + ": density " +
                                    common::formatReal(rho) +
                                    " (granagg's particles have mass 1: density 6/pi = " +
                                    common::formatReal(UNIT_DENSITY) + ")");
    } else if (mass.count(type) && std::fabs(mass[type] - 1.0) > 1e-9) {
      throw std::invalid_argument(
          file.at(d) + "atom " + std::to_string(id) + ": type " + std::to_string(type) +
          " has mass " + common::formatReal(mass[type]) + " (granagg's particles have mass 1)");
    }
  }
  return by_id;
}

/// Each atom's Velocities line, by id: one per atom of the Atoms section (by_id).
std::map<long long, const DataLine*> velocityLines(const DataFile& file,
                                                   const std::map<long long, std::size_t>& by_id) {
  std::map<long long, const DataLine*> vel_of;
  for (const DataLine& d : file.section("Velocities")) {
    if (d.words.size() < 4)
      throw std::invalid_argument(file.at(d) + "a Velocities line is 'id vx vy vz [...]'");
    const long long id = file.integer(d, 0, "atom id");
    if (!by_id.count(id))
      throw std::invalid_argument(file.at(d) + "velocity of atom " + std::to_string(id) +
                                  ", which is not in the Atoms section");
    if (!vel_of.emplace(id, &d).second)
      throw std::invalid_argument(file.at(d) + "atom " + std::to_string(id) +
                                  " has two velocity lines");
  }
  for (const auto& [id, k] : by_id)
    if (!vel_of.count(id))
      throw std::invalid_argument(file.at(file.keyword.at("Velocities")) + "atom " +
                                  std::to_string(id) + " has no velocity line");
  return vel_of;
}

}  // namespace

Frame readInitialStateLammps(const std::string& path) {
  const DataFile file(path);
  const DataHeader h = readHeader(file);
  if (!file.sections.count("Atoms")) throw std::invalid_argument(path + ": no Atoms section");
  if (!file.sections.count("Velocities"))
    throw std::invalid_argument(path +
                                ": no Velocities section (an initial state needs velocities)");
  const auto& atoms = file.section("Atoms");
  if (static_cast<long long>(atoms.size()) != h.atoms)
    throw std::invalid_argument(file.at(file.keyword.at("Atoms")) + "the Atoms section has " +
                                std::to_string(atoms.size()) + " lines, the header says " +
                                std::to_string(h.atoms) + " atoms");
  checkMinimumSize(atoms.size(), path);
  bool images = false;
  const AtomStyle& style = atomStyle(file, images);
  const auto by_id = checkAtoms(file, style);
  const auto vel_of = velocityLines(file, by_id);

  Frame f;
  f.box = h.L;
  const std::size_t n = atoms.size();
  for (auto* v : {&f.x, &f.y, &f.z, &f.vx, &f.vy, &f.vz, &f.charge}) v->resize(n);
  for (auto* v : {&f.ix, &f.iy, &f.iz}) v->assign(n, 0);
  std::size_t i = 0;
  for (const auto& [id, k] : by_id) {  // particle i: the i-th smallest id
    const DataLine& d = atoms[k];
    f.x[i] = file.real(d, style.x, "x") - h.lo[0];
    f.y[i] = file.real(d, style.x + 1, "y") - h.lo[1];
    f.z[i] = file.real(d, style.x + 2, "z") - h.lo[2];
    f.charge[i] = style.q >= 0 ? file.real(d, style.q, "q") : 0.0;
    if (images) {
      std::int32_t* im[3] = {&f.ix[i], &f.iy[i], &f.iz[i]};
      for (int a = 0; a < 3; ++a) {
        const long long v = file.integer(d, style.columns + a, "image flag");
        if (v < -(1LL << 30) || v > (1LL << 30))
          throw std::invalid_argument(file.at(d) + "image flag " + std::to_string(v) +
                                      " too large");
        *im[a] = static_cast<std::int32_t>(v);
      }
    }
    const DataLine& v = *vel_of.at(id);
    f.vx[i] = file.real(v, 1, "vx");
    f.vy[i] = file.real(v, 2, "vy");
    f.vz[i] = file.real(v, 3, "vz");
    ++i;
  }
  try {
    wrapIntoBox(f);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return f;
}

Frame engineFrame(const common::TrajectoryFrame& in) {
  const std::size_t n = in.size();
  Frame f;
  f.step = in.step;
  f.time = in.time;
  f.box = in.box;
  auto split = [n](const std::vector<double>& aos, std::vector<double>& a, std::vector<double>& b,
                   std::vector<double>& c) {
    a.resize(n);
    b.resize(n);
    c.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      a[k] = aos[3 * k];
      b[k] = aos[3 * k + 1];
      c[k] = aos[3 * k + 2];
    }
  };
  split(in.position, f.x, f.y, f.z);
  if (in.hasVelocities()) split(in.velocity, f.vx, f.vy, f.vz);
  f.charge = in.hasCharges() ? in.charge : std::vector<double>(n, 0.0);
  f.ix.assign(n, 0);
  f.iy.assign(n, 0);
  f.iz.assign(n, 0);
  if (in.hasImages())
    for (std::size_t k = 0; k < n; ++k) {
      f.ix[k] = in.image[3 * k];
      f.iy[k] = in.image[3 * k + 1];
      f.iz[k] = in.image[3 * k + 2];
    }
  return f;
}

Frame readInitialStateH5md(const std::string& path, long frame, const std::string& particle_group) {
  common::H5mdReader r(path, particle_group);
  r.keepWrapCrossings(true);  // unwrapped positions keep their crossings as image counts
  const long nf = static_cast<long>(r.frames());
  if (nf == 0) throw std::invalid_argument("initial state '" + path + "' holds no complete frame");
  const long idx = frame < 0 ? nf + frame : frame;
  if (idx < 0 || idx >= nf)
    throw std::invalid_argument("initial state '" + path + "': frame " + std::to_string(frame) +
                                " requested, the file has " + std::to_string(nf) + " frames");
  if (!r.hasVelocity())
    throw std::invalid_argument("initial state '" + path + "' has no velocities (particles/" +
                                r.particleGroup() + "/velocity); an initial state needs them");
  const common::TrajectoryFrame in = r.readFrame(static_cast<std::size_t>(idx));
  for (const auto& [has_file, has_frame, name] :
       {std::tuple{r.hasVelocity(), in.hasVelocities(), "velocity"},
        std::tuple{r.hasCharge(), in.hasCharges(), "charge"}})
    if (has_file && !has_frame)
      throw std::invalid_argument("initial state '" + path + "' frame " + std::to_string(idx) +
                                  ": particles/" + r.particleGroup() + "/" + name +
                                  " has no sample at step " + std::to_string(in.step));
  Frame f = engineFrame(in);  // positions wrapped, images filled
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

namespace {

enum class StateFormat { H5md, LammpsData, Csv };

/// The format of an initial state file, told by its content (readInitialState).
StateFormat stateFormat(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    throw std::invalid_argument("initial state file '" + path + "' does not exist");
  if (S_ISDIR(st.st_mode))
    throw std::invalid_argument("initial state '" + path + "' is a directory, not a file");
  h5::silenceErrors();
  const htri_t is_h5 = H5Fis_hdf5(path.c_str());
  h5::lastError();  // clear whatever H5Fis_hdf5 left on the stack
  if (is_h5 > 0) return StateFormat::H5md;
  return isLammpsData(path) ? StateFormat::LammpsData : StateFormat::Csv;
}

}  // namespace

Frame readInitialState(const std::string& path, double box_if_csv) {
  switch (stateFormat(path)) {
    case StateFormat::H5md:
      return readInitialStateH5md(path);
    case StateFormat::LammpsData:
      return readInitialStateLammps(path);
    case StateFormat::Csv:
      break;
  }
  return readInitialStateCsv(path, box_if_csv);
}

OverlapPair deepestOverlap(const Frame& f) {
  const std::size_t n = f.size();
  const common::Box box{f.box};
  OverlapPair worst;
  auto consider = [&](std::size_t i, std::size_t j) {
    const double rx = box.minimumImage(f.x[i] - f.x[j]), ry = box.minimumImage(f.y[i] - f.y[j]),
                 rz = box.minimumImage(f.z[i] - f.z[j]);
    const double overlap = 1.0 - std::sqrt(rx * rx + ry * ry + rz * rz);
    if (overlap > worst.overlap) worst = {std::min(i, j), std::max(i, j), overlap};
  };
  // Cells of edge >= 1: two overlapping particles lie in the same or adjacent cells. At most
  // about 2N cells, so that a large dilute box costs no more than its particles.
  const long per_side = static_cast<long>(
      std::min(std::floor(f.box), std::cbrt(2.0 * static_cast<double>(n)) + 1.0));
  if (per_side < 3) {  // adjacent cells would repeat: compare every pair
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) consider(i, j);
    return worst;
  }
  const double cell = f.box / static_cast<double>(per_side);
  auto cellOf = [&](double x) {
    const long c = static_cast<long>(std::floor(x / cell)) % per_side;
    return c < 0 ? c + per_side : c;
  };
  constexpr std::size_t NONE = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> head(static_cast<std::size_t>(per_side * per_side * per_side), NONE),
      next(n, NONE);
  std::vector<long> cx(n), cy(n), cz(n);
  auto index = [per_side](long a, long b, long c) {
    return static_cast<std::size_t>(((a + per_side) % per_side * per_side +
                                     (b + per_side) % per_side) *
                                        per_side +
                                    (c + per_side) % per_side);
  };
  for (std::size_t i = 0; i < n; ++i) {
    cx[i] = cellOf(f.x[i]);
    cy[i] = cellOf(f.y[i]);
    cz[i] = cellOf(f.z[i]);
    std::size_t& h = head[index(cx[i], cy[i], cz[i])];
    next[i] = h;
    h = i;
  }
  for (std::size_t i = 0; i < n; ++i)
    for (long a = -1; a <= 1; ++a)
      for (long b = -1; b <= 1; ++b)
        for (long c = -1; c <= 1; ++c)
          for (std::size_t j = head[index(cx[i] + a, cy[i] + b, cz[i] + c)]; j != NONE; j = next[j])
            if (j > i) consider(i, j);
  return worst;
}

namespace {

/// " (run.toml:3:1)": where the configuration set `key`, for messages.
std::string setAt(const MdConfig& c, const std::string& key) {
  const auto it = c.origin.find(key);
  return it == c.origin.end() ? std::string() : " (" + it->second + ")";
}

/// A filling fraction read from a file agrees with a given one to this relative difference: a
/// box written with 4 significant digits (L = 23.97 for N = 2000 at phi = 0.076) still agrees.
constexpr double PHI_AGREEMENT = 1e-3;

}  // namespace

Frame prepareInitialState(MdConfig& c) {
  if (c.system.initial == "random") return randomInitialState(c);
  const std::string& path = c.system.initial;
  const StateFormat format = stateFormat(path);
  Frame f = format == StateFormat::H5md         ? readInitialStateH5md(path)
            : format == StateFormat::LammpsData ? readInitialStateLammps(path)
                                                : readCsvParticles(path);
  // N is the file's: a system.N the user gave must agree with it
  const std::size_t n = f.size();
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::invalid_argument("system.initial '" + path + "' holds " + std::to_string(n) +
                                " particles, more than system.N can count");
  if (static_cast<int>(n) != c.system.N && c.origin.count("system.N"))
    throw std::invalid_argument(
        "system.N = " + std::to_string(c.system.N) + setAt(c, "system.N") +
        " contradicts system.initial '" + path + "', which holds " + std::to_string(n) +
        " particles: N (and the box of an H5MD or LAMMPS data file) come from the file; leave "
        "system.N out or set it to " + std::to_string(n));
  c.system.N = static_cast<int>(n);
  if (format == StateFormat::Csv) {
    placeInBox(f, boxLength(c.system), path);  // a CSV has no box: system.phi sets it
  } else {
    // the box is the file's: phi = N pi / (6 L^3) is the one the run has
    const double phi = static_cast<double>(n) * M_PI / (6.0 * f.box * f.box * f.box);
    if (c.origin.count("system.phi") &&
        !(std::fabs(phi - c.system.phi) <= PHI_AGREEMENT * c.system.phi))
      throw std::invalid_argument(
          "system.phi = " + common::formatReal(c.system.phi) + setAt(c, "system.phi") +
          " contradicts system.initial '" + path + "': " + std::to_string(n) +
          " particles in its box L = " + common::formatReal(f.box) +
          " are phi = " + common::formatReal(phi) + "; leave system.phi out (the file's box is "
          "used) or set it to that value");
    if (!(phi > 0.0 && phi < 0.6))
      throw std::invalid_argument("system.initial '" + path + "': " + std::to_string(n) +
                                  " particles in its box L = " + common::formatReal(f.box) +
                                  " are phi = " + common::formatReal(phi) +
                                  ", outside the (0, 0.6) of system.phi");
    c.system.phi = phi;
  }
  f.step = 0;
  f.time = 0.0;
  const double tolerance = c.system.initialMaxOverlap(c.run.max_overlap);
  const OverlapPair deepest = deepestOverlap(f);
  if (deepest.overlap > tolerance)
    throw std::invalid_argument(
        "system.initial '" + path + "': particles " + std::to_string(deepest.i) + " and " +
        std::to_string(deepest.j) + " overlap by " + common::formatReal(deepest.overlap) +
        " (distance " + common::formatReal(1.0 - deepest.overlap) +
        "), deeper than system.initial_max_overlap = " + common::formatReal(tolerance) +
        (c.system.initial_max_overlap > 0.0 ? "" : " (auto: run.max_overlap)") +
        "; contacts up to it are accepted, as in a running gas. To continue a granagg run bit "
        "for bit, use granagg md --restart RUN (its folder) instead");
  assignInitialCharges(c, f);
  return f;
}

Frame randomInitialState(const MdConfig& c) {
  const int N = c.system.N;
  const double L = std::cbrt(N * M_PI / (6.0 * c.system.phi));
  Frame f;
  f.box = L;
  f.x.resize(N);
  f.y.resize(N);
  f.z.resize(N);
  // Random sequential insertion on a hash grid of cell >= 1 (a particle overlaps only particles in
  // the 27 surrounding cells). Deterministic: attempt k of particle i draws Philox(seed, i, k).
  const int nc = std::max(1, static_cast<int>(std::floor(L)));
  const double cell = L / nc;
  std::unordered_multimap<long, int> grid;
  grid.reserve(2 * N);
  common::Box box{L};
  auto key = [nc](int a, int b, int cc) {
    return (static_cast<long>((a + nc) % nc) * nc + (b + nc) % nc) * nc + (cc + nc) % nc;
  };
  const std::uint32_t max_attempts = 100000;
  for (int i = 0; i < N; ++i) {
    bool placed = false;
    for (std::uint32_t k = 0; k < max_attempts && !placed; ++k) {
      const auto r =
          philoxDraw(c.system.seed, RNG_INIT_POSITION, static_cast<std::uint32_t>(i), k, 0);
      const double px = uniform01(r[0]) * L, py = uniform01(r[1]) * L, pz = uniform01(r[2]) * L;
      const int cx = std::min(nc - 1, static_cast<int>(px / cell)),
                cy = std::min(nc - 1, static_cast<int>(py / cell)),
                cz = std::min(nc - 1, static_cast<int>(pz / cell));
      bool ok = true;
      for (int a = -1; a <= 1 && ok; ++a)
        for (int b = -1; b <= 1 && ok; ++b)
          for (int e = -1; e <= 1 && ok; ++e) {
            auto range = grid.equal_range(key(cx + a, cy + b, cz + e));
            for (auto it = range.first; it != range.second && ok; ++it) {
              const int j = it->second;
              const double rx = box.minimumImage(px - f.x[j]), ry = box.minimumImage(py - f.y[j]),
                           rz = box.minimumImage(pz - f.z[j]);
              ok = rx * rx + ry * ry + rz * rz >= 1.0;
            }
          }
      if (ok) {
        f.x[i] = px >= L ? 0.0 : px;
        f.y[i] = py >= L ? 0.0 : py;
        f.z[i] = pz >= L ? 0.0 : pz;
        grid.emplace(key(cx, cy, cz), i);
        placed = true;
      }
    }
    if (!placed)
      throw std::invalid_argument(
          "random insertion failed after " + std::to_string(max_attempts) +
          " attempts for particle " + std::to_string(i) +
          ": system.phi = " + common::formatReal(c.system.phi) +
          " is too dense for random sequential insertion (use phi < 0.3 or give an initial file).");
  }
  // Maxwell velocities (Box-Muller on Philox words), then zero momentum and T_g = temperature
  // exactly
  f.vx.resize(N);
  f.vy.resize(N);
  f.vz.resize(N);
  for (int i = 0; i < N; ++i) {
    const auto r =
        philoxDraw(c.system.seed, RNG_INIT_VELOCITY, static_cast<std::uint32_t>(i), 0, 0);
    const double u1 = uniform01(r[0]), u2 = uniform01(r[1]), u3 = uniform01(r[2]),
                 u4 = uniform01(r[3]);
    const double a = std::sqrt(-2.0 * std::log(u1)), b = std::sqrt(-2.0 * std::log(u3));
    f.vx[i] = a * std::cos(2.0 * M_PI * u2);
    f.vy[i] = a * std::sin(2.0 * M_PI * u2);
    f.vz[i] = b * std::cos(2.0 * M_PI * u4);
  }
  double m[3] = {0, 0, 0};
  for (int i = 0; i < N; ++i) {
    m[0] += f.vx[i];
    m[1] += f.vy[i];
    m[2] += f.vz[i];
  }
  double s2 = 0.0;
  for (int i = 0; i < N; ++i) {
    f.vx[i] -= m[0] / N;
    f.vy[i] -= m[1] / N;
    f.vz[i] -= m[2] / N;
    s2 += f.vx[i] * f.vx[i] + f.vy[i] * f.vy[i] + f.vz[i] * f.vz[i];
  }
  const double scale = std::sqrt(c.system.temperature * 3.0 * N / s2);
  for (int i = 0; i < N; ++i) {
    f.vx[i] *= scale;
    f.vy[i] *= scale;
    f.vz[i] *= scale;
  }
  f.charge.assign(N, 0.0);
  assignInitialCharges(c, f);
  f.ix.assign(N, 0);
  f.iy.assign(N, 0);
  f.iz.assign(N, 0);
  return f;
}

void assignInitialCharges(const MdConfig& c, Frame& f) {
  const std::size_t N = f.size();
  const std::string& how = c.charging.initial;
  if (how == "file") {
    if (f.charge.size() != N)
      throw std::invalid_argument(
          "charging.initial = \"file\" but the initial state holds no charges");
    return;
  }
  f.charge.assign(N, 0.0);
  if (how == "neutral") return;
  if (how == "monopolar") {
    f.charge.assign(N, c.charging.q0);
    return;
  }
  if (how != "bipolar")
    throw std::invalid_argument("charging.initial = \"" + how +
                                "\" is not one of neutral, monopolar, bipolar, file");
  // bipolar: a random half +q0, the other half -q0 (exactly zero net; for odd N one particle stays
  // neutral). The halves come from ordering particles by a Philox key per particle.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> key(N);
  for (std::size_t i = 0; i < N; ++i)
    key[i] = {philoxDraw(c.system.seed, RNG_INIT_CHARGE, static_cast<std::uint32_t>(i), 0, 0)[0],
              static_cast<std::uint32_t>(i)};
  std::sort(key.begin(), key.end());
  for (std::size_t k = 0; k < 2 * (N / 2); ++k)
    f.charge[key[k].second] = k < N / 2 ? c.charging.q0 : -c.charging.q0;
}

}  // namespace granagg::md
