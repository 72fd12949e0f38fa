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
  if (!(dt >= 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("the LAMMPS timestep dt must be >= 0, got " +
                                common::formatReal(dt));
}

void LammpsDump::error(const std::string& what) const { errorAt(m_line, what); }

void LammpsDump::errorAt(std::size_t line, const std::string& what) const {
  throw TrajectoryError(m_path, m_frame, what + " (line " + std::to_string(line) + ")");
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
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return true;
}

bool LammpsDump::next(Frame& f) {
  std::string line;
  // Skip blank lines between frames; a clean end of file here is the regular end.
  do {
    if (!getLine(line)) return false;
  } while (common::trim(line).empty());

  bool have_step = false, have_time = false, have_n = false, have_box = false;
  double time = 0.0;
  std::int64_t step = 0;
  std::size_t n = 0;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
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
      step = std::strtoll(line.c_str(), &end, 10);
      if (errno || end == line.c_str()) error("bad timestep " + quoted(line, 40));
      have_step = true;
    } else if (item == "TIME") {
      need(line, "the time");
      if (!common::parseReal(common::trim(line), time)) error("bad time " + quoted(line, 40));
      have_time = true;
    } else if (item == "NUMBER OF ATOMS") {
      need(line, "the number of atoms");
      char* end = nullptr;
      const long long v = std::strtoll(line.c_str(), &end, 10);
      if (end == line.c_str() || v <= 0) error("bad number of atoms " + quoted(line, 40));
      n = static_cast<std::size_t>(v);
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
        if (!(is >> lo[d] >> hi[d]) || !(hi[d] > lo[d]))
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
  if (m_n == 0) m_n = n;
  if (n != m_n)
    error("has " + std::to_string(n) + " atoms, the first frame had " + std::to_string(m_n));
  const double L = hi[0] - lo[0];
  for (int d = 1; d < 3; ++d)
    if (std::fabs((hi[d] - lo[d]) - L) > 1e-9 * L)
      error("the box is not cubic; only cubic boxes are supported");

  // Column layout.
  std::vector<std::string> cols;
  for (const auto& c : common::split(common::trim(line.substr(line.find("ATOMS") + 5)), ' '))
    if (!c.empty()) cols.push_back(c);
  auto find = [&](const char* name) {
    const auto it = std::find(cols.begin(), cols.end(), name);
    return it == cols.end() ? -1 : static_cast<int>(it - cols.begin());
  };
  const int c_id = find("id");
  int c_pos[3], c_img[3], c_vel[3];
  enum { WRAPPED, UNWRAPPED, SCALED } kind = WRAPPED;
  const char* names[3][3] = {{"x", "y", "z"}, {"xu", "yu", "zu"}, {"xs", "ys", "zs"}};
  int found = -1;
  for (int k = 0; k < 3 && found < 0; ++k)
    if (find(names[k][0]) >= 0) found = k;
  if (found < 0) error("ATOMS columns have no positions (x y z, xu yu zu or xs ys zs)");
  kind = static_cast<decltype(kind)>(found);
  for (int d = 0; d < 3; ++d) {
    c_pos[d] = find(names[found][d]);
    if (c_pos[d] < 0) error(std::string("ATOMS columns lack ") + names[found][d]);
    c_img[d] = find((std::string("i") + "xyz"[d]).c_str());
    c_vel[d] = find((std::string("v") + "xyz"[d]).c_str());
  }
  const bool has_img = c_img[0] >= 0 && c_img[1] >= 0 && c_img[2] >= 0;
  const bool has_vel = c_vel[0] >= 0 && c_vel[1] >= 0 && c_vel[2] >= 0;
  const int c_q = find("q");

  std::vector<std::int64_t> ids(n);
  std::vector<double> pos(3 * n), vel(has_vel ? 3 * n : 0), q(c_q >= 0 ? n : 0);
  std::vector<std::int32_t> img(3 * n, 0);
  std::vector<double> values(cols.size());
  std::vector<std::size_t> line_of(n);  // each atom's line, for errors found after reading
  for (std::size_t a = 0; a < n; ++a) {
    if (!getLine(line))
      error("file ends after " + std::to_string(a) + " of " + std::to_string(n) +
            " atoms (truncated dump?)");
    line_of[a] = m_line;
    const char* p = line.c_str();
    for (std::size_t c = 0; c < cols.size(); ++c) {
      char* end = nullptr;
      values[c] = std::strtod(p, &end);
      if (end == p)
        error("atom line has " + std::to_string(c) + " of " + std::to_string(cols.size()) +
              " values: " + quoted(line, 80));
      p = end;
    }
    ids[a] = c_id >= 0 ? static_cast<std::int64_t>(values[c_id]) : static_cast<std::int64_t>(a);
    for (int d = 0; d < 3; ++d) {
      const double v = values[c_pos[d]];
      pos[3 * a + d] = kind == SCALED ? v * L : v - lo[d];
      if (has_img && kind != UNWRAPPED)
        img[3 * a + d] = static_cast<std::int32_t>(values[c_img[d]]);
      if (has_vel) vel[3 * a + d] = values[c_vel[d]];
    }
    if (c_q >= 0) q[a] = values[c_q];
  }

  // Sort by id (LAMMPS writes atoms in processor order).
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),  // stable: a repeated id is named at its 2nd line
                   [&](std::size_t a, std::size_t b) { return ids[a] < ids[b]; });
  for (std::size_t k = 1; k < n; ++k)
    if (ids[order[k]] == ids[order[k - 1]])
      errorAt(line_of[order[k]], "atom id " + std::to_string(ids[order[k]]) +
                                     " appears twice (also on line " +
                                     std::to_string(line_of[order[k - 1]]) + ")");

  const common::Box box{L};
  const bool images = has_img || kind == UNWRAPPED;
  f.index = m_frame;
  f.step = step;
  f.time =
      have_time ? time : (m_dt > 0 ? static_cast<double>(step) * m_dt : static_cast<double>(step));
  f.box = L;
  f.position.resize(3 * n);
  f.image.assign(images ? 3 * n : 0, 0);
  f.velocity.resize(has_vel ? 3 * n : 0);
  f.charge.resize(c_q >= 0 ? n : 0);
  f.id.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = order[k];
    f.id[k] = ids[a];
    for (int d = 0; d < 3; ++d) {
      double x = pos[3 * a + d];
      if (!std::isfinite(x))
        errorAt(line_of[a], "atom " + std::to_string(ids[a]) + " has a non-finite position");
      const int shift = box.wrap(x);
      f.position[3 * k + d] = x;
      if (images) f.image[3 * k + d] = img[3 * a + d] + shift;
      if (has_vel) f.velocity[3 * k + d] = vel[3 * a + d];
    }
    if (c_q >= 0) f.charge[k] = q[a];
  }
  ++m_frame;
  return true;
}

}  // namespace granagg::analysis
