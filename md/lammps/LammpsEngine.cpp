/// \file LammpsEngine.cpp
/// LAMMPS behind md::RunEngine (LammpsEngine.h).
#include "md/lammps/LammpsEngine.h"

#include <fcntl.h>
#include <library.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <toml++/toml.h>

#include "common/Csv.h"
#include "common/OutputPath.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/io/InitialState.h"
#include "md/lammps/FixCharging.h"

namespace granagg::md::lammps {

namespace fs = std::filesystem;
using common::formatReal;

namespace {

/// LAMMPS (built without exceptions) ends the process with exit(1) on an error, after writing
/// the error to its log. Rank 0 then prints that line on stderr, so that the cause is not only
/// in OUT/log.lammps (screen output is off).
std::string g_log_path;
bool g_run_finished = true;
extern "C" void reportLammpsError() {
  if (g_run_finished || g_log_path.empty()) return;
  std::ifstream in(g_log_path);
  std::string line, last;
  while (std::getline(in, line))
    if (line.rfind("ERROR", 0) == 0) last = line;
  std::fprintf(stderr, "granagg-lammps: LAMMPS stopped: %s (log: %s)\n",
               last.empty() ? "see its log" : last.c_str(), g_log_path.c_str());
}

void broadcast(std::string& s, MPI_Comm comm) {
  long long n = static_cast<long long>(s.size());
  MPI_Bcast(&n, 1, MPI_LONG_LONG, 0, comm);
  s.resize(static_cast<std::size_t>(n));
  if (n > 0) MPI_Bcast(s.data(), static_cast<int>(n), MPI_CHAR, 0, comm);
}

void broadcast(double& x, MPI_Comm comm) { MPI_Bcast(&x, 1, MPI_DOUBLE, 0, comm); }

void broadcast(long long& x, MPI_Comm comm) { MPI_Bcast(&x, 1, MPI_LONG_LONG, 0, comm); }

void broadcast(int& x, MPI_Comm comm) { MPI_Bcast(&x, 1, MPI_INT, 0, comm); }

/// Lines joined by '\n' and split again.
std::string joinLines(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + '\n';
  return s;
}
std::vector<std::string> splitLines(const std::string& s) {
  std::vector<std::string> lines;
  std::istringstream in(s);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

/// Rank 0's translation to every rank.
void broadcast(LammpsInput& in, MPI_Comm comm) {
  std::string commands = joinLines(in.commands), notes = joinLines(in.notes);
  broadcast(commands, comm);
  broadcast(notes, comm);
  broadcast(in.dt_reason, comm);
  broadcast(in.pair_style, comm);
  broadcast(in.dt, comm);
  long long steps = in.steps;
  broadcast(steps, comm);
  int coulomb = in.coulomb ? 1 : 0;
  broadcast(coulomb, comm);
  broadcast(in.respa_loop, comm);
  CoulombSetup& cs = in.coulomb_setup;
  broadcast(cs.method, comm);
  double reals[5] = {cs.alpha, cs.r_cut, cs.estimated_error, cs.sum_q2_design, cs.r_fast};
  int ints[5] = {cs.mesh, cs.order, cs.k_max, cs.every, cs.every_max};
  MPI_Bcast(reals, 5, MPI_DOUBLE, 0, comm);
  MPI_Bcast(ints, 5, MPI_INT, 0, comm);
  cs.alpha = reals[0];
  cs.r_cut = reals[1];
  cs.estimated_error = reals[2];
  cs.sum_q2_design = reals[3];
  cs.r_fast = reals[4];
  cs.mesh = ints[0];
  cs.order = ints[1];
  cs.k_max = ints[2];
  cs.every = ints[3];
  cs.every_max = ints[4];
  in.commands = splitLines(commands);
  in.notes = splitLines(notes);
  in.steps = steps;
  in.coulomb = coulomb != 0;
}

/// What rank 0 did, on every rank: status 0 goes on; 2 throws std::invalid_argument, 1
/// std::runtime_error, with rank 0's message.
void agree(int status, std::string message, MPI_Comm comm) {
  broadcast(status, comm);
  if (status == 0) return;
  broadcast(message, comm);
  if (status == 2) throw std::invalid_argument(message);
  throw std::runtime_error(message);
}

/// Runs `work` on rank 0 and agree()s on its outcome.
template <class Work>
void onRankZero(int rank, MPI_Comm comm, Work&& work) {
  int status = 0;
  std::string message;
  if (rank == 0) {
    try {
      work();
    } catch (const std::invalid_argument& e) {
      status = 2;
      message = e.what();
    } catch (const std::exception& e) {
      status = 1;
      message = e.what();
    }
  }
  agree(status, message, comm);
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << text;
  f.close();
  if (!f) throw std::runtime_error("cannot write " + path.string());
}

/// fsync(2) of a file or folder: what is renamed into place is on disk first.
void syncToDisk(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw std::runtime_error("cannot open " + path.string() + " to sync it");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) throw std::runtime_error("cannot sync " + path.string() + " to disk");
}

bool isRestartFile(const std::string& name) {
  return name.rfind("checkpoint-", 0) == 0 &&
         (name.size() > 8 && (name.compare(name.size() - 8, 8, ".restart") == 0 ||
                              name.find(".restart.partial") != std::string::npos));
}

std::string ranksText(int n) {
  return std::to_string(n) + (n == 1 ? " MPI rank" : " MPI ranks");
}

std::unique_ptr<LAMMPS_NS::LAMMPS> newLammps(MPI_Comm comm) {
  // the log is opened by begin(), in the output folder (which does not exist yet)
  std::vector<std::string> args = {"granagg-lammps", "-log", "none", "-screen", "none",
                                   "-nocite"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  auto lmp =
      std::make_unique<LAMMPS_NS::LAMMPS>(static_cast<int>(argv.size()), argv.data(), comm);
  FixCharging::registerStyle(lmp.get());
  return lmp;
}

}  // namespace

LammpsEngine::LammpsEngine(MdConfig& cfg, const fs::path& folder, bool record_collisions,
                           const std::string& command_line, MPI_Comm comm)
    : m_comm(comm), m_record_collisions(record_collisions) {
  MPI_Comm_rank(comm, &m_rank);
  MPI_Comm_size(comm, &m_ranks);
  std::string folder_text, config_text;
  double box = 0.0;
  long long N = 0;
  onRankZero(m_rank, comm, [&] {
    common::checkOutputFolder(folder);  // (rank 0 writes it)
    m_folder = fs::absolute(folder);
    // (a bad key is named before the initial state is read or drawn)
    checkLammpsCanRun(cfg);
    m_initial = prepareInitialState(cfg);
    m_input = translateConfig(cfg, m_initial, (m_folder / "initial.data").string(),
                              record_collisions);
    m_input_text = m_input.text(
        "# LAMMPS input generated by granagg-lammps " + common::versionString() +
        "\n# command: " + command_line +
        "\n# fix granagg/charging is registered by granagg-lammps (LAMMPS has no such style)."
        "\n# granagg-lammps runs the final `run` in chunks between its outputs "
        "(run N pre no post no),\n# which changes no result.\n");
    folder_text = m_folder.string();
    config_text = toToml(cfg);
    box = m_initial.box;
    N = static_cast<long long>(m_initial.size());
  });
  broadcast(folder_text, comm);
  broadcast(config_text, comm);
  broadcast(box, comm);
  broadcast(N, comm);
  broadcast(m_input, comm);
  broadcast(m_input_text, comm);
  if (m_rank != 0) {
    m_folder = folder_text;
    cfg = parseConfigString(config_text, "(granagg-lammps: the configuration of rank 0)");
  }
  m_N = static_cast<std::size_t>(N);
  m_box = box;
  m_cfg = cfg;
  m_lmp = newLammps(comm);
}

LammpsEngine::LammpsEngine(const MdConfig& cfg, const fs::path& folder,
                           const LammpsCheckpoint& ck, MPI_Comm comm)
    : m_comm(comm), m_resumed(true), m_record_collisions(ck.record_collisions), m_cfg(cfg) {
  MPI_Comm_rank(comm, &m_rank);
  MPI_Comm_size(comm, &m_ranks);
  std::string folder_text;
  if (m_rank == 0) folder_text = fs::absolute(folder).string();
  broadcast(folder_text, comm);
  m_folder = folder_text;
  m_N = ck.N;
  m_box = ck.box;
  m_first_step = ck.step;
  // (the same on every rank: everything comes from the checkpoint and the configuration)
  m_input = translateRestart(cfg, ck.N, ck.box, ck.sum_q2_design,
                             (m_folder / ck.restart_file).string(), ck.record_collisions);
  m_input_text = m_input.text("# granagg-lammps continues the run from " + ck.restart_file +
                              " (step " + std::to_string(ck.step) + ")\n");
  m_lmp = newLammps(comm);
}

LammpsEngine::~LammpsEngine() {
  m_lmp.reset();
  if (m_rank == 0) g_run_finished = true;
}

void LammpsEngine::begin(const fs::path& /*folder: the one given to the constructor*/) {
  onRankZero(m_rank, m_comm, [&] {
    if (m_resumed) return;
    writeText(m_folder / "initial.data", lammpsDataText(m_initial));
    writeText(m_folder / "lammps.in", m_input_text);
    // restart files of a run this one overwrites (--force) are not this run's
    for (const auto& entry : fs::directory_iterator(m_folder))
      if (isRestartFile(entry.path().filename().string())) fs::remove(entry.path());
  });
  m_initial = Frame{};
  const std::string log = (m_folder / "log.lammps").string();
  if (m_rank == 0) {
    g_log_path = log;
    g_run_finished = false;
    static bool registered = false;
    if (!registered) std::atexit(reportLammpsError);
    registered = true;
  }
  m_lmp->input->one("log " + log + (m_resumed ? " append" : ""));
  for (const auto& c : m_input.commands) m_lmp->input->one(c);
  const int ifix = m_lmp->modify->find_fix(CHARGING_FIX_ID);
  m_fix = ifix >= 0 ? dynamic_cast<FixCharging*>(m_lmp->modify->fix[ifix]) : nullptr;
  if (!m_fix) throw std::logic_error("granagg-lammps: the input defines no fix granagg/charging");
  // the setup: forces and energies of the first state (from a restart file: the stored forces)
  m_lmp->input->one("run 0 post no");
}

void LammpsEngine::run(std::int64_t steps) {
  // LAMMPS's run takes an int: chunks of at most 1e9 steps
  while (steps > 0) {
    const std::int64_t n = std::min<std::int64_t>(steps, 1000000000);
    // (rRESPA refuses `pre no`: each run starts with its full setup, in which the fix puts the
    // kept forces of the state back, FixCharging.h)
    m_lmp->input->one("run " + std::to_string(n) +
                      (m_input.respa_loop > 1 ? " post no" : " pre no post no"));
    steps -= n;
  }
}

std::int64_t LammpsEngine::step() const {
  return m_fix ? static_cast<std::int64_t>(m_lmp->update->ntimestep) : m_first_step;
}

FixCharging& LammpsEngine::fix() const {
  if (!m_fix) throw std::logic_error("LammpsEngine::fix() before begin()");
  return *m_fix;
}

template <class Fill>
std::vector<double> LammpsEngine::gather(int width, Fill fill) const {
  const LAMMPS_NS::Atom* atom = m_lmp->atom;
  const int nlocal = atom->nlocal;
  const std::size_t w = static_cast<std::size_t>(width) + 1;  // the id first
  std::vector<double> mine(static_cast<std::size_t>(nlocal) * w);
  for (int i = 0; i < nlocal; ++i) {
    double* row = &mine[static_cast<std::size_t>(i) * w];
    row[0] = static_cast<double>(atom->tag[i]);
    fill(i, row + 1);
  }
  const int n = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(m_ranks)), displs(counts.size());
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, m_comm);
  std::vector<double> all;
  if (m_rank == 0) {
    long long total = 0;
    for (int r = 0; r < m_ranks; ++r) {
      displs[static_cast<std::size_t>(r)] = static_cast<int>(total);
      total += counts[static_cast<std::size_t>(r)];
    }
    if (total != static_cast<long long>(m_N * w))
      throw std::runtime_error("granagg-lammps: gathered " + std::to_string(total / w) +
                               " particles of " + std::to_string(m_N));
    all.resize(static_cast<std::size_t>(total));
  }
  MPI_Gatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE,
              0, m_comm);
  return all;
}

Frame LammpsEngine::frame(StateKind) const {
  const LAMMPS_NS::Atom* atom = m_lmp->atom;
  const double L = m_box;
  const auto rows = gather(10, [&](int i, double* row) {
    // wrapped into [0, L) with the image counts adjusted (LAMMPS remaps atoms into the box only
    // when it rebuilds its lists); positions in the box are kept bit for bit
    const LAMMPS_NS::imageint image = atom->image[i];
    const int img[3] = {static_cast<int>((image & IMGMASK) - IMGMAX),
                        static_cast<int>((image >> IMGBITS & IMGMASK) - IMGMAX),
                        static_cast<int>((image >> IMG2BITS) - IMGMAX)};
    for (int k = 0; k < 3; ++k) {
      double x = atom->x[i][k];
      int crossed = 0;
      if (!(x >= 0.0 && x < L)) {
        const double s = std::floor(x / L);
        x -= s * L;
        crossed = static_cast<int>(s);
        if (x >= L) {  // (rounding)
          x -= L;
          ++crossed;
        }
        if (x < 0.0) x = 0.0;
      }
      row[k] = x;
      row[3 + k] = img[k] + crossed;
      row[6 + k] = atom->v[i][k];
    }
    row[9] = atom->q[i];
  });
  Frame f;
  f.step = step();
  f.time = time();
  f.box = L;
  if (m_rank != 0) return f;
  for (auto* v : {&f.x, &f.y, &f.z, &f.vx, &f.vy, &f.vz, &f.charge}) v->assign(m_N, 0.0);
  for (auto* v : {&f.ix, &f.iy, &f.iz}) v->assign(m_N, 0);
  std::vector<char> seen(m_N, 0);
  for (std::size_t r = 0; r < m_N; ++r) {
    const double* row = &rows[r * 11];
    const auto id = static_cast<std::size_t>(row[0]) - 1;
    if (id >= m_N || seen[id]) throw std::runtime_error("granagg-lammps: atom ids are not 1..N");
    seen[id] = 1;
    f.x[id] = row[1];
    f.y[id] = row[2];
    f.z[id] = row[3];
    f.ix[id] = static_cast<std::int32_t>(row[4]);
    f.iy[id] = static_cast<std::int32_t>(row[5]);
    f.iz[id] = static_cast<std::int32_t>(row[6]);
    f.vx[id] = row[7];
    f.vy[id] = row[8];
    f.vz[id] = row[9];
    f.charge[id] = row[10];
  }
  return f;
}

Forces LammpsEngine::forces(StateKind) const {
  const LAMMPS_NS::Atom* atom = m_lmp->atom;
  const auto rows = gather(3, [&](int i, double* row) {
    for (int k = 0; k < 3; ++k) row[k] = atom->f[i][k];
  });
  if (m_rank != 0) return {};
  Forces f;
  std::vector<double>* comp[3] = {&f.x, &f.y, &f.z};
  for (auto* c : comp) c->resize(m_N);
  for (std::size_t r = 0; r < m_N; ++r) {
    const double* row = &rows[r * 4];
    const auto id = static_cast<std::size_t>(row[0]) - 1;
    for (std::size_t k = 0; k < 3; ++k) (*comp[k])[id] = row[1 + k];
  }
  return f;
}

Observables LammpsEngine::observables() const {
  const LAMMPS_NS::Atom* atom = m_lmp->atom;
  double s[7] = {0, 0, 0, 0, 0, 0, 0};  // sum v (3), sum v^2, sum q, sum |q|, sum |v|
  double qmax = 0.0;
  for (int i = 0; i < atom->nlocal; ++i) {
    const double* v = atom->v[i];
    s[0] += v[0];
    s[1] += v[1];
    s[2] += v[2];
    const double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    s[3] += v2;
    s[4] += atom->q[i];
    s[5] += std::fabs(atom->q[i]);
    s[6] += std::sqrt(v2);
    qmax = std::max(qmax, std::fabs(atom->q[i]));
  }
  double g[7], gqmax = 0.0;
  MPI_Allreduce(s, g, 7, MPI_DOUBLE, MPI_SUM, m_comm);
  MPI_Allreduce(&qmax, &gqmax, 1, MPI_DOUBLE, MPI_MAX, m_comm);
  const ContactStats c = m_fix->stats();
  const double N = static_cast<double>(m_N);
  const double p2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
  Observables o;
  o.step = step();
  o.time = time();
  o.temperature = (g[3] - p2 / N) / (3.0 * N);  // T_g = (1/3N) sum (v - <v>)^2
  o.kinetic_energy = 0.5 * g[3];
  o.elastic_energy = m_cfg.contact.model == "hertz" ? 0.4 * m_cfg.contact.E * c.sum_xi_5_2
                                                    : 0.5 * m_cfg.contact.stiffness * c.sum_xi_2;
  for (int k = 0; k < 3; ++k) o.momentum[k] = g[k];
  o.momentum_abs_sum = g[6];
  o.contacts_per_particle = 2.0 * static_cast<double>(c.contacts) / N;
  o.collisions = c.collisions;
  o.mean_overlap = c.contacts > 0 ? c.overlap_sum / static_cast<double>(c.contacts) : 0.0;
  o.max_overlap = c.max_overlap;
  o.total_charge = g[4];
  o.mean_abs_charge = g[5] / N;
  o.max_abs_charge = gqmax;
  // LAMMPS tallies the energy at the last step of every run: pair coul/long + kspace
  o.coulomb_energy = m_input.coulomb ? lammps_get_thermo(m_lmp.get(), "pe") : 0.0;
  return o;
}

const CoulombSetup* LammpsEngine::coulombSetup() const {
  return m_input.coulomb ? &m_input.coulomb_setup : nullptr;
}

std::int64_t LammpsEngine::neighborBuilds() const {
  return m_fix ? static_cast<std::int64_t>(m_lmp->neighbor->ncalls) : 0;
}

std::string LammpsEngine::description() const {
  return std::string("LAMMPS ") + m_lmp->version + " on " + ranksText(m_ranks);
}

std::vector<std::pair<std::string, std::string>> LammpsEngine::parameters() const {
  return {{"engine", std::string("LAMMPS ") + m_lmp->version},
          {"mpi_ranks", std::to_string(m_ranks)},
          {"lammps_input", m_input_text}};
}

bool LammpsEngine::anyRank(bool local) const {
  int mine = local ? 1 : 0, any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_LOR, m_comm);
  return any != 0;
}

fs::path LammpsEngine::checkpointPath(const fs::path& folder) const {
  return folder / LAMMPS_CHECKPOINT_FILE;
}

void LammpsEngine::saveCheckpoint(const fs::path& /*folder: the constructor's*/,
                                  const RunFields& run) {
  const std::int64_t now = step();
  const std::string name = "checkpoint-" + std::to_string(now) + ".restart";
  const fs::path partial = m_folder / (name + ".partial");
  // write_restart without noinit runs its own init() and setup_pre_exchange(), in which fix
  // neigh/history rebuilds its per-atom contact history from a neighbour list that init() has
  // invalidated: "Neighbor history overflow", or a fault in its reverse communication, with
  // contacts. Instead a `run 0` (LAMMPS's setup: atoms wrapped into the box and moved to their
  // ranks, the list rebuilt, the history made per atom again by fix neigh/history's post_run)
  // brings the state into the form a restart file needs, and write_restart then writes it as
  // it is. atom->f does not follow the atoms there: the fix keeps the state's forces in its
  // migrating per-atom array first and puts them back in setup (FixCharging.h).
  m_fix->keepForcesForRestart();
  m_lmp->input->one("run 0 post no");
  m_lmp->input->one("write_restart " + partial.string() + " noinit");  // rank 0 writes it
  onRankZero(m_rank, m_comm, [&] {
    syncToDisk(partial);
    fs::rename(partial, m_folder / name);
    toml::table t{{"format", "granagg-lammps-checkpoint"},
                  {"format_version", 1},
                  {"restart_file", name},
                  {"step", static_cast<std::int64_t>(now)},
                  {"N", static_cast<std::int64_t>(m_N)},
                  {"box", formatReal(m_box)},
                  {"sum_q2_design", formatReal(m_input.coulomb_setup.sum_q2_design)},
                  {"record_collisions", m_record_collisions},
                  {"lammps_version", std::string(m_lmp->version)},
                  {"mpi_ranks", m_ranks},
                  {"creator", common::versionString()},
                  {"seed", std::to_string(run.seed)},
                  {"frames_written", static_cast<std::int64_t>(run.frames_written)},
                  {"config_toml", run.config_toml}};
    std::ostringstream text;
    text << "# granagg-lammps checkpoint (docs/lammps.md): the run's fields; the state is the "
            "LAMMPS restart\n# file restart_file (atoms, fix granagg/charging's forces and "
            "collision count).\n"
         << t << '\n';
    const fs::path final_path = checkpointPath(m_folder);
    const fs::path aside = final_path.string() + ".partial";
    writeText(aside, text.str());
    syncToDisk(aside);
    fs::rename(aside, final_path);
    syncToDisk(m_folder);
    for (const auto& entry : fs::directory_iterator(m_folder)) {
      const std::string file = entry.path().filename().string();
      if (file != name && isRestartFile(file)) fs::remove(entry.path());
    }
  });
}

LammpsCheckpoint readLammpsCheckpoint(const fs::path& folder, MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const fs::path path = folder / LAMMPS_CHECKPOINT_FILE;
  std::string text;
  LammpsCheckpoint ck;
  auto parse = [&] {
    const std::string where = path.string();
    toml::table t;
    try {
      t = toml::parse(std::string_view(text), std::string_view(where));
    } catch (const toml::parse_error& e) {
      throw std::runtime_error(where + ": not a granagg-lammps checkpoint (" +
                               std::string(e.description()) + ")");
    }
    auto need = [&](const char* key) -> const toml::node& {
      const toml::node* n = t.get(key);
      if (!n)
        throw std::runtime_error(where + ": not a granagg-lammps checkpoint (no " + key + ")");
      return *n;
    };
    auto text_of = [&](const char* key) {
      const auto v = need(key).value<std::string>();
      if (!v) throw std::runtime_error(where + ": " + key + " is not a string");
      return *v;
    };
    auto int_of = [&](const char* key) {
      const auto v = need(key).value<std::int64_t>();
      if (!v || *v < 0) throw std::runtime_error(where + ": " + key + " is not a count");
      return *v;
    };
    auto real_of = [&](const char* key) {
      const std::string s = text_of(key);
      char* end = nullptr;
      const double x = std::strtod(s.c_str(), &end);
      if (end == s.c_str() || *end != '\0') throw std::runtime_error(where + ": bad " + key);
      return x;
    };
    if (text_of("format") != "granagg-lammps-checkpoint" || int_of("format_version") != 1)
      throw std::runtime_error(where + ": not a granagg-lammps checkpoint of format version 1");
    ck.restart_file = text_of("restart_file");
    if (!isRestartFile(ck.restart_file) || ck.restart_file.find('/') != std::string::npos)
      throw std::runtime_error(where + ": restart_file names no restart file in the folder");
    ck.step = int_of("step");
    ck.N = static_cast<std::size_t>(int_of("N"));
    ck.box = real_of("box");
    ck.sum_q2_design = real_of("sum_q2_design");
    const auto record = need("record_collisions").value<bool>();
    if (!record) throw std::runtime_error(where + ": record_collisions is not true or false");
    ck.record_collisions = *record;
    ck.run_fields.config_toml = text_of("config_toml");
    ck.run_fields.seed = std::strtoull(text_of("seed").c_str(), nullptr, 10);
    ck.run_fields.frames_written = static_cast<std::uint64_t>(int_of("frames_written"));
  };
  onRankZero(rank, comm, [&] {
    if (!fs::exists(path))
      throw std::invalid_argument(
          "--restart: no checkpoint at " + path.string() +
          (fs::exists(path.parent_path() / "traj.h5")
               ? ": the run stopped before its first checkpoint, so there is nothing to "
                 "continue; start it again with its command and --force"
               : std::string()));
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    if (!in) throw std::runtime_error("cannot read " + path.string());
    text = s.str();
    parse();
    if (!fs::exists(folder / ck.restart_file))
      throw std::runtime_error(path.string() + " names " + ck.restart_file +
                               ", which is not in the folder");
  });
  broadcast(text, comm);
  if (rank != 0) parse();
  return ck;
}

}  // namespace granagg::md::lammps
