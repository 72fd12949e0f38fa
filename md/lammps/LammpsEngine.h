#pragma once
/// \file LammpsEngine.h
/// granagg's model on LAMMPS across MPI ranks behind md::RunEngine (md/engine/RunEngine.h), so
/// that md::Simulation drives it exactly as it drives granagg's own engine: the H5MD trajectory,
/// /granagg/observables, checkpoints, the log lines and the stop signal (granagg-lammps,
/// cli/lammps/main.cpp; docs/lammps.md). The engine owns the LAMMPS instance with fix
/// granagg/charging (FixCharging.h) and feeds it the translated input (LammpsInput.h).
///
/// Life cycle (every call collective: every rank makes it, in the same order):
/// - Constructed for a new run (rank 0 builds the initial state and the translation; an error
///   there throws on every rank, std::invalid_argument for bad input) or from a checkpoint. No
///   file is written and no command run: the output folder is not yet checked and locked.
/// - begin(folder), once Simulation holds the folder: rank 0 writes initial.data and lammps.in;
///   LAMMPS logs to log.lammps (appended on a restart), runs the input and `run 0` (the setup:
///   forces and energies of the first state).
/// - run(n): `run n pre no post no`. No setup between chunks, so chunks change no result: the
///   chunked run is bit-identical to one `run`. Under rRESPA (coulomb.every > 1, LammpsInput.h)
///   LAMMPS refuses `pre no`: `run n post no`, whose setup recomputes the forces, and the fix
///   puts the kept forces of each level back (FixCharging.h). Steps and dt are LAMMPS's outer
///   steps there; frames and checkpoints fall on them.
/// - frame(), forces(): gathered to rank 0 in id order (below). observables(): sums over ranks
///   (MPI_Allreduce) and the fix's contact statistics; the Coulomb energy is LAMMPS's
///   (pair coul/long + kspace, `pe`).
/// - saveCheckpoint(): `write_restart` into a new file, then `run 0 post no` (write_restart moves
///   atoms between ranks, so the next run needs LAMMPS's setup; the fix puts the forces of the
///   state back there, FixCharging.h), then rank 0 names the file in checkpoint.toml.
///
/// Gathering to rank 0. A frame holds id, position, image, velocity and charge of every particle
/// (11 doubles each; 3 more with forces) in rank 0's memory, and the Frame built from it as much
/// again: about 1.6 GB at N = 1e7, plus the HDF5 write. Frames are few (log-spaced, tens per
/// run) and a gather moves that once over the interconnect (about a second at 1e7), so up to
/// ~1e7 particles this costs little against the run. MPI_Gatherv's int counts limit one gather to
/// ~1.6e8 particles; beyond ~1e7 rank 0's memory is the limit, and per-rank (parallel HDF5)
/// output would be needed.
///
/// Checkpoint files in the folder:
///     checkpoint.toml             the run's fields (configuration, frame counters), N, box,
///                                 the Coulomb design's sum q^2 and the name of:
///     checkpoint-<step>.restart   LAMMPS's restart file: the atoms (with the fix's per-atom
///                                 forces) and the fix's collision count
/// The restart file is written under a new name, then checkpoint.toml is replaced atomically
/// (written aside, fsync'ed, renamed) to name it, then older restart files are removed: a crash
/// at any point leaves a checkpoint.toml that names a complete restart file.
#include <mpi.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "md/config/MdConfig.h"
#include "md/engine/RunEngine.h"
#include "md/io/Checkpoint.h"
#include "md/lammps/LammpsInput.h"

namespace LAMMPS_NS {
class LAMMPS;
}

namespace granagg::md::lammps {

class FixCharging;

/// What a granagg-lammps checkpoint holds besides the LAMMPS restart file.
struct LammpsCheckpoint {
  std::string restart_file;    ///< its name in the folder
  std::int64_t step = 0;       ///< the step it was written at
  std::size_t N = 0;
  double box = 0.0;            ///< edge L of the periodic cube
  double sum_q2_design = 0.0;  ///< CoulombSetup::sum_q2_design of the run (0 without Coulomb)
  bool record_collisions = false;  ///< the run logs its collisions (collisions.csv)
  RunFields run_fields;            ///< config_toml, seed, frames_written
};

/// The name of the checkpoint file in a run's folder.
inline constexpr const char* LAMMPS_CHECKPOINT_FILE = "checkpoint.toml";

/// Reads `folder`/checkpoint.toml (collective: rank 0 reads it and checks that the restart file
/// it names exists; every rank gets the result). Throws std::invalid_argument
/// ("--restart: no checkpoint at ...") when there is none, std::runtime_error when it cannot be
/// read or is not a granagg-lammps checkpoint.
LammpsCheckpoint readLammpsCheckpoint(const std::filesystem::path& folder, MPI_Comm comm);

class LammpsEngine : public RunEngine {
 public:
  /// A new run of `config` into `folder` (collective). Rank 0 builds the initial state
  /// (md::prepareInitialState, which sets system.N and system.phi of a file-given state in
  /// `config`; every rank gets the result) and the translation; bad input throws
  /// std::invalid_argument on every rank, before anything is written. record_collisions: the
  /// fix keeps every collision (CollisionLog). command_line goes into lammps.in's header.
  LammpsEngine(MdConfig& config, const std::filesystem::path& folder, bool record_collisions,
               const std::string& command_line, MPI_Comm comm);
  /// Continues `checkpoint` of `folder` under `config` (the run's stored configuration; run.t_end
  /// may be later). Collective.
  LammpsEngine(const MdConfig& config, const std::filesystem::path& folder,
               const LammpsCheckpoint& checkpoint, MPI_Comm comm);
  ~LammpsEngine() override;
  LammpsEngine(const LammpsEngine&) = delete;
  LammpsEngine& operator=(const LammpsEngine&) = delete;

  void begin(const std::filesystem::path& folder) override;
  void run(std::int64_t steps) override;
  std::int64_t step() const override;
  double time() const override { return static_cast<double>(step()) * m_input.dt; }
  /// LAMMPS's timestep: granagg's dt, or under rRESPA the outer step (LammpsInput.h).
  double dt() const override { return m_input.dt; }
  std::string dtReason() const override { return m_input.dt_reason; }
  double box() const override { return m_box; }
  std::size_t size() const override { return m_N; }
  /// Wrapped positions with image counts, velocities and charges, in id order, on rank 0.
  /// LAMMPS integrates every force at every step: both kinds are the same state.
  Frame frame(StateKind kind = StateKind::Integrator) const override;
  /// The total force on each particle at the current step (pair and k-space), on rank 0.
  Forces forces(StateKind kind = StateKind::Integrator) const override;
  Observables observables() const override;
  const CoulombSetup* coulombSetup() const override;
  /// LAMMPS's neighbour-list builds (Neighbor::ncalls).
  std::int64_t neighborBuilds() const override;
  /// "LAMMPS 29 Sep 2021 on 4 MPI ranks".
  std::string description() const override;
  /// engine (LAMMPS and its version), mpi_ranks, lammps_input (the text of lammps.in).
  std::vector<std::pair<std::string, std::string>> parameters() const override;
  bool writesFiles() const override { return m_rank == 0; }
  bool anyRank(bool local) const override;
  std::filesystem::path checkpointPath(const std::filesystem::path& folder) const override;
  void saveCheckpoint(const std::filesystem::path& folder,
                      const RunFields& run_fields) override;

  /// The generated input as lammps.in holds it (header comments, commands, the `run`).
  const std::string& inputText() const { return m_input_text; }
  /// How keys were resolved for LAMMPS, and the time step's reason (log lines).
  const LammpsInput& input() const { return m_input; }
  bool recordsCollisions() const { return m_record_collisions; }
  /// The charging fix (after begin()): its statistics and collision records.
  FixCharging& fix() const;
  int ranks() const { return m_ranks; }
  MPI_Comm comm() const { return m_comm; }

 private:
  MPI_Comm m_comm;
  int m_rank = 0, m_ranks = 1;
  std::filesystem::path m_folder;  // absolute
  bool m_resumed = false;
  bool m_record_collisions = false;
  MdConfig m_cfg;
  LammpsInput m_input;
  std::string m_input_text;
  Frame m_initial;  // rank 0, a new run: written as initial.data by begin()
  std::size_t m_N = 0;
  double m_box = 0.0;
  std::int64_t m_first_step = 0;  // before begin()
  std::unique_ptr<LAMMPS_NS::LAMMPS> m_lmp;
  FixCharging* m_fix = nullptr;

  /// Per-atom values of every rank, in id order, on rank 0 (empty elsewhere): `width` values per
  /// atom from `fill(i, row)` for each owned atom i.
  template <class Fill>
  std::vector<double> gather(int width, Fill fill) const;
};

}  // namespace granagg::md::lammps
