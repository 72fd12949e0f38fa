#pragma once
/// \file FixCharging.h
/// `fix ID group granagg/charging ...`: granagg's collisional charging (docs/model.md section 7,
/// md/potentials/ChargeExchange.h) inside LAMMPS, plus the engine's collision count, contact
/// statistics and overlap guard. Debian's LAMMPS has no PLUGIN package: a program that owns the
/// LAMMPS instance registers the style with FixCharging::registerStyle() before it runs any
/// command (what PLUGIN does inside).
///
///     fix ID all granagg/charging pair STYLE seed S Q Q kappa K psi1 MIN MAX psi2 HALF_WIDTH
///         exchange yes|no max_overlap X [record yes|no] [respa K]
///
/// pair: the granular pair style whose neighbour list holds the contacts (gran/hertz/history,
/// gran/hooke/history, possibly a sub-style of hybrid/overlay); the rest are ChargeExchange's
/// parameters (psi2 = psi2_fraction kappa) and run.max_overlap. exchange no: charges never change
/// (charging.mode = "fixed"), collisions and contacts are still counted. record yes: every
/// collision is kept (step, ids, xi', charge gained by the lower id) for collisionRecords().
/// respa K: the run uses `run_style respa 2 K pair 1 kspace 2` (below); default 1, run_style
/// verlet.
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
/// rRESPA (respa K > 1): `run_style respa 2 K pair 1 kspace 2` integrates the pair forces
/// (contacts and the real-space Coulomb force, r < r_cut) with the inner step dt = Dt / K and
/// the PPPM mesh force with the outer step Dt (LAMMPS's `timestep`), as impulses of Dt at the
/// outer boundaries: the impulse multiple-time-step method of granagg md (docs/coulomb.md),
/// split at r_cut. LAMMPS then calls only the fixes' *_respa methods, and this fix does at the
/// inner level what it does at every step under verlet:
/// - post_integrate_respa: keeps the inner force f_in(t_{n-1}) that kicked the drift velocities;
/// - pre_force_respa: the contact pass, with the inner step dt for the collision test and the
///   charge-exchange counter n = (outer step - 1) K + inner index + 1: the inner steps counted
///   from the initial state, as granagg md counts its steps;
/// - post_force_respa: the exchange takes effect, after the inner forces of the step.
/// The predicted velocity is u + (dt/2) f_in(t_{n-1}), plus at the last inner step of an outer
/// step the half impulse (Dt/2) F_mesh that closes it: granagg md's prediction at an evaluation
/// step (ContactStep::ext_predict_scale), except that F_mesh is the last evaluation's (the new
/// one is computed after the inner steps). Under rRESPA every `run` starts with LAMMPS's full
/// setup (`pre no` is refused), which recomputes the forces of each level from v(t_n); the fix
/// keeps each level's force of the state (f_in at the last inner step, F_mesh at the outer
/// level) and puts them back in the setup (setup_pre_reverse), so that a chunked or restarted
/// run takes the same kicks as an uninterrupted one.
///
/// Requirements checked at init: atom_style with q, radius and rmass; unit spheres of unit mass
/// (granagg's particles: the charging rule's m_eff = 1/2); newton_pair on; comm_modify vel yes;
/// run_style verlet, or respa with respa K (2 levels, K inner steps: checked at the first outer
/// step).
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
  // rRESPA (respa K > 1)
  void setup_pre_force_respa(int vflag, int ilevel) override;
  void setup_pre_reverse(int eflag, int vflag) override;
  void post_integrate_respa(int ilevel, int iloop) override;
  void pre_force_respa(int vflag, int ilevel, int iloop) override;
  void post_force_respa(int vflag, int ilevel, int iloop) override;

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
  /// Inner steps per outer step (respa K; 1 under run_style verlet).
  int respaLoop() const { return m_respa_loop; }
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
  int m_respa_loop = 1;     ///< respa K
  int m_restart_loop = 1;   ///< the respa K of the run that wrote the restart file read
  int m_setup_level = 0;    ///< the level whose forces LAMMPS's rRESPA setup is computing
  int m_inner_steps = 0;    ///< inner steps taken in the current outer step
  std::string m_pair_style;
  LAMMPS_NS::Pair* m_pair = nullptr;

  // per atom, owned and ghost (grown with atom->nmax)
  double** m_fprev = nullptr;     ///< f(t_{n-1}), saved at post_integrate (owned; migrates)
  double** m_vpred = nullptr;     ///< predicted v(t_n) (owned, then ghosts by forward comm)
  double* m_dq = nullptr;         ///< charge gained this step (owned and ghost, reverse comm)
  double** m_frestart = nullptr;  ///< the state's (inner) force kept for a setup (owned; migrates)
  double** m_fslow = nullptr;     ///< rRESPA: the last outer (mesh) force (owned; migrates)
  int m_nmax = 0;
  bool m_restore_forces = false;  ///< m_frestart (and m_fslow) hold forces to put back at the
                                  ///< next setup

  // local (this rank's) statistics of the last step and counters
  std::int64_t m_collisions_local = 0;  ///< cumulative, this rank
  std::int64_t m_collisions_restart = 0;  ///< global count carried over from a restart file
  std::int64_t m_contacts = 0, m_migrations = 0;
  double m_overlap_sum = 0.0, m_max_overlap_now = 0.0, m_sum_xi52 = 0.0, m_sum_xi2 = 0.0;
  std::vector<CollisionRecord> m_records;
  /// The pass over the contacts: statistics and the overlap guard; with step_taken (pre_force
  /// of a step, not a run's setup) also the collisions and their exchange. dt: the step just
  /// taken (the inner step under rRESPA); step: the charge-exchange counter; slow_kick: the
  /// factor of m_fslow in the predicted velocity (rRESPA's closing half impulse, else 0).
  void scanContacts(bool step_taken, double dt, std::int64_t step, double slow_kick);
  /// The exchange of the step takes effect (owned atoms; ghosts follow by forward communication).
  void applyExchange();
};

}  // namespace granagg::md::lammps
