#include "md/lammps/FixCharging.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

namespace granagg::md::lammps {

using namespace LAMMPS_NS;

namespace {

Fix* createFixCharging(LAMMPS* lmp, int narg, char** arg) {
  return new FixCharging(lmp, narg, arg);
}

/// Values per atom that migrate: the saved force, the kept force and the mesh force.
constexpr int EXCHANGE_SIZE = 9;
/// Values per atom in a restart file: the count itself, the kept force and the mesh force (a
/// file with count 4 has no mesh force).
constexpr int RESTART_SIZE = 7;
/// The first value of the global restart data: a collision count is never negative, so a
/// negative first value marks the layout (marker, collisions, respa K); without it the value is
/// the collision count alone.
constexpr double RESTART_LAYOUT_2 = -2.0;

}  // namespace

void FixCharging::registerStyle(LAMMPS* lmp) {
  (*lmp->modify->fix_map)[STYLE] = &createFixCharging;
}

FixCharging::FixCharging(LAMMPS* lmp, int narg, char** arg) : Fix(lmp, narg, arg) {
  const std::string usage =
      std::string("fix ID group ") + STYLE +
      " pair STYLE seed S Q Q kappa K psi1 MIN MAX psi2 HALF_WIDTH exchange yes|no "
      "max_overlap X [record yes|no] [respa K]";
  auto number = [&](int k) {
    char* end = nullptr;
    const double v = std::strtod(arg[k], &end);
    if (end == arg[k] || *end != '\0' || !std::isfinite(v))
      error->all(FLERR, std::string("fix ") + STYLE + ": '" + arg[k] + "' after '" + arg[k - 1] +
                            "' is not a number; usage: " + usage);
    return v;
  };
  auto yesNo = [&](int k) {
    if (std::strcmp(arg[k], "yes") == 0) return true;
    if (std::strcmp(arg[k], "no") == 0) return false;
    error->all(FLERR, std::string("fix ") + STYLE + ": " + arg[k - 1] + " takes yes or no");
  };
  bool have_seed = false, have_pair = false, have_exchange = false;
  for (int k = 3; k < narg;) {
    const std::string key = arg[k];
    const int left = narg - k - 1;
    if (key == "pair" && left >= 1) {
      m_pair_style = arg[k + 1];
      have_pair = true;
      k += 2;
    } else if (key == "seed" && left >= 1) {
      char* end = nullptr;
      m_params.seed = std::strtoull(arg[k + 1], &end, 10);
      if (end == arg[k + 1] || *end != '\0' || arg[k + 1][0] == '-')
        error->all(FLERR, std::string("fix ") + STYLE + ": seed must be an integer in [0, 2^64)");
      have_seed = true;
      k += 2;
    } else if (key == "Q" && left >= 1) {
      m_params.Q = number(k + 1);
      k += 2;
    } else if (key == "kappa" && left >= 1) {
      m_params.kappa = number(k + 1);
      k += 2;
    } else if (key == "psi1" && left >= 2) {
      m_params.psi1_min = number(k + 1);
      m_params.psi1_max = number(k + 2);
      k += 3;
    } else if (key == "psi2" && left >= 1) {
      m_params.psi2_half_width = number(k + 1);
      k += 2;
    } else if (key == "exchange" && left >= 1) {
      m_exchange = yesNo(k + 1);
      have_exchange = true;
      k += 2;
    } else if (key == "max_overlap" && left >= 1) {
      m_max_overlap = number(k + 1);
      k += 2;
    } else if (key == "record" && left >= 1) {
      m_record = yesNo(k + 1);
      k += 2;
    } else if (key == "respa" && left >= 1) {
      const double loop = number(k + 1);
      if (!(loop >= 1.0 && loop <= 1000.0) || loop != std::floor(loop))
        error->all(FLERR, std::string("fix ") + STYLE + ": respa takes an integer K in [1, 1000]");
      m_respa_loop = static_cast<int>(loop);
      k += 2;
    } else {
      error->all(FLERR, std::string("fix ") + STYLE + ": unknown or incomplete keyword '" + key +
                            "'; usage: " + usage);
    }
  }
  if (!have_pair || !have_seed || !have_exchange)
    error->all(FLERR, std::string("fix ") + STYLE + " needs pair, seed and exchange; usage: " +
                          usage);
  m_params.m_eff = 0.5;  // unit masses (checked in init)

  nevery = 1;  // end_of_step at every step
  restart_global = 1;
  restart_peratom = 1;
  comm_forward = 4;  // predicted velocity and charge of each ghost
  comm_reverse = 1;  // charge a ghost gained
  maxexchange = EXCHANGE_SIZE;

  grow_arrays(atom->nmax);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
  for (int i = 0; i < atom->nmax; ++i)
    for (int k = 0; k < 3; ++k)
      m_fprev[i][k] = m_vpred[i][k] = m_frestart[i][k] = m_fslow[i][k] = 0.0;
}

FixCharging::~FixCharging() {
  atom->delete_callback(id, Atom::GROW);
  atom->delete_callback(id, Atom::RESTART);
  memory->destroy(m_fprev);
  memory->destroy(m_vpred);
  memory->destroy(m_dq);
  memory->destroy(m_frestart);
  memory->destroy(m_fslow);
}

int FixCharging::setmask() {
  if (m_respa_loop > 1)
    return FixConst::POST_INTEGRATE_RESPA | FixConst::PRE_FORCE_RESPA |
           FixConst::POST_FORCE_RESPA | FixConst::PRE_REVERSE;
  return FixConst::POST_INTEGRATE | FixConst::PRE_FORCE | FixConst::END_OF_STEP;
}

void FixCharging::init() {
  const std::string me = std::string("fix ") + STYLE;
  if (!atom->q_flag || !atom->radius_flag || !atom->rmass_flag)
    error->all(FLERR, me + " needs per-atom charge, radius and mass (atom_style hybrid sphere "
                           "charge)");
  if (!force->newton_pair)
    error->all(FLERR, me + " needs newton_pair on (each pair on one rank)");
  if (!comm->ghost_velocity)
    error->all(FLERR, me + " needs comm_modify vel yes (ghost velocities)");
  const bool respa = std::strncmp(update->integrate_style, "respa", 5) == 0;
  if (m_respa_loop > 1 && !respa)
    error->all(FLERR, me + " with respa " + std::to_string(m_respa_loop) +
                          " needs run_style respa 2 " + std::to_string(m_respa_loop) +
                          " pair 1 kspace 2");
  if (m_respa_loop == 1 && std::strcmp(update->integrate_style, "verlet") != 0)
    error->all(FLERR, me + " without respa K supports run_style verlet only");
  // forces kept by a run with another integration are not this one's levels: recomputed
  if (m_restart_loop != m_respa_loop) {
    m_restore_forces = false;
    m_restart_loop = m_respa_loop;
  }
  m_inner_steps = 0;
  m_pair = force->pair_match(m_pair_style, 1, 0);
  if (!m_pair) error->all(FLERR, me + ": no pair style " + m_pair_style + " is defined");
  // granagg's particles: unit spheres of unit mass (the charging rule's m_eff = 1/2, and the
  // predicted velocity of the engine)
  int bad = 0;
  for (int i = 0; i < atom->nlocal; ++i)
    if (atom->radius[i] != 0.5 || atom->rmass[i] != 1.0) bad = 1;
  int any_bad = 0;
  MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, world);
  if (any_bad)
    error->all(FLERR, me + " needs unit spheres of unit mass (diameter 1, mass 1: set group all "
                           "mass 1.0)");
  // Between runs (whichflag 0), LAMMPS's write_data (and write_restart without noinit) call
  // init() and then move atoms between ranks and within the arrays (pbc, exchange), which
  // atom->f does not follow: the forces are kept in the array that migrates with the atoms.
  if (update->whichflag == 0) keepForcesForRestart();
}

void FixCharging::keepForcesForRestart() {
  // Not before the first run (no forces yet), nor over forces read from a restart file that no
  // run has restored yet.
  // Under rRESPA the forces of each level are kept at every step and every setup.
  if (m_respa_loop > 1 || !update->first_update || m_restore_forces) return;
  double** f = atom->f;
  for (int i = 0; i < atom->nlocal; ++i)
    for (int k = 0; k < 3; ++k) m_frestart[i][k] = f[i][k];
  m_restore_forces = true;
}

void FixCharging::setup(int /*vflag*/) {
  if (m_respa_loop > 1) return;  // restored per level (setup_pre_reverse)
  if (!(m_restore_forces || restart_reset)) return;
  // the forces of the step the restart was written at, in place of setup's recomputed ones
  double** f = atom->f;
  for (int i = 0; i < atom->nlocal; ++i)
    for (int k = 0; k < 3; ++k) f[i][k] = m_frestart[i][k];
  m_restore_forces = false;
  restart_reset = 0;
}

void FixCharging::post_integrate() {
  // f(t_{n-1}), which kicked the drift velocities; force_clear erases atom->f before pre_force
  double** f = atom->f;
  for (int i = 0; i < atom->nlocal; ++i)
    for (int k = 0; k < 3; ++k) m_fprev[i][k] = f[i][k];
}

void FixCharging::setup_pre_force(int /*vflag*/) {
  // the contact statistics of the state a run starts from (no step is taken: no collisions)
  scanContacts(false, update->dt, update->ntimestep, 0.0);
}

void FixCharging::pre_force(int /*vflag*/) {
  scanContacts(true, update->dt, update->ntimestep, 0.0);
}

void FixCharging::setup_pre_force_respa(int /*vflag*/, int ilevel) {
  m_setup_level = ilevel;
  if (ilevel == 0) scanContacts(false, update->dt / m_respa_loop, update->ntimestep, 0.0);
}

void FixCharging::setup_pre_reverse(int /*eflag*/, int /*vflag*/) {
  if (m_respa_loop == 1) return;
  // The forces of level m_setup_level, before LAMMPS's reverse communication and its copy into
  // the level's store. Kept forces replace them: the owned atoms get them and the ghosts zero,
  // so that the reverse communication adds nothing. Otherwise (a new run's first setup) they
  // are the state's forces: completed here by the reverse communication (the ghosts are then
  // zeroed, so that LAMMPS's adds nothing again) and kept.
  double** f = atom->f;
  const int nlocal = atom->nlocal, nall = nlocal + atom->nghost;
  double** kept = m_setup_level == 0 ? m_frestart : m_fslow;
  if (m_restore_forces) {
    for (int i = 0; i < nlocal; ++i)
      for (int k = 0; k < 3; ++k) f[i][k] = kept[i][k];
  } else {
    if (m_setup_level == 0) comm->reverse_comm();
    for (int i = 0; i < nlocal; ++i)
      for (int k = 0; k < 3; ++k) kept[i][k] = f[i][k];
  }
  for (int i = nlocal; i < nall; ++i)
    for (int k = 0; k < 3; ++k) f[i][k] = 0.0;
  // The reverse communication above also moved the ghosts' torques (atom_style sphere), which
  // LAMMPS's own would add again: zeroed too. (They are zero with this model, which has no
  // tangential force, but the fix must not rely on that.)
  if (!m_restore_forces && m_setup_level == 0 && atom->torque_flag)
    for (int i = nlocal; i < nall; ++i)
      for (int k = 0; k < 3; ++k) atom->torque[i][k] = 0.0;
  if (m_setup_level == 1) {
    m_restore_forces = true;  // both levels kept: every later setup restores them
    restart_reset = 0;
  }
}

void FixCharging::post_integrate_respa(int ilevel, int /*iloop*/) {
  if (ilevel == 0) post_integrate();  // f_in(t_{n-1}), which kicked the drift velocities
}

void FixCharging::pre_force_respa(int /*vflag*/, int ilevel, int iloop) {
  const std::string me = std::string("fix ") + STYLE;
  if (ilevel == 0) {
    if (iloop >= m_respa_loop)
      error->all(FLERR, me + ": run_style respa takes more than respa " +
                            std::to_string(m_respa_loop) + " inner steps per outer step");
    ++m_inner_steps;
    const double dt = update->dt / m_respa_loop;
    const std::int64_t step =
        (static_cast<std::int64_t>(update->ntimestep) - 1) * m_respa_loop + iloop + 1;
    const double slow_kick = iloop == m_respa_loop - 1 ? 0.5 * update->dt * force->ftm2v : 0.0;
    scanContacts(true, dt, step, slow_kick);
  } else if (ilevel == 1) {
    if (m_inner_steps != m_respa_loop)
      error->all(FLERR, me + ": run_style respa took " + std::to_string(m_inner_steps) +
                            " inner steps in an outer step; respa " +
                            std::to_string(m_respa_loop) + " says how many it must take");
    m_inner_steps = 0;
    // sum q and sum q^2 of the charges the mesh force is about to use (self and background
    // terms, and PPPM's estimates)
    if (m_exchange && force->kspace) force->kspace->qsum_qsq(0);
  } else {
    error->all(FLERR, me + " supports two rRESPA levels (pair 1 kspace 2)");
  }
}

void FixCharging::post_force_respa(int /*vflag*/, int ilevel, int iloop) {
  const double* const* f = atom->f;  // this level's force, complete for the owned atoms
  const int nlocal = atom->nlocal;
  if (ilevel == 0) {
    applyExchange();
    if (iloop == m_respa_loop - 1)  // the inner force of the state at the outer boundary
      for (int i = 0; i < nlocal; ++i)
        for (int k = 0; k < 3; ++k) m_frestart[i][k] = f[i][k];
  } else if (ilevel == 1) {
    for (int i = 0; i < nlocal; ++i)
      for (int k = 0; k < 3; ++k) m_fslow[i][k] = f[i][k];
    m_restore_forces = true;
  }
}

void FixCharging::scanContacts(bool step_taken, double dt, std::int64_t step,
                               double slow_kick) {
  const int nlocal = atom->nlocal, nall = nlocal + atom->nghost;
  double** x = atom->x;
  double** v = atom->v;
  const double* radius = atom->radius;
  const double* rmass = atom->rmass;
  const tagint* tag = atom->tag;

  const bool exchange = m_exchange && step_taken;
  if (exchange) {
    // predicted full-step velocities v(t_n) = u + (dt/2) f(t_{n-1}) / m: the arithmetic of fix
    // nve/sphere's kick (dtf / rmass), which with m = 1 is the engine's u + (dt/2) f
    const double dtf = 0.5 * dt * force->ftm2v;
    for (int i = 0; i < nlocal; ++i) {
      const double dtfm = dtf / rmass[i];
      for (int k = 0; k < 3; ++k) m_vpred[i][k] = v[i][k] + dtfm * m_fprev[i][k];
      if (slow_kick != 0.0) {
        const double sm = slow_kick / rmass[i];
        for (int k = 0; k < 3; ++k) m_vpred[i][k] += sm * m_fslow[i][k];
      }
    }
    comm->forward_comm_fix(this);  // ghosts: predicted velocities and current charges
    for (int i = 0; i < nall; ++i) m_dq[i] = 0.0;
  }

  m_contacts = 0;
  m_overlap_sum = m_max_overlap_now = m_sum_xi52 = m_sum_xi2 = 0.0;
  int worst_i = -1, worst_j = -1;
  const NeighList* list = m_pair->list;
  for (int ii = 0; ii < list->inum; ++ii) {
    const int i = list->ilist[ii];
    const int* jlist = list->firstneigh[i];
    for (int jj = 0; jj < list->numneigh[i]; ++jj) {
      const int j = jlist[jj] & NEIGHMASK;
      const double rx = x[i][0] - x[j][0], ry = x[i][1] - x[j][1], rz = x[i][2] - x[j][2];
      const double r2 = rx * rx + ry * ry + rz * rz;
      const double R = radius[i] + radius[j];
      if (!(r2 < R * R)) continue;
      const double r = std::sqrt(r2);
      const double xi = R - r;
      ++m_contacts;
      m_overlap_sum += xi;
      m_sum_xi2 += xi * xi;
      m_sum_xi52 += xi * xi * std::sqrt(xi);
      if (xi > m_max_overlap_now) {
        m_max_overlap_now = xi;
        worst_i = i;
        worst_j = j;
      }
      // a collision: the separation one step earlier (the drift undone) was not a contact
      const double px = rx - dt * (v[i][0] - v[j][0]), py = ry - dt * (v[i][1] - v[j][1]),
                   pz = rz - dt * (v[i][2] - v[j][2]);
      if (!step_taken || !(px * px + py * py + pz * pz >= R * R)) continue;
      ++m_collisions_local;
      const auto id_i = static_cast<std::uint32_t>(tag[i] - 1),
                 id_j = static_cast<std::uint32_t>(tag[j] - 1);
      double dqi = 0.0, xi_dot = 0.0;
      if (exchange) {
        const double inv_r = 1.0 / r;
        const double nx = rx * inv_r, ny = ry * inv_r, nz = rz * inv_r;  // from j to i
        const double gx = m_vpred[i][0] - m_vpred[j][0], gy = m_vpred[i][1] - m_vpred[j][1],
                     gz = m_vpred[i][2] - m_vpred[j][2];
        xi_dot = -(gx * nx + gy * ny + gz * nz);  // > 0 while approaching
        dqi = ChargeExchange::transferTo(m_params, step, id_i, id_j, xi_dot);
        m_dq[i] += dqi;
        m_dq[j] -= dqi;  // exactly transferTo(j, i)
      }
      if (m_record) {
        CollisionRecord c;
        c.step = step;
        c.id_lo = id_i < id_j ? id_i : id_j;
        c.id_hi = id_i < id_j ? id_j : id_i;
        c.xi_dot = xi_dot;
        c.dq_lo = id_i < id_j ? dqi : -dqi;
        m_records.push_back(c);
      }
    }
  }
  if (m_max_overlap_now > m_max_overlap) {
    // the engine's guard (run.max_overlap): stop the run, naming the pair
    std::ostringstream msg;
    msg << "step " << step << ": overlap " << m_max_overlap_now << " of particles "
        << tag[worst_i] - 1 << " and " << tag[worst_j] - 1 << " beyond run.max_overlap = "
        << m_max_overlap << "; the time step dt = " << dt
        << " may be too large for these impacts";
    std::fprintf(stderr, "granagg-lammps: %s\n", msg.str().c_str());
    error->one(FLERR, msg.str());
  }
  if (exchange) comm->reverse_comm_fix(this);  // ghosts' shares to their owners
}

void FixCharging::end_of_step() {
  if (!m_exchange) return;
  applyExchange();
  // sum q and sum q^2 enter the k-space energy (self and background terms) and its estimates
  if (force->kspace) force->kspace->qsum_qsq(0);
}

void FixCharging::applyExchange() {
  if (!m_exchange) return;
  // the exchange of this step takes effect after its forces (the engine's kick applies it)
  double* q = atom->q;
  for (int i = 0; i < atom->nlocal; ++i)
    if (m_dq[i] != 0.0) q[i] += m_dq[i];
}

void FixCharging::grow_arrays(int nmax) {
  memory->grow(m_fprev, nmax, 3, "granagg/charging:fprev");
  memory->grow(m_vpred, nmax, 3, "granagg/charging:vpred");
  memory->grow(m_frestart, nmax, 3, "granagg/charging:frestart");
  memory->grow(m_fslow, nmax, 3, "granagg/charging:fslow");
  memory->grow(m_dq, nmax, "granagg/charging:dq");
  m_nmax = nmax;
}

void FixCharging::copy_arrays(int i, int j, int /*delflag*/) {
  for (int k = 0; k < 3; ++k) {
    m_fprev[j][k] = m_fprev[i][k];
    m_frestart[j][k] = m_frestart[i][k];
    m_fslow[j][k] = m_fslow[i][k];
  }
}

int FixCharging::pack_exchange(int i, double* buf) {
  for (int k = 0; k < 3; ++k) {
    buf[k] = m_fprev[i][k];
    buf[3 + k] = m_frestart[i][k];
    buf[6 + k] = m_fslow[i][k];
  }
  return EXCHANGE_SIZE;
}

int FixCharging::unpack_exchange(int nlocal, double* buf) {
  for (int k = 0; k < 3; ++k) {
    m_fprev[nlocal][k] = buf[k];
    m_frestart[nlocal][k] = buf[3 + k];
    m_fslow[nlocal][k] = buf[6 + k];
  }
  ++m_migrations;
  return EXCHANGE_SIZE;
}

int FixCharging::pack_restart(int i, double* buf) {
  // the forces of the state: in the migrating array while a restore is pending (init() between
  // runs, or a restart file read and not yet run), else atom->f (the `restart` command's output
  // during a run, where atoms have not moved since the forces)
  // (rRESPA: the kept forces of both levels, always current after a setup)
  const double* f = m_restore_forces ? m_frestart[i] : atom->f[i];
  buf[0] = RESTART_SIZE;
  for (int k = 0; k < 3; ++k) {
    buf[1 + k] = f[k];
    buf[4 + k] = m_respa_loop > 1 ? m_fslow[i][k] : 0.0;
  }
  return RESTART_SIZE;
}

void FixCharging::unpack_restart(int nlocal, int nth) {
  // this fix's values among the atom's extra restart values (Atom::extra: per fix, a count first)
  double** extra = atom->extra;
  int m = 0;
  for (int i = 0; i < nth; ++i) m += static_cast<int>(extra[nlocal][m]);
  const int count = static_cast<int>(extra[nlocal][m]);
  ++m;
  for (int k = 0; k < 3; ++k) {
    m_frestart[nlocal][k] = extra[nlocal][m + k];
    m_fslow[nlocal][k] = count >= RESTART_SIZE ? extra[nlocal][m + 3 + k] : 0.0;
  }
  m_restore_forces = true;
}

int FixCharging::size_restart(int /*nlocal*/) { return RESTART_SIZE; }
int FixCharging::maxsize_restart() { return RESTART_SIZE; }

void FixCharging::write_restart(FILE* fp) {
  const double data[3] = {RESTART_LAYOUT_2, static_cast<double>(stats().collisions),
                          static_cast<double>(m_respa_loop)};  // (stats(): collective)
  if (comm->me == 0) {
    const int size = sizeof data;
    std::fwrite(&size, sizeof(int), 1, fp);
    std::fwrite(data, sizeof(double), 3, fp);
  }
}

void FixCharging::restart(char* buf) {
  double first = 0.0;
  std::memcpy(&first, buf, sizeof first);
  if (first == RESTART_LAYOUT_2) {
    double rest[2];
    std::memcpy(rest, buf + sizeof first, sizeof rest);
    m_collisions_restart = static_cast<std::int64_t>(rest[0]);
    m_restart_loop = static_cast<int>(rest[1]);
  } else {
    m_collisions_restart = static_cast<std::int64_t>(first);
    m_restart_loop = 1;
  }
  m_collisions_local = 0;
}

int FixCharging::pack_forward_comm(int n, int* list, double* buf, int /*pbc_flag*/,
                                   int* /*pbc*/) {
  const double* q = atom->q;
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const int j = list[k];
    buf[m++] = m_vpred[j][0];
    buf[m++] = m_vpred[j][1];
    buf[m++] = m_vpred[j][2];
    buf[m++] = q[j];
  }
  return m;
}

void FixCharging::unpack_forward_comm(int n, int first, double* buf) {
  double* q = atom->q;
  int m = 0;
  for (int i = first; i < first + n; ++i) {
    m_vpred[i][0] = buf[m++];
    m_vpred[i][1] = buf[m++];
    m_vpred[i][2] = buf[m++];
    q[i] = buf[m++];
  }
}

int FixCharging::pack_reverse_comm(int n, int first, double* buf) {
  int m = 0;
  for (int i = first; i < first + n; ++i) buf[m++] = m_dq[i];
  return m;
}

void FixCharging::unpack_reverse_comm(int n, int* list, double* buf) {
  for (int k = 0; k < n; ++k) m_dq[list[k]] += buf[k];
}

double FixCharging::memory_usage() {
  return static_cast<double>(m_nmax) * 13.0 * sizeof(double) +
         static_cast<double>(m_records.capacity()) * sizeof(CollisionRecord);
}

ContactStats FixCharging::stats() const {
  double sums[3] = {m_overlap_sum, m_sum_xi52, m_sum_xi2};
  long long counts[3] = {m_collisions_local, m_contacts, m_migrations};
  double gsums[3], gmax = 0.0;
  long long gcounts[3];
  MPI_Allreduce(sums, gsums, 3, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(counts, gcounts, 3, MPI_LONG_LONG, MPI_SUM, world);
  MPI_Allreduce(&m_max_overlap_now, &gmax, 1, MPI_DOUBLE, MPI_MAX, world);
  ContactStats s;
  s.collisions = m_collisions_restart + gcounts[0];
  s.contacts = gcounts[1];
  s.migrations = gcounts[2];
  s.overlap_sum = gsums[0];
  s.sum_xi_5_2 = gsums[1];
  s.sum_xi_2 = gsums[2];
  s.max_overlap = gmax;
  return s;
}

}  // namespace granagg::md::lammps
