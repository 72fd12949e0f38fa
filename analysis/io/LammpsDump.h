#pragma once
/// \file LammpsDump.h
/// Streams frames from a LAMMPS text dump (`dump custom`, https://docs.lammps.org/dump.html):
///
///     ITEM: TIME                  (optional, `dump_modify time yes`)
///     ITEM: TIMESTEP
///     ITEM: NUMBER OF ATOMS
///     ITEM: BOX BOUNDS pp pp pp   (orthogonal, periodic, cubic)
///     ITEM: ATOMS id x y z ix iy iz vx vy vz q
///
/// Columns: id; x y z (wrapped) or xu yu zu (unwrapped) or xs ys zs (scaled); optional ix iy iz,
/// vx vy vz, q; others are ignored. Atoms are sorted by id. Positions are shifted by the box's
/// lower bound and wrapped into [0, L), the shift going into the image count.
#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "analysis/io/TrajectoryReader.h"

namespace granagg::analysis {

class LammpsDump final : public TrajectoryReader {
 public:
  /// `dt` turns timesteps into times when the dump has no ITEM: TIME (0: time = timestep).
  explicit LammpsDump(const std::string& path, double dt = 0.0);
  bool next(Frame& f) override;
  std::size_t frameCountHint() const override { return 0; }
  const std::map<std::string, std::string>& parameters() const override { return m_params; }
  const std::string& path() const override { return m_path; }
  std::string format() const override { return "lammps-dump"; }

 private:
  [[noreturn]] void error(const std::string& what) const;  ///< at the line just read
  [[noreturn]] void errorAt(std::size_t line, const std::string& what) const;
  bool getLine(std::string& line);

  /// A frame's header, read up to its ITEM: ATOMS line (kept in `atoms_line`).
  struct Header {
    std::int64_t step = 0;
    double time = 0.0;
    bool have_time = false;
    std::size_t atoms = 0;
    double lo[3] = {0, 0, 0};
    double L = 0.0;  // the cubic box's edge
    std::string atoms_line;
  };
  /// Where each quantity sits among the ATOMS columns (-1: absent).
  struct Columns {
    std::size_t count = 0;
    int id = -1, q = -1;
    int pos[3] = {-1, -1, -1}, img[3] = {-1, -1, -1}, vel[3] = {-1, -1, -1};
    enum Kind { WRAPPED, UNWRAPPED, SCALED } kind = WRAPPED;  // x y z, xu yu zu, xs ys zs
    bool images = false, velocities = false;
  };
  /// The atoms as read, in file order.
  struct Atoms {
    std::vector<std::int64_t> ids;
    std::vector<double> pos, vel, q;
    std::vector<std::int32_t> img;
    std::vector<std::size_t> line_of;  // each atom's line, for errors found after reading
  };
  /// A header count that cannot be right: std::invalid_argument in frame 0, else error().
  [[noreturn]] void countError(const std::string& what) const;
  /// Reads the header of a frame whose first line is `line`.
  Header readHeader(std::string& line);
  Columns columns(const std::string& atoms_line) const;
  Atoms readAtoms(const Header& h, const Columns& c);
  /// The atoms sorted by id (ids unique), wrapped into the box, into f.
  void fill(const Header& h, const Columns& c, const Atoms& a, Frame& f) const;

  std::string m_path;
  double m_dt;
  std::ifstream m_in;
  std::int64_t m_bytes = -1;  // file size (-1: not seekable); bounds the atoms a header claims
  std::size_t m_offset = 0;      // bytes read so far
  std::size_t m_count_line = 0;  // the line of the NUMBER OF ATOMS value, for errors
  std::size_t m_frame = 0, m_line = 0;
  std::size_t m_n = 0;  // atoms of the first frame: later frames must match
  std::map<std::string, std::string> m_params;
};

}  // namespace granagg::analysis
