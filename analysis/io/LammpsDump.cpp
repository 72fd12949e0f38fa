#include "analysis/io/LammpsDump.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "common/Box.h"
#include "common/Csv.h"
#include "common/Strings.h"

namespace granagg::analysis {

LammpsDump::LammpsDump(const std::string& path, double dt) : m_path(path), m_dt(dt), m_in(path) {
  if (!m_in) throw std::invalid_argument("cannot open LAMMPS dump '" + path + "'");
  if (m_in.seekg(0, std::ios::end)) m_bytes = static_cast<std::int64_t>(m_in.tellg());
  m_in.clear();
  m_in.seekg(0, std::ios::beg);
  if (!(dt >= 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("the LAMMPS timestep dt must be >= 0, got " +
                                common::formatReal(dt));
}

void LammpsDump::error(const std::string& what) const { errorAt(m_line, what); }

void LammpsDump::errorAt(std::size_t line, const std::string& what) const {
  throw TrajectoryError(m_path, m_frame, what + " (line " + std::to_string(line) + ")");
}

void LammpsDump::countError(const std::string& what) const {
  // In frame 0 the file is not a dump whose header can be believed: bad input (exit 2). In a
  // later frame it is a damaged tail, which --allow-partial may leave out like any other.
  if (m_frame == 0) throw std::invalid_argument("LAMMPS dump '" + m_path + "': " + what);
  error(what);
}

namespace {

/// A line for an error message: at most `max` characters, quoted; a line with bytes that are not
/// printable text is not echoed (a binary file would print garbage to the terminal).
std::string quoted(const std::string& line, std::size_t max) {
  for (unsigned char c : line)
    if ((c < 0x20 && c != '\t') || c >= 0x7f) return "binary data (not a text dump)";
  return "'" + (line.size() > max ? line.substr(0, max) + "..." : line) + "'";
}

}  // namespace

bool LammpsDump::getLine(std::string& line) {
  if (!std::getline(m_in, line)) return false;
  ++m_line;
  m_offset += line.size() + 1;  // (tellg is -1 once a last line without newline set eof)
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return true;
}

bool LammpsDump::next(Frame& f) {
  std::string line;
  // Skip blank lines between frames; a clean end of file here is the regular end.
  do {
    if (!getLine(line)) return false;
  } while (common::trim(line).empty());
  const Header h = readHeader(line);
  const Columns c = columns(h.atoms_line);
  const Atoms a = readAtoms(h, c);
  fill(h, c, a, f);
  ++m_frame;
  return true;
}

LammpsDump::Header LammpsDump::readHeader(std::string& line) {
  Header h;
  bool have_step = false, have_n = false, have_box = false;
  double hi[3] = {0, 0, 0};
  auto need = [&](std::string& l, const char* what) {
    if (!getLine(l))
      error(std::string("file ends inside the frame header (expected ") + what + ")");
  };
  while (true) {
    if (line.rfind("ITEM:", 0) != 0) error("expected an 'ITEM:' line, found " + quoted(line, 60));
    const std::string item = common::trim(line.substr(5));
    if (item == "TIMESTEP") {
      need(line, "the timestep");
      char* end = nullptr;
      errno = 0;
      h.step = std::strtoll(line.c_str(), &end, 10);
      if (errno || end == line.c_str()) error("bad timestep " + quoted(line, 40));
      have_step = true;
    } else if (item == "TIME") {
      need(line, "the time");
      if (!common::parseReal(common::trim(line), h.time)) error("bad time " + quoted(line, 40));
      h.have_time = true;
    } else if (item == "NUMBER OF ATOMS") {
      need(line, "the number of atoms");
      char* end = nullptr;
      errno = 0;
      const long long v = std::strtoll(line.c_str(), &end, 10);
      if (errno || end == line.c_str() || v <= 0)
        countError("bad NUMBER OF ATOMS " + quoted(line, 40) + " (line " +
                   std::to_string(m_line) + "; expected an integer >= 1)");
      m_count_line = m_line;
      h.atoms = static_cast<std::size_t>(v);
      have_n = true;
    } else if (item.rfind("BOX BOUNDS", 0) == 0) {
      const auto flags = common::split(common::trim(item.substr(10)), ' ');
      if (std::find(flags.begin(), flags.end(), "xy") != flags.end())
        error("triclinic boxes are not supported");
      for (const auto& fl : flags)
        if (!fl.empty() && fl != "pp")
          error("box boundary '" + fl + "' is not periodic ('pp' needed)");
      for (int d = 0; d < 3; ++d) {
        need(line, "the box bounds");
        std::istringstream is(line);
        if (!(is >> h.lo[d] >> hi[d]) || !(hi[d] > h.lo[d]) || !std::isfinite(hi[d] - h.lo[d]))
          error("bad box bounds " + quoted(line, 60));
      }
      have_box = true;
    } else if (item.rfind("ATOMS", 0) == 0) {
      break;
    } else if (item == "UNITS") {
      need(line, "the units");
    } else {
      error("unknown item '" + item + "'");
    }
    need(line, "ITEM: ATOMS");
  }
  if (!have_step || !have_n || !have_box)
    error("frame header lacks TIMESTEP, NUMBER OF ATOMS or BOX BOUNDS");
  if (m_n == 0) m_n = h.atoms;
  if (h.atoms != m_n)
    error("has " + std::to_string(h.atoms) + " atoms, the first frame had " + std::to_string(m_n));
  h.L = hi[0] - h.lo[0];
  for (int d = 1; d < 3; ++d)
    if (std::fabs((hi[d] - h.lo[d]) - h.L) > 1e-9 * h.L)
      error("the box is not cubic; only cubic boxes are supported");
  h.atoms_line = line;
  return h;
}

LammpsDump::Columns LammpsDump::columns(const std::string& atoms_line) const {
  std::vector<std::string> cols;
  for (const auto& c :
       common::split(common::trim(atoms_line.substr(atoms_line.find("ATOMS") + 5)), ' '))
    if (!c.empty()) cols.push_back(c);
  auto find = [&](const char* name) {
    const auto it = std::find(cols.begin(), cols.end(), name);
    return it == cols.end() ? -1 : static_cast<int>(it - cols.begin());
  };
  Columns c;
  c.count = cols.size();
  c.id = find("id");
  const char* names[3][3] = {{"x", "y", "z"}, {"xu", "yu", "zu"}, {"xs", "ys", "zs"}};
  int found = -1;
  for (int k = 0; k < 3 && found < 0; ++k)
    if (find(names[k][0]) >= 0) found = k;
  if (found < 0) error("ATOMS columns have no positions (x y z, xu yu zu or xs ys zs)");
  c.kind = static_cast<Columns::Kind>(found);
  for (int d = 0; d < 3; ++d) {
    c.pos[d] = find(names[found][d]);
    if (c.pos[d] < 0) error(std::string("ATOMS columns lack ") + names[found][d]);
    c.img[d] = find((std::string("i") + "xyz"[d]).c_str());
    c.vel[d] = find((std::string("v") + "xyz"[d]).c_str());
  }
  c.images = c.img[0] >= 0 && c.img[1] >= 0 && c.img[2] >= 0;
  c.velocities = c.vel[0] >= 0 && c.vel[1] >= 0 && c.vel[2] >= 0;
  c.q = find("q");
  return c;
}

LammpsDump::Atoms LammpsDump::readAtoms(const Header& h, const Columns& c) {
  const std::size_t n = h.atoms;
  // Before anything is sized from the header: an atom line holds c.count values, each of at least
  // one character and a separator (or the newline), so the rest of the file bounds the count.
  if (m_bytes >= 0) {
    const double left = std::max(0.0, static_cast<double>(m_bytes) - static_cast<double>(m_offset));
    const double most = left / (2.0 * static_cast<double>(c.count));
    if (static_cast<double>(n) > most)
      countError("NUMBER OF ATOMS = " + std::to_string(n) + " (line " +
                 std::to_string(m_count_line) + "), but the rest of the file has room for at " +
                 "most " + std::to_string(static_cast<long long>(most)) + " atom lines of " +
                 std::to_string(c.count) + " values (a corrupt, truncated or miscounted dump?)");
  }
  Atoms a;
  a.ids.resize(n);
  a.pos.resize(3 * n);
  a.vel.resize(c.velocities ? 3 * n : 0);
  a.q.resize(c.q >= 0 ? n : 0);
  a.img.assign(3 * n, 0);
  a.line_of.resize(n);
  std::vector<double> values(c.count);
  std::string line;
  for (std::size_t k = 0; k < n; ++k) {
    if (!getLine(line))
      error("file ends after " + std::to_string(k) + " of " + std::to_string(n) +
            " atoms (truncated dump?)");
    a.line_of[k] = m_line;
    const char* p = line.c_str();
    for (std::size_t col = 0; col < c.count; ++col) {
      char* end = nullptr;
      values[col] = std::strtod(p, &end);
      if (end == p)
        error("atom line has " + std::to_string(col) + " of " + std::to_string(c.count) +
              " values: " + quoted(line, 80));
      p = end;
    }
    // Integers are range-checked before the cast: a double out of range converts undefined.
    if (c.id >= 0 && !(std::fabs(values[c.id]) <= 9007199254740992.0 &&  // 2^53: exact in double
                       values[c.id] == std::floor(values[c.id])))
      error("atom id " + common::formatReal(values[c.id]) + " is not an integer");
    a.ids[k] = c.id >= 0 ? static_cast<std::int64_t>(values[c.id]) : static_cast<std::int64_t>(k);
    for (int d = 0; d < 3; ++d) {
      const double v = values[c.pos[d]];
      a.pos[3 * k + d] = c.kind == Columns::SCALED ? v * h.L : v - h.lo[d];
      if (c.images && c.kind != Columns::UNWRAPPED) {
        const double im = values[c.img[d]];
        if (!(std::fabs(im) <= 1073741824.0 && im == std::floor(im)))  // |image| <= 2^30
          error("image flag " + common::formatReal(im) + " is not an integer of at most 2^30");
        a.img[3 * k + d] = static_cast<std::int32_t>(im);
      }
      if (c.velocities) a.vel[3 * k + d] = values[c.vel[d]];
    }
    if (c.q >= 0) a.q[k] = values[c.q];
  }
  return a;
}

void LammpsDump::fill(const Header& h, const Columns& c, const Atoms& a, Frame& f) const {
  const std::size_t n = h.atoms;
  // Sort by id (LAMMPS writes atoms in processor order).
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),  // stable: a repeated id is named at its 2nd line
                   [&](std::size_t x, std::size_t y) { return a.ids[x] < a.ids[y]; });
  for (std::size_t k = 1; k < n; ++k)
    if (a.ids[order[k]] == a.ids[order[k - 1]])
      errorAt(a.line_of[order[k]], "atom id " + std::to_string(a.ids[order[k]]) +
                                       " appears twice (also on line " +
                                       std::to_string(a.line_of[order[k - 1]]) + ")");

  const common::Box box{h.L};
  const bool images = c.images || c.kind == Columns::UNWRAPPED;
  f.index = m_frame;
  f.step = h.step;
  f.time = h.have_time
               ? h.time
               : (m_dt > 0 ? static_cast<double>(h.step) * m_dt : static_cast<double>(h.step));
  f.box = h.L;
  f.position.resize(3 * n);
  f.image.assign(images ? 3 * n : 0, 0);
  f.velocity.resize(c.velocities ? 3 * n : 0);
  f.charge.resize(c.q >= 0 ? n : 0);
  f.id.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = order[k];
    f.id[k] = a.ids[i];
    for (int d = 0; d < 3; ++d) {
      double x = a.pos[3 * i + d];
      if (!std::isfinite(x))
        errorAt(a.line_of[i], "atom " + std::to_string(a.ids[i]) + " has a non-finite position");
      // the image count must stay an int: 1e9 box lengths is beyond any physical trajectory
      if (std::fabs(x) > 1e9 * h.L)
        errorAt(a.line_of[i], "atom " + std::to_string(a.ids[i]) + " lies " +
                                  common::formatReal(x / h.L) + " box lengths from the box");
      const int shift = box.wrap(x);
      f.position[3 * k + d] = x;
      if (images) f.image[3 * k + d] = a.img[3 * i + d] + shift;
      if (c.velocities) f.velocity[3 * k + d] = a.vel[3 * i + d];
    }
    if (c.q >= 0) f.charge[k] = a.q[i];
  }
}

}  // namespace granagg::analysis
