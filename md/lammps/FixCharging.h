#pragma once
/// \file FixCharging.h
/// `fix ID group granagg/charging ...`: granagg's collisional charging (docs/model.md section 7,
/// md/potentials/ChargeExchange.h) inside LAMMPS, plus the engine's collision count, contact
/// statistics and overlap guard. Debian's LAMMPS has no PLUGIN package: a program that owns the
/// LAMMPS instance registers the style with FixCharging::registerStyle() before it runs any
/// command (what PLUGIN does inside).
///
///     fix ID all granagg/charging pair STYLE seed S Q Q kappa K psi1 MIN MAX psi2 HALF_WIDTH
///         exchange yes|no max_overlap X [record yes|no]
///
/// pair: the granular pair style whose neighbour list holds the contacts (gran/hertz/history,
/// gran/hooke/history, possibly a sub-style of hybrid/overlay); the rest are ChargeExchange's
/// parameters (psi2 = psi2_fraction kappa) and run.max_overlap. exchange no: charges never change
/// (charging.mode = "fixed"), collisions and contacts are still counted. record yes: every
/// collision is kept (step, ids, xi', charge gained by the lower id) for collisionRecords().
///
/// What it does, matching the engine (md/compute/ContactForce.h) step by step. LAMMPS's velocity
/// Verlet (fix nve/sphere) runs a step as: kick + drift (initial_integrate), post_integrate,
/// communication, force_clear, pre_force, pair and kspace forces, kick (final_integrate),
/// end_of_step. At pre_force of step n the positions are x(t_n), the velocities the drift
/// velocities u = v(t_n - dt/2) (also on ghosts: comm_modify vel yes), and the forces f(t_{n-1})
/// that kicked u were saved at post_integrate (atom->f is cleared before pre_force):
/// - A collision is the first step of a contact: a pair in contact at t_n (r < R_i + R_j) whose
///   separation one step earlier, r - dt (u_i - u_j) (the drift undone), was at least R_i + R_j.
/// - Its approach speed xi' = -(v_i - v_j).n with the predicted full-step velocities
///   v(t_n) = u + (dt/2) f(t_{n-1}) / m, the engine's (second order in dt).
/// - The charge the pair exchanges is ChargeExchange::transferTo(params, n, id_i, id_j, xi'),
///   a pure function of (seed, step, ids, xi'): ids are LAMMPS atom ids - 1 (granagg's particle
///   index), n is LAMMPS's step, which counts from 0 at the initial state as the engine does.
/// - The exchange takes effect after the forces of step n (end_of_step), as in the engine, whose
///   kick applies it: the Coulomb force of step n uses the charges before it, the output of step
///   n the charges after it.
/// Decomposition: the pair style's half list with newton_pair on (required) holds each pair
/// once, on one rank; that rank computes the exchange once and gives +dq and -dq to the two
/// partners, ghost or owned; a reverse communication adds the ghosts' shares to their owners.
/// Each rank then changes only the charges of the atoms it owns, and the sum of the charges is
/// conserved up to the rounding of the per-atom sums. Ghosts need the predicted velocities and
/// the current charges of their owners: one forward communication of 4 values per ghost at every
/// step (pre_force). The saved forces migrate with their atoms (exchange), since post_integrate
/// comes before the exchange of a re-neighbouring step.
///
/// Restarts: the fix stores each atom's force (write_restart writes f(t_n), the force that both
/// closed step n and opens step n + 1) and, when a run starts from a restart with this fix,
/// puts it back after LAMMPS's setup has recomputed the forces. LAMMPS's setup evaluates the
/// granular damping with the full-step velocity v(t_n) where the uninterrupted run used
/// u(t_n - dt/2); with the stored forces the continued run takes the same first kick as the
/// uninterrupted one. The cumulative collision count is stored as global restart data.
/// The write_restart command moves atoms between ranks before it writes (pbc, exchange), and
/// atom->f does not move with them: init(), which it calls first, keeps the forces in the
/// per-atom array that migrates, and the next run's setup puts them back in the writing process
/// too (that run must not be `pre no`: the neighbour lists are stale after the move).
///
/// Requirements checked at init: atom_style with q, radius and rmass; unit spheres of unit mass
/// (granagg's particles: the charging rule's m_eff = 1/2); newton_pair on; comm_modify vel yes;
/// run_style verlet.
#include <cstdint>
#include <vector>

#include "md/lammps/LammpsApi.h"
#include "md/potentials/ChargeExchange.h"

namespace granagg::md::lammps {

/// One collision (record yes).
struct CollisionRecord {
  std::int64_t step = 0;
  std::uint32_t id_lo = 0, id_hi = 0;  ///< granagg particle indices (LAMMPS ids - 1)
  double xi_dot = 0.0;                 ///< approach speed xi'
  double dq_lo = 0.0;                  ///< charge the partner with the lower id gained
};

/// Global contact statistics at the last step (positions x(t_n) of its pre_force).
struct ContactStats {
  std::int64_t collisions = 0;  ///< since the start of the run (restarts included)
  std::int64_t contacts = 0;    ///< pairs in contact
  double overlap_sum = 0.0;     ///< sum of overlaps xi over pairs in contact
  double max_overlap = 0.0;
  double sum_xi_5_2 = 0.0;  ///< sum xi^{5/2}: Hertz elastic energy = (2/5) E times this
  double sum_xi_2 = 0.0;    ///< sum xi^2: spring elastic energy = (1/2) k times this
  std::int64_t migrations = 0;  ///< atoms received from another rank since the fix was created
};

class FixCharging : public LAMMPS_NS::Fix {
 public:
  static constexpr const char* STYLE = "granagg/charging";
  /// Adds the style to lmp's fix style map; call before any command that defines the fix.
  static void registerStyle(LAMMPS_NS::LAMMPS* lmp);

  FixCharging(LAMMPS_NS::LAMMPS* lmp, int narg, char** arg);
  ~FixCharging() override;

  int setmask() override;
  void init() override;
  void setup(int vflag) override;
  void post_integrate() override;
  void setup_pre_force(int vflag) override;
  void pre_force(int vflag) override;
  void end_of_step() override;

  void grow_arrays(int nmax) override;
  void copy_arrays(int i, int j, int delflag) override;
  int pack_exchange(int i, double* buf) override;
  int unpack_exchange(int nlocal, double* buf) override;
  int pack_restart(int i, double* buf) override;
  void unpack_restart(int nlocal, int nth) override;
  int size_restart(int nlocal) override;
  int maxsize_restart() override;
  void write_restart(FILE* fp) override;
  void restart(char* buf) override;

  int pack_forward_comm(int n, int* list, double* buf, int pbc_flag, int* pbc) override;
  void unpack_forward_comm(int n, int first, double* buf) override;
  int pack_reverse_comm(int n, int first, double* buf) override;
  void unpack_reverse_comm(int n, int* list, double* buf) override;

  double memory_usage() override;

  /// The statistics of the last step, summed over ranks (collective: every rank calls it).
  ContactStats stats() const;
  /// This rank's collision records since the last clear (record yes); each collision is on
  /// exactly one rank.
  const std::vector<CollisionRecord>& collisionRecords() const { return m_records; }
  void clearCollisionRecords() { m_records.clear(); }
  const ChargeExchange::Params& params() const { return m_params; }
  bool exchanges() const { return m_exchange; }
  /// Between runs, before `write_restart ... noinit`: keeps the forces of the state in the
  /// per-atom array that the restart file stores (pack_restart) and the next run's setup puts
  /// back (setup()).
  void keepForcesForRestart();

 private:
  ChargeExchange::Params m_params;
  bool m_exchange = true;
  bool m_record = false;
  double m_max_overlap = 0.6;
  std::string m_pair_style;
  LAMMPS_NS::Pair* m_pair = nullptr;

  // per atom, owned and ghost (grown with atom->nmax)
  double** m_fprev = nullptr;     ///< f(t_{n-1}), saved at post_integrate (owned; migrates)
  double** m_vpred = nullptr;     ///< predicted v(t_n) (owned, then ghosts by forward comm)
  double* m_dq = nullptr;         ///< charge gained this step (owned and ghost, reverse comm)
  double** m_frestart = nullptr;  ///< forces read from a restart file (owned; migrates)
  int m_nmax = 0;
  bool m_restore_forces = false;  ///< m_frestart holds forces to put back at the next setup

  // local (this rank's) statistics of the last step and counters
  std::int64_t m_collisions_local = 0;  ///< cumulative, this rank
  std::int64_t m_collisions_restart = 0;  ///< global count carried over from a restart file
  std::int64_t m_contacts = 0, m_migrations = 0;
  double m_overlap_sum = 0.0, m_max_overlap_now = 0.0, m_sum_xi52 = 0.0, m_sum_xi2 = 0.0;
  std::vector<CollisionRecord> m_records;
  /// The pass over the contacts: statistics and the overlap guard; with step_taken (pre_force
  /// of a step, not a run's setup) also the collisions and their exchange.
  void scanContacts(bool step_taken);
};

}  // namespace granagg::md::lammps
