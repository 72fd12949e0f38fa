#pragma once
/// \file InitialState.h
/// User-given initial states (`[system] initial = "file"` in the run configuration) and the
/// periodic wrapping shared by the readers and the H5MD writer. Reduced units: lengths in
/// particle diameters d, velocities in sqrt(T0/m), charges in the engine's reduced charge unit.
///
/// CSV input (common::readCsv: '#' lines are comments, one header row, comma separated):
///
///     # my initial state
///     x,y,z,vx,vy,vz,q
///     0.5,1.25,3.0,0.1,-0.3,0.02,0.0
///     ...
///
/// Columns x,y,z,vx,vy,vz are required, q (charge) is optional (zero otherwise), in any order;
/// other columns are rejected. A CSV has no box: the caller passes L (from N and phi); positions
/// outside [0, L) are wrapped and the crossings recorded as image counts.
///
/// H5MD input: any H5MD 1.1 file common::H5mdReader accepts (ours or another engine's); the last
/// frame by default. Velocities are required; missing charges are zero; the box is the file's.
///
/// LAMMPS data file (the `read_data` / `write_data` format), so that one starting configuration
/// runs in LAMMPS and in granagg: a title line, a header with "N atoms" and a cubic box ("xlo xhi"
/// etc.; no tilt factors), an `Atoms` section and a `Velocities` section (required). Atom styles,
/// named by the comment after `Atoms` as write_data writes it, or else told by the column count:
///
///     sphere   id type diameter density x y z [ix iy iz]
///     charge   id type q x y z [ix iy iz]
///     atomic   id type x y z [ix iy iz]
///     hybrid   id type x y z diameter density q [ix iy iz]   (atom_style hybrid sphere charge)
///
/// granagg's particles are unit spheres of unit mass: a diameter must be 1 and a density 6/pi
/// (sphere), a type's mass in `Masses` 1 (charge, atomic). Atoms are ordered by id (ids need not
/// be contiguous); velocities are matched by id (angular velocities are ignored); positions are
/// shifted by -xlo and wrapped, image flags added. Charges are taken as written, in granagg's
/// reduced charge unit (K q_i q_j / r is the pair energy in T0).
#include <cstdint>
#include <string>

#include "common/Box.h"
#include "common/TrajectoryFrame.h"
#include "md/config/MdConfig.h"
#include "md/io/Frame.h"

namespace granagg::md {

/// Reads an initial state from `path`, detected by content: an HDF5 file is read as H5MD (its
/// last frame, its own box; `box_if_csv` is ignored), a file whose header holds an "N atoms" line
/// as a LAMMPS data file (its own box), anything else as CSV in a cubic box of edge `box_if_csv`
/// (> 0, reduced length units). The result has N >= 2 particles, finite values and
/// positions wrapped into [0, L) with image counts. Step and time are 0 for CSV and the frame's
/// for H5MD (the engine may reset them).
/// Throws std::invalid_argument for bad values (naming the file, line or particle index) and for
/// a missing file; std::runtime_error for unreadable or malformed H5MD files.
Frame readInitialState(const std::string& path, double box_if_csv);

/// CSV branch of readInitialState: columns as described above, box edge `box` > 0.
/// Errors name the file and line ("init.csv:7: particle 4: vx = nan is not finite").
Frame readInitialStateCsv(const std::string& path, double box);

/// LAMMPS data file branch of readInitialState (format above). Errors name the file and line
/// ("state.data:14: atom 3: diameter 2 (granagg's particles have diameter 1)").
Frame readInitialStateLammps(const std::string& path);

/// Whether `path` looks like a LAMMPS data file: an "N atoms" line among its first 50 lines.
bool isLammpsData(const std::string& path);

/// H5MD branch of readInitialState: frame `frame` (negative counts from the end, -1 = last) of
/// the particle group `particle_group` ("" = the first group under /particles).
Frame readInitialStateH5md(const std::string& path, long frame = -1,
                           const std::string& particle_group = "");

/// The deepest overlap of a state: particles i < j at distance r = 1 - overlap (diameter 1), or
/// overlap <= 0 (and i = j = 0) when no two particles overlap.
struct OverlapPair {
  std::size_t i = 0, j = 0;
  double overlap = 0.0;  ///< 1 - r, in particle diameters
};

/// The pair of `state` whose overlap is deepest (minimum image in the cubic box state.box),
/// found on a cell grid of edge >= 1 in O(N).
OverlapPair deepestOverlap(const Frame& state);

/// The initial state of a new run of `config`: randomInitialState for system.initial = "random",
/// else the file (readInitialState's formats), with the charges of charging.initial, and `config`
/// made to say what the run has. N is the file's particle count. The box of an H5MD or LAMMPS
/// data file is the file's, and system.phi becomes N pi / (6 L^3); a CSV has no box: system.phi
/// and N set it, L = (N pi / (6 phi))^(1/3). A system.N or system.phi the user gave
/// (config.origin) that contradicts the file is refused naming both values (phi agrees within
/// a relative 1e-3, so a box written to 4 digits does); defaults are replaced. A new run's clock
/// starts at its initial state: step and time are 0 whatever frame the file held (run.t_end is
/// the time run from it). A file may hold contacts, as any frame of a running gas does, up to
/// system.initial_max_overlap ("auto": run.max_overlap, which no step of a run exceeds); a
/// deeper overlap is refused naming the pair, the overlap and that key, and pointing to
/// `granagg md --restart RUN`, which continues a run bit for bit. Throws std::invalid_argument.
Frame prepareInitialState(MdConfig& config);

/// Random non-overlapping positions at the configured phi (random sequential insertion),
/// Maxwell velocities rescaled to T_g = temperature exactly with zero total momentum, and the
/// charges of config.charging.initial (docs/model.md section 5). Deterministic in
/// config.system.seed (Philox streams RNG_INIT_*, md/rng/RngStreams.h). Throws
/// std::invalid_argument when phi is too dense for insertion.
Frame randomInitialState(const MdConfig& config);

/// Sets the charges of an initial state from config.charging.initial: "neutral" (0), "monopolar"
/// (+q0), "bipolar" (a random half +q0, the other -q0: zero net charge; Philox stream
/// RNG_INIT_CHARGE) or "file" (kept; throws if the state has none).
void assignInitialCharges(const MdConfig& config, Frame& state);

/// Wraps one coordinate into [0, box), adding the box lengths removed to `image`
/// (common/Box.h).
using common::wrapCoordinate;

/// Wraps every position of `frame` into [0, frame.box) with wrapCoordinate; missing image arrays
/// (empty) are created as zeros first. Throws std::invalid_argument naming the particle index if
/// a position is not finite or the box is not positive.
void wrapIntoBox(Frame& frame);

/// A frame read from a trajectory file (common::H5mdReader) in the engine's layout, one array per
/// component: absent charges and image counts become zeros, absent velocities stay empty.
Frame engineFrame(const common::TrajectoryFrame& frame);

}  // namespace granagg::md
