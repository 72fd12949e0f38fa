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
#include <fstream>
#include <map>
#include <string>

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

  std::string m_path;
  double m_dt;
  std::ifstream m_in;
  std::size_t m_frame = 0, m_line = 0;
  std::size_t m_n = 0;  // atoms of the first frame: later frames must match
  std::map<std::string, std::string> m_params;
};

}  // namespace granagg::analysis
