#include "md/run/Simulation.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>
#include <set>
#include <stdexcept>

#include "common/Csv.h"
#include "common/FolderLock.h"
#include "common/H5mdReader.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/io/Checkpoint.h"
#include "md/io/H5mdWriter.h"
#include "md/io/InitialState.h"

namespace granagg::md {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

/// The frame to write: the physical state, with its per-particle forces when output.write_forces
/// (collective; empty on ranks that do not write).
Frame outputFrame(const RunEngine& engine, const MdConfig& cfg) {
  Frame f = engine.frame(StateKind::Physical);
  if (cfg.output.write_forces) {
    const std::vector<double> all = engine.forces(StateKind::Physical);
    const std::size_t N = engine.size();
    if (all.size() != 3 * N) return f;  // a rank that does not write
    f.fx.assign(all.begin(), all.begin() + N);
    f.fy.assign(all.begin() + N, all.begin() + 2 * N);
    f.fz.assign(all.begin() + 2 * N, all.end());
  }
  return f;
}

/// The observables as /granagg/observables stores them (docs/model.md section 10).
std::vector<std::pair<std::string, double>> observableRow(const Observables& o) {
  return {{"temperature", o.temperature},
          {"kinetic_energy", o.kinetic_energy},
          {"elastic_energy", o.elastic_energy},
          {"momentum_x", o.momentum[0]},
          {"momentum_y", o.momentum[1]},
          {"momentum_z", o.momentum[2]},
          {"contacts_per_particle", o.contacts_per_particle},
          {"collisions", static_cast<double>(o.collisions)},
          {"mean_overlap", o.mean_overlap},
          {"total_charge", o.total_charge},
          {"mean_abs_charge", o.mean_abs_charge},
          {"max_abs_charge", o.max_abs_charge},
          {"coulomb_energy", o.coulomb_energy},
          {"max_overlap", o.max_overlap}};
}

/// /parameters of a new trajectory: every configuration key, then what the run chose.
std::vector<std::pair<std::string, std::string>> parameters(const MdConfig& cfg,
                                                            const RunEngine& engine,
                                                            const std::string& command_line,
                                                            const std::string& dt_reason) {
  auto params = flatten(cfg);
  params.emplace_back("version", common::versionString());
  params.emplace_back("command", command_line);
  params.emplace_back("backend", engine.description());
  for (auto& p : engine.parameters()) params.push_back(std::move(p));
  params.emplace_back("dt", common::formatReal(engine.dt()));
  params.emplace_back("dt_reason", dt_reason);
  if (const CoulombSetup* cs = engine.coulombSetup()) {  // chosen for coulomb.accuracy
    params.emplace_back("coulomb_alpha", common::formatReal(cs->alpha));
    params.emplace_back("coulomb_r_cut_used", common::formatReal(cs->r_cut));
    params.emplace_back("coulomb_mesh_used", std::to_string(cs->mesh));
    params.emplace_back("coulomb_order_used", std::to_string(cs->order));
    params.emplace_back("coulomb_k_max", std::to_string(cs->k_max));
    params.emplace_back("coulomb_estimated_error", common::formatReal(cs->estimated_error));
    params.emplace_back("coulomb_sum_q2_design", common::formatReal(cs->sum_q2_design));
    params.emplace_back("coulomb_r_fast_used", common::formatReal(cs->r_fast));
    params.emplace_back("coulomb_every_used", std::to_string(cs->every));
    params.emplace_back("coulomb_every_max_used", std::to_string(cs->every_max));
  }
  return params;
}

/// profile.csv: one row, seconds per phase of the loop (`other` = the loop's time in no phase:
/// observables, output, checkpoints; column names are the phase names in snake case), then the
/// list builds and slow Coulomb evaluations; the provenance holds box, dt, the end time and the
/// Coulomb set-up, so that benchmark scripts need not read the log.
void writeProfile(const RunEngine& engine, const fs::path& path, const std::string& command_line,
                  std::int64_t steps, double loop_seconds, std::int64_t neighbor_builds,
                  std::int64_t slow_evaluations) {
  std::vector<std::string> columns = {"steps", "N", "loop_s"};
  std::vector<double> row = {static_cast<double>(steps), static_cast<double>(engine.size()),
                             loop_seconds};
  double sum = 0.0;
  for (const auto& [name, s] : engine.phaseSeconds()) {
    std::string col;  // "PPPM k-space" -> "pppm_k_space"
    for (char c : name)
      col += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(c)) : '_';
    while (col.find("__") != std::string::npos) col.erase(col.find("__"), 1);
    if (!col.empty() && col.back() == '_') col.pop_back();
    columns.push_back(col + "_s");
    row.push_back(s);
    sum += s;
  }
  columns.push_back("other_s");
  row.push_back(loop_seconds - sum);
  columns.push_back("neighbor_builds");
  row.push_back(static_cast<double>(neighbor_builds));
  columns.push_back("slow_evaluations");
  row.push_back(static_cast<double>(slow_evaluations));
  common::Provenance prov(command_line);
  prov.add("version", common::versionString());
  prov.add("backend", engine.description());
  // the set-up the timings belong to, for scripts (the log lines are for people)
  prov.add("box_L", engine.box());
  prov.add("dt", engine.dt());
  prov.add("t_end", engine.time());
  if (const CoulombSetup* cs = engine.coulombSetup()) {
    prov.add("coulomb_method", cs->method);
    prov.add("coulomb_alpha", cs->alpha);
    prov.add("coulomb_r_cut", cs->r_cut);
    if (cs->method == "pppm") {
      prov.add("coulomb_mesh", cs->mesh);
      prov.add("coulomb_order", cs->order);
    } else {
      prov.add("coulomb_k_max", cs->k_max);
    }
    prov.add("coulomb_estimated_error", cs->estimated_error);
    prov.add("coulomb_r_fast", cs->r_fast);
    prov.add("coulomb_every", cs->every);
    prov.add("coulomb_every_max", cs->every_max);
  }
  common::CsvWriter w(path.string(), prov, columns, /*overwrite=*/true);
  w.row(row);
  w.close();
}

// Bounds of what a run may ask for (issue 17): beyond them a typo (t_end = 1e300, a frame every
// 1e-12) would overflow the step counter or hang in building the frame schedule.
constexpr double MAX_STEPS = 1e12;  // ~30 years at 1e3 steps/s
constexpr double MAX_FRAMES = 1e6;  // ~a petabyte at N = 50016

/// A number for an error message: four significant digits.
std::string people(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", x);
  return b;
}

/// Memory a run needs per particle, at least: the peak resident memory of `granagg md` (CPU
/// build) grows by 616 B per particle neutral and by about 2.6 kB with Coulomb forces at K = 5
/// (N = 2e4 to 8e4, phi = 0.076), rounded down. Neutral: the engine's particle arrays (positions
/// and charge 32 B, velocities and forces 48 B, image counts and ids 16 B), their sorted copies,
/// the contact list (rows of at least 16 entries) and cells, the host frames of the output;
/// Coulomb: the real-space list (~120 entries a particle at r_cut = 5) and the mesh on top.
constexpr double BYTES_PER_PARTICLE = 500.0;
constexpr double COULOMB_BYTES_PER_PARTICLE = 1500.0;

/// A size for people: "23.4 GB", "1.2 TB".
std::string gigabytes(double bytes) {
  char b[32];
  if (bytes >= 1e12)
    std::snprintf(b, sizeof b, "%.3g TB", bytes / 1e12);
  else
    std::snprintf(b, sizeof b, "%.3g GB", bytes / 1e9);
  return b;
}

/// Refuses a system.N whose run cannot fit in this machine's memory (sysconf), before anything
/// is allocated: otherwise the allocation fails (std::bad_alloc) or the kernel kills the process.
void checkMemory(const MdConfig& c) {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return;  // not known here: nothing to compare with
  const double machine = static_cast<double>(pages) * static_cast<double>(page);
  const double per_particle =
      BYTES_PER_PARTICLE + (c.coulomb.K > 0.0 ? COULOMB_BYTES_PER_PARTICLE : 0.0);
  const double need = per_particle * c.system.N;
  const std::string what = c.coulomb.K > 0.0 ? "arrays, neighbour lists and the Coulomb mesh"
                                             : "arrays and neighbour lists";
  if (need > machine)
    throw std::invalid_argument(
        "system.N = " + std::to_string(c.system.N) + " needs about " + gigabytes(need) +
        " of memory (at least " + people(per_particle) + " bytes per particle for the engine's " +
        what + "), more than this machine's " + gigabytes(machine) +
        ": lower system.N (to at most " + people(std::floor(machine / per_particle)) + " here)");
}

/// The time step, the schedule and the memory that `config` asks for, checked before anything is
/// built or written: a positive finite dt, a step count that fits, a bounded number of frames,
/// a system.N that fits in memory (checkMemory).
void checkSchedule(const MdConfig& c) {
  std::string why;
  const double dt = Engine::chooseTimeStep(c, &why);
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("integrator.dt: the time step is " + people(dt) + " (" + why +
                                "): it must be positive and finite; check contact.* or give "
                                "integrator.dt");
  const double steps = c.run.t_end / dt;
  if (!(steps <= MAX_STEPS))
    throw std::invalid_argument("run.t_end = " + people(c.run.t_end) + " at dt = " + people(dt) +
                                " is " + people(steps) + " steps, more than 1e12: lower run.t_end");
  double frames = 0.0;
  if (c.output.frames_per_decade > 0) {
    const double t0 = std::max(0.01, dt);
    frames += c.output.frames_per_decade * std::max(0.0, std::log10(c.run.t_end / t0));
  }
  if (c.output.frame_interval > 0.0) frames += c.run.t_end / c.output.frame_interval;
  if (!(frames <= MAX_FRAMES))
    throw std::invalid_argument(
        "output.frames_per_decade = " + std::to_string(c.output.frames_per_decade) +
        " and output.frame_interval = " + people(c.output.frame_interval) + " ask for " +
        people(std::round(frames)) + " frames up to run.t_end = " + people(c.run.t_end) +
        ", more than 1e6: space them further apart");
  checkMemory(c);
}

}  // namespace

struct Simulation::Impl {
  MdConfig cfg;
  fs::path out;
  RunOptions options;
  bool resumed = false;
  std::string dt_reason;
  std::int64_t last = 0;
  std::unique_ptr<RunEngine> engine;
  std::unique_ptr<H5mdWriter> writer;  // on the writing rank
  std::vector<std::int64_t> frames;  // frameSteps()
  std::size_t next_frame = 0;        // index into frames of the next frame to write
  std::vector<std::shared_ptr<Reporter>> reporters;
  std::int64_t last_checkpoint_step = -1;  // -1: none written by this process or found
  Observables observables;                 // at the end of the last chunk

  std::size_t frames_written = 0;          // frames in the trajectory (counted on every rank)
  bool at_end = false;                     // resumed at run.t_end: nothing to do, no file opened
  std::optional<common::FolderLock> lock;  // held from the first write to the end of the run
  struct stat traj_stat {};                // the trajectory as this run last left it

  fs::path trajectory() const { return out / "traj.h5"; }
  fs::path checkpointFile() const { return engine->checkpointPath(out); }

  /// The trajectory changed behind the run's back (removed, replaced, truncated by another
  /// program; other granagg commands are kept out by the folder lock): the run stops, and never
  /// reports success for a file it cannot vouch for.
  [[noreturn]] void trajectoryDamaged(const std::string& what) const {
    throw std::runtime_error(
        trajectory().string() + " was damaged while this run wrote it (" + what +
        "); its frames cannot be trusted. Start the run again into a new folder" +
        (last_checkpoint_step >= 0
             ? " (" + checkpointFile().filename().string() + " holds step " +
                   std::to_string(last_checkpoint_step) + ", but the trajectory up to it is lost)"
             : ""));
  }

  void watchTrajectory() {
    if (::stat(trajectory().c_str(), &traj_stat) != 0) trajectoryDamaged("it is gone");
  }

  /// Called between chunks: the file must be the one this run opened, and no shorter. (The HDF5
  /// library only ever extends a file it writes.)
  void checkTrajectory() {
    struct stat now {};
    if (::stat(trajectory().c_str(), &now) != 0) trajectoryDamaged("it was removed");
    if (now.st_ino != traj_stat.st_ino || now.st_dev != traj_stat.st_dev)
      trajectoryDamaged("another file took its name");
    if (now.st_size < traj_stat.st_size)
      trajectoryDamaged("its size fell from " + std::to_string(traj_stat.st_size) + " to " +
                        std::to_string(now.st_size) + " bytes");
    traj_stat = now;
  }

  /// After the writer closed the file: it reads back whole, with every frame written.
  void verifyTrajectory(std::size_t frames_written) const {
    try {
      const common::H5mdReader reader(trajectory().string());
      if (reader.frames() != frames_written)
        trajectoryDamaged("it reads back with " + std::to_string(reader.frames()) +
                          " frames of the " + std::to_string(frames_written) + " written");
      if (frames_written > 0) {
        reader.readFrame(0);
        reader.readFrame(frames_written - 1);
      }
    } catch (const std::runtime_error& e) {
      if (std::string(e.what()).find("was damaged while") != std::string::npos) throw;
      trajectoryDamaged(std::string("it cannot be read back: ") + e.what());
    }
  }

  /// engine, dt, last step and frame schedule (both start() and resume())
  void setUp(std::unique_ptr<RunEngine> e) {
    engine = std::move(e);
    engine->enableProfile(options.profile);
    Engine::chooseTimeStep(cfg, &dt_reason);
    last = static_cast<std::int64_t>(std::llround(cfg.run.t_end / engine->dt()));
    frames = Simulation::frameSteps(cfg, engine->dt(), last);
    next_frame = static_cast<std::size_t>(
        std::upper_bound(frames.begin(), frames.end(), engine->step()) - frames.begin());
  }

  /// The engine's checkpoint with the run's fields (collective).
  void checkpoint() {
    if (writer) writer->flush();
    CheckpointExtra run;
    run.config_toml = toToml(cfg);
    run.seed = cfg.system.seed;
    run.frames_written = writer ? writer->frames() : frames_written;
    run.next_frame_index = next_frame;
    engine->saveCheckpoint(out, run);
    last_checkpoint_step = engine->step();
  }

  /// The frame at the engine's step (collective), written on the writing rank.
  void writeFrame() {
    const Frame f = outputFrame(*engine, cfg);
    if (writer) writer->writeFrame(f);
    ++frames_written;
  }
};

namespace {

/// Runs `check` on the rank that writes files; then every rank throws if it threw there. The
/// writing rank rethrows its own exception (the message main() prints); the others throw the same
/// kind (std::invalid_argument: bad input, exit 2; else std::runtime_error), so that no rank goes
/// on into a collective call alone. Without MPI (anyRank is the identity) this is `check()`.
template <class Check>
void onWritingRank(const RunEngine& engine, Check&& check) {
  std::exception_ptr failure;
  bool bad_input = false;
  if (engine.writesFiles()) {
    try {
      check();
    } catch (const std::invalid_argument&) {
      failure = std::current_exception();
      bad_input = true;
    } catch (...) {
      failure = std::current_exception();
    }
  }
  const bool any_bad_input = engine.anyRank(bad_input);
  const bool any_failure = engine.anyRank(failure != nullptr);
  if (failure) std::rethrow_exception(failure);
  if (any_bad_input)
    throw std::invalid_argument(
        "refused by the rank that writes the output (its message says why)");
  if (any_failure)
    throw std::runtime_error("failed on the rank that writes the output (its message says why)");
}

/// The checks of a new run's output folder (before anything is built or written).
void checkNewFolder(const fs::path& out, const RunOptions& options) {
  if (fs::exists(out) && !fs::is_directory(out))  // (--force would not help: say what it is)
    throw std::invalid_argument("--out '" + out.string() +
                                "' is a file, not a folder; a run writes a folder");
  // a folder in use by another command is refused before anything else, even with --force
  common::FolderLock::checkAvailable(out, options.overwrite);
  if (fs::exists(out) && !fs::is_empty(out) && !options.overwrite)
    throw std::invalid_argument("output folder '" + out.string() +
                                "' exists and is not empty; choose another --out or pass --force "
                                "to overwrite it");
}

}  // namespace

Simulation::Simulation(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
Simulation::Simulation(Simulation&&) noexcept = default;
Simulation& Simulation::operator=(Simulation&&) noexcept = default;
Simulation::~Simulation() = default;

std::unique_ptr<Simulation::Impl> Simulation::checkedRun(const MdConfig& config,
                                                        const fs::path& out,
                                                        const RunOptions& options) {
  auto d = std::make_unique<Impl>();
  d->cfg = config;
  d->out = out;
  d->options = options;
  validateConfig(d->cfg);
  checkSchedule(d->cfg);
  return d;
}

Simulation Simulation::start(const MdConfig& config, const fs::path& out,
                             const RunOptions& options) {
  auto d = checkedRun(config, out, options);
  checkNewFolder(out, options);
  // everything that can fail on the input fails before the folder is touched
  // (a file's contacts within system.initial_max_overlap are accepted: InitialState.h)
  const Frame init = prepareInitialState(d->cfg);
  d->setUp(std::make_unique<Engine>(d->cfg, init, /*allow_contacts=*/true));
  return startWriting(std::move(d));
}

Simulation Simulation::start(const MdConfig& config, std::unique_ptr<RunEngine> engine,
                             const fs::path& out, const RunOptions& options) {
  auto d = checkedRun(config, out, options);
  onWritingRank(*engine, [&] { checkNewFolder(out, options); });
  d->setUp(std::move(engine));
  return startWriting(std::move(d));
}

Simulation Simulation::startWriting(std::unique_ptr<Impl> d) {
  RunEngine& e = *d->engine;
  const fs::path& out = d->out;
  const RunOptions& options = d->options;
  onWritingRank(e, [&] {
    d->lock = common::FolderLock::acquire(out, options.command_line, options.overwrite);
  });
  try {
    if (e.writesFiles()) {  // an overwritten run's checkpoint and profile are not this run's
      fs::remove(d->checkpointFile());
      fs::remove(out / "profile.csv");
    }
    e.begin(out);
    const Observables o = e.observables();
    const Frame f = outputFrame(e, d->cfg);
    if (e.writesFiles()) {
      d->writer = std::make_unique<H5mdWriter>(
          d->trajectory().string(), e.size(),
          parameters(d->cfg, e, options.command_line, d->dt_reason), toToml(d->cfg),
          options.overwrite, d->cfg.output.write_velocities, d->cfg.output.write_forces);
      d->writer->writeObservables(0, 0.0, observableRow(o));
      d->writer->writeFrame(f);
    }
  } catch (...) {
    d->writer.reset();
    if (d->lock && d->lock->createdFolder()) {  // nothing half-written: a folder made here goes
      d->lock.reset();
      std::error_code ec;
      fs::remove_all(out, ec);
    }
    throw;
  }
  if (d->writer) d->watchTrajectory();
  d->next_frame = 1;  // frames[0] = 0: written
  d->frames_written = 1;
  return Simulation(std::move(d));
}

namespace {
void checkResumeOverrides(const std::vector<std::string>& overrides) {
  for (const auto& s : overrides)
    if (s.rfind("run.t_end=", 0) != 0)
      throw std::invalid_argument(
          "--restart accepts only --set run.t_end=... (to run further); got --set " + s);
}
}  // namespace

Simulation Simulation::resume(const fs::path& out, const std::vector<std::string>& overrides,
                              const RunOptions& options) {
  checkResumeOverrides(overrides);
  const fs::path cpath = out / "checkpoint.h5";  // (Engine::checkpointPath)
  if (!fs::exists(cpath))
    throw std::invalid_argument("--restart: no checkpoint at " + cpath.string());
  common::FolderLock::checkAvailable(out, options.overwrite, "--restart");
  const Checkpoint ck = readCheckpoint(cpath.string());
  return resumeWith(
      out, overrides, options, ck.extra, cpath.string() + ":/config_toml",
      [&ck](const MdConfig& cfg) { return std::make_unique<Engine>(cfg, ck); },
      /*folder_checked=*/true);
}

Simulation Simulation::resume(const fs::path& out, const std::vector<std::string>& overrides,
                              const RunOptions& options, const CheckpointExtra& run_fields,
                              const std::string& config_source,
                              const EngineFromCheckpoint& continue_engine) {
  checkResumeOverrides(overrides);
  return resumeWith(out, overrides, options, run_fields, config_source, continue_engine,
                    /*folder_checked=*/false);
}

Simulation Simulation::resumeWith(const fs::path& out, const std::vector<std::string>& overrides,
                                  const RunOptions& options, const CheckpointExtra& run_fields,
                                  const std::string& config_source,
                                  const EngineFromCheckpoint& continue_engine,
                                  bool folder_checked) {
  auto d = std::make_unique<Impl>();
  d->out = out;
  d->options = options;
  d->resumed = true;
  d->cfg = parseConfigString(run_fields.config_toml, config_source, overrides);
  validateConfig(d->cfg);
  checkSchedule(d->cfg);
  d->setUp(continue_engine(d->cfg));
  RunEngine& e = *d->engine;
  if (!folder_checked)
    onWritingRank(e,
                  [&] { common::FolderLock::checkAvailable(out, options.overwrite, "--restart"); });
  if (d->last < e.step())  // (equal: a finished run; run() has nothing to do)
    throw std::invalid_argument(
        "run.t_end = " + common::formatReal(d->cfg.run.t_end) + " lies before the checkpoint in " +
        out.string() + " (t = " + common::formatReal(e.time()) + ", step " +
        std::to_string(e.step()) + "): give a later --set run.t_end=... to run further");
  d->last_checkpoint_step = e.step();
  d->frames_written = run_fields.frames_written;
  if (d->last == e.step()) {  // finished: nothing to open
    d->at_end = true;
    return Simulation(std::move(d));
  }
  onWritingRank(e, [&] {
    d->lock =
        common::FolderLock::acquire(out, options.command_line, options.overwrite, "--restart");
  });
  e.begin(out);
  if (e.writesFiles()) {
    d->writer = std::make_unique<H5mdWriter>(
        H5mdWriter::reopen(d->trajectory().string(), e.size(), e.step(),
                           d->cfg.output.write_velocities, d->cfg.output.write_forces));
    // the run's history: who continued it from where, to where
    d->writer->recordRestart(e.step(), e.time(), d->cfg.run.t_end, options.command_line,
                             common::versionString());
    d->watchTrajectory();
  }
  return Simulation(std::move(d));
}

void Simulation::addReporter(std::shared_ptr<Reporter> reporter) {
  m_impl->reporters.push_back(std::move(reporter));
}

RunSummary Simulation::run() {
  Impl& d = *m_impl;
  if (finished()) return {};  // resumed at run.t_end: no file is opened, nothing to do
  RunEngine& engine = *d.engine;
  const MdConfig& cfg = d.cfg;
  const std::int64_t obs_every = cfg.output.observable_interval;
  const std::int64_t ck_every = cfg.output.checkpoint_interval;
  const std::int64_t first_step = engine.step(), first_builds = engine.neighborBuilds(),
                     first_slow = engine.slowEvaluations();
  auto last_checkpoint_time = Clock::now();
  const auto loop_start = Clock::now();
  struct Finish {  // reporters hear of the end however run() ends
    Simulation& sim;
    ~Finish() {
      for (auto& r : sim.m_impl->reporters) r->finish(sim);
    }
  } finish{*this};
  // (collective: a signal caught by one rank stops every rank at this chunk boundary)
  const auto stopRequested = [&] {
    return engine.anyRank(d.options.stop != nullptr && *d.options.stop != 0);
  };
  try {
    while (engine.step() < d.last && !stopRequested()) {
      std::int64_t target = std::min(d.last, (engine.step() / obs_every + 1) * obs_every);
      if (d.next_frame < d.frames.size()) target = std::min(target, d.frames[d.next_frame]);
      if (ck_every > 0) target = std::min(target, (engine.step() / ck_every + 1) * ck_every);
      for (const auto& r : d.reporters)
        if (const std::int64_t s = r->nextStep(*this); s > engine.step())
          target = std::min(target, s);
      engine.run(target - engine.step());
      if (d.writer) d.checkTrajectory();
      d.observables = engine.observables();
      const Observables& o = d.observables;
      if (d.writer && (engine.step() % obs_every == 0 || engine.step() == d.last))
        d.writer->writeObservables(o.step, o.time, observableRow(o));
      if (d.next_frame < d.frames.size() && engine.step() == d.frames[d.next_frame]) {
        d.writeFrame();
        ++d.next_frame;
      }
      const bool by_steps = ck_every > 0 && engine.step() % ck_every == 0;
      // (the ranks' clocks may disagree: the wall-time checkpoint is agreed on)
      const bool by_wall =
          cfg.output.checkpoint_wall_seconds > 0 &&
          engine.anyRank(
              std::chrono::duration<double>(Clock::now() - last_checkpoint_time).count() >
              cfg.output.checkpoint_wall_seconds);
      if (by_steps || by_wall) {
        d.checkpoint();
        last_checkpoint_time = Clock::now();
      }
      for (const auto& r : d.reporters) r->report(*this);
    }
  } catch (const RunAborted& e) {
    if (d.writer) d.writer->close();
    const fs::path cpath = d.checkpointFile();
    throw RunAborted(
        std::string(e.what()) + ". Trajectory up to the last frame in " + d.trajectory().string() +
        (d.last_checkpoint_step >= 0
             ? "; last good checkpoint (step " + std::to_string(d.last_checkpoint_step) +
                   ") kept in " + cpath.string()
             : "; no checkpoint was written before the failure"));
  }
  RunSummary s;
  s.loop_seconds = std::chrono::duration<double>(Clock::now() - loop_start).count();
  s.steps = engine.step() - first_step;
  s.neighbor_builds = engine.neighborBuilds() - first_builds;
  s.slow_evaluations = engine.slowEvaluations() - first_slow;
  s.stopped = engine.step() < d.last;
  s.observables = s.steps > 0 ? d.observables : engine.observables();
  if (d.writer) d.checkTrajectory();
  d.checkpoint();
  if (d.writer) {
    d.writer->close();
    d.verifyTrajectory(d.writer->frames());
  }
  d.lock.reset();
  if (d.options.profile && engine.writesFiles())
    writeProfile(engine, d.out / "profile.csv", d.options.command_line, s.steps, s.loop_seconds,
                 s.neighbor_builds, s.slow_evaluations);
  return s;
}

void Simulation::writeCheckpoint() {
  if (!finished()) m_impl->checkpoint();
}

const std::string& Simulation::clearedStaleLock() const {
  static const std::string none;
  return m_impl->lock ? m_impl->lock->clearedStale() : none;
}

bool Simulation::finished() const { return m_impl->at_end; }

const RunEngine& Simulation::engine() const { return *m_impl->engine; }
const MdConfig& Simulation::config() const { return m_impl->cfg; }
const fs::path& Simulation::folder() const { return m_impl->out; }
fs::path Simulation::trajectoryPath() const { return m_impl->trajectory(); }
fs::path Simulation::checkpointPath() const { return m_impl->checkpointFile(); }
const std::string& Simulation::dtReason() const { return m_impl->dt_reason; }
std::int64_t Simulation::lastStep() const { return m_impl->last; }
bool Simulation::resumed() const { return m_impl->resumed; }
std::size_t Simulation::framesWritten() const {
  return m_impl->writer ? m_impl->writer->frames() : m_impl->frames_written;
}
const Observables& Simulation::lastObservables() const { return m_impl->observables; }

std::vector<std::int64_t> Simulation::frameSteps(const MdConfig& c, double dt, std::int64_t last) {
  std::set<std::int64_t> s{0, last};
  if (c.output.frames_per_decade > 0) {
    const double t0 = std::max(0.01, dt);
    const double k = std::pow(10.0, 1.0 / c.output.frames_per_decade);
    for (double t = t0; t < c.run.t_end * (1 + 1e-12); t *= k)
      s.insert(std::min<std::int64_t>(last, std::llround(t / dt)));
  }
  if (c.output.frame_interval > 0.0)
    for (double t = c.output.frame_interval; t < c.run.t_end * (1 + 1e-12);
         t += c.output.frame_interval)
      s.insert(std::min<std::int64_t>(last, std::llround(t / dt)));
  return {s.begin(), s.end()};
}

}  // namespace granagg::md
