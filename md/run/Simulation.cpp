#include "md/run/Simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <optional>
#include <set>
#include <stdexcept>

#include "common/Csv.h"
#include "common/FolderLock.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/io/Checkpoint.h"
#include "md/io/InitialState.h"
#include "md/run/OutputReporters.h"
#include "md/run/RunChecks.h"

namespace granagg::md {
namespace fs = std::filesystem;

namespace {
// integrator.dt = "adaptive": the step is re-chosen at every frame time and at these many
// log-spaced times per decade (from t = 0.01). A gas cooling as Haff's law, T ~ t^-2, changes
// its Hertz step (~ T^{-1/10}) by 2.3 % between two of them.
constexpr int ADAPT_PER_DECADE = 20;
}  // namespace

/// integrator.dt = "adaptive": the times at which the step may change (the ends of its epochs),
/// each marked if a frame falls on it: the frame times (output.frames_per_decade and
/// output.frame_interval, as frameSteps), ADAPT_PER_DECADE log-spaced times and run.t_end, with
/// times closer than half the "auto" step merged (t_end kept exact). Within an epoch the step
/// is constant and divides it into whole steps, so frames fall on their times.
struct EpochTimes {
  std::vector<double> t;
  std::vector<char> frame;

  EpochTimes(const MdConfig& c, double dt_auto) {
    std::vector<std::pair<double, char>> all;
    const double t_end = c.run.t_end;
    const double t0 = std::max(0.01, dt_auto);
    if (c.output.frames_per_decade > 0) {
      const double k = std::pow(10.0, 1.0 / c.output.frames_per_decade);
      for (double t = t0; t < t_end * (1 + 1e-12); t *= k) all.emplace_back(t, 1);
    }
    if (c.output.frame_interval > 0.0)
      for (double t = c.output.frame_interval; t < t_end * (1 + 1e-12);
           t += c.output.frame_interval)
        all.emplace_back(t, 1);
    const double k = std::pow(10.0, 1.0 / ADAPT_PER_DECADE);
    for (double t = 0.01; t < t_end; t *= k) all.emplace_back(t, 0);
    all.emplace_back(t_end, 1);
    std::sort(all.begin(), all.end());
    for (const auto& [time, is_frame] : all) {
      const double at = std::min(time, t_end);
      if (!t.empty() && at - t.back() < 0.5 * dt_auto) {  // one epoch end for both
        frame.back() = static_cast<char>(frame.back() | is_frame);
        if (at == t_end) t.back() = t_end;
        continue;
      }
      if (at <= 0.0) continue;
      t.push_back(at);
      frame.push_back(is_frame);
    }
  }
  /// Index of the first epoch end after `time` (beyond `tol`); t.size() if none.
  std::size_t after(double time, double tol) const {
    return static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), time + tol) - t.begin());
  }
};

struct Simulation::Impl {
  MdConfig cfg;
  fs::path out;
  RunOptions options;
  bool resumed = false;
  std::string dt_reason;
  std::int64_t last = 0;  // adaptive dt: -1 until the last epoch is planned
  std::unique_ptr<RunEngine> engine;
  // integrator.dt = "adaptive": the epochs (EpochTimes) and the step where the current one ends
  // (-1: to be planned at the next chunk)
  std::unique_ptr<EpochTimes> epochs;
  std::int64_t epoch_end = -1;
  // the run's outputs (md/run/OutputReporters.h), called before the user's reporters
  std::unique_ptr<TrajectoryReporter> trajectory;
  std::unique_ptr<CheckpointReporter> checkpoints;
  std::vector<std::shared_ptr<Reporter>> reporters;
  Observables observables;  // at the end of the last chunk where a reporter needed them
  std::int64_t observables_step = -1;  // the step of `observables`

  bool at_end = false;                     // resumed at run.t_end: nothing to do, no file opened
  std::size_t frames_at_end = 0;           // the trajectory's frames then
  std::optional<common::FolderLock> lock;  // held from the first write to the end of the run

  fs::path trajectoryFile() const { return out / "traj.h5"; }

  /// engine, dt, last step and the output reporters (both start() and resume());
  /// `frames_written` and `checkpoint_step` (-1: none) describe the folder it continues
  void setUp(std::unique_ptr<RunEngine> e, std::size_t frames_written,
             std::int64_t checkpoint_step) {
    engine = std::move(e);
    engine->enableProfile(options.profile);
    const double dt_auto = Engine::chooseTimeStep(cfg, &dt_reason);
    if (std::string why = engine->dtReason(); !why.empty()) dt_reason = std::move(why);
    std::vector<std::int64_t> frames;
    if (cfg.integrator.adaptive) {
      if (!engine->adaptsTimeStep())
        throw std::invalid_argument(
            "integrator.dt = \"adaptive\" needs granagg's own engine (granagg md); this engine "
            "runs a fixed step: use \"auto\" or a number");
      dt_reason = "adaptive, from the auto step (" + dt_reason +
                  "); chosen again at every epoch (observable dt)";
      epochs = std::make_unique<EpochTimes>(cfg, dt_auto);
      last = -1;
      continueEpoch();  // frames and the last step of a resumed epoch; a new one is planned
    } else {
      last = static_cast<std::int64_t>(std::llround(cfg.run.t_end / engine->dt()));
      frames = Simulation::frameSteps(cfg, engine->dt(), last);
    }
    const auto next_frame = static_cast<std::size_t>(
        std::upper_bound(frames.begin(), frames.end(), engine->step()) - frames.begin());
    trajectory = std::make_unique<TrajectoryReporter>(*engine, cfg, trajectoryFile(),
                                                      std::move(frames), next_frame,
                                                      frames_written, last);
    checkpoints =
        std::make_unique<CheckpointReporter>(*engine, cfg, out, *trajectory, checkpoint_step);
    if (epoch_end > engine->step()) scheduleEpochEnd(epochs->after(engine->time(), tolerance()));
  }

  /// Times closer than this are the same epoch end (a step apart at the least).
  double tolerance() const { return 1e-6 * engine->dt(); }

  /// The epoch a resumed engine is in: its dt divides the rest of the epoch into whole steps.
  /// At an epoch end (or at t = 0) the next epoch is planned by the first chunk instead.
  void continueEpoch() {
    const double t = engine->time(), tol = tolerance();
    const std::size_t i = epochs->after(t, tol);
    const bool at_end = i > 0 && std::abs(epochs->t[i - 1] - t) <= tol;
    if (i == epochs->t.size()) {  // at run.t_end: nothing left
      last = engine->step();
      return;
    }
    // (not a whole number of steps: a run continued to a later run.t_end, whose epochs differ:
    // a new epoch starts here)
    const double steps = (epochs->t[i] - t) / engine->dt();
    const bool whole = std::abs(steps - std::round(steps)) <= 1e-6 * std::max(1.0, steps);
    epoch_end = (t <= tol || at_end || !whole) ? -1 : engine->step() + std::llround(steps);
    // the slow Coulomb intervals end at the epoch's end, as in the run that wrote the checkpoint
    if (epoch_end > 0) engine->setTimeStep(engine->dt(), epoch_end);
  }
  /// The trajectory's frame and last step for the epoch that ends at epochs->t[i], at epoch_end.
  void scheduleEpochEnd(std::size_t i) {
    if (epochs->frame[i]) trajectory->addFrameStep(epoch_end);
    if (i + 1 == epochs->t.size()) {
      last = epoch_end;
      trajectory->setLastStep(last);
    }
  }
  /// Chooses the step of the next epoch from the gas (RunEngine::adaptiveTimeStep): the whole
  /// number of steps that fills the epoch at no more than that step.
  void planEpoch() {
    const double t = engine->time();
    const std::size_t i = epochs->after(t, tolerance());
    const double span = epochs->t[i] - t;
    const double want = engine->adaptiveTimeStep();
    const auto n =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(span / want - 1e-9)));
    epoch_end = engine->step() + n;
    engine->setTimeStep(span / static_cast<double>(n), epoch_end);
    scheduleEpochEnd(i);
  }
  /// The run has reached run.t_end.
  bool atEnd() const { return last >= 0 && engine->step() >= last; }
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
  d->setUp(std::make_unique<Engine>(d->cfg, init, /*allow_contacts=*/true), 0, -1);
  return startWriting(std::move(d));
}

Simulation Simulation::start(const MdConfig& config, std::unique_ptr<RunEngine> engine,
                             const fs::path& out, const RunOptions& options) {
  auto d = checkedRun(config, out, options);
  onWritingRank(*engine, [&] { checkNewFolder(out, options); });
  d->setUp(std::move(engine), 0, -1);
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
      fs::remove(e.checkpointPath(out));
      fs::remove(out / "profile.csv");
    }
    e.begin(out);
    const Observables o = e.observables();
    d->trajectory->create(trajectoryParameters(d->cfg, e, options.command_line, d->dt_reason),
                          toToml(d->cfg), options.overwrite, o);
  } catch (...) {
    d->trajectory.reset();
    if (d->lock && d->lock->createdFolder()) {  // nothing half-written: a folder made here goes
      d->lock.reset();
      std::error_code ec;
      fs::remove_all(out, ec);
    }
    throw;
  }
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
    throw std::invalid_argument(
        "--restart: no checkpoint at " + cpath.string() +
        (fs::exists(out / "traj.h5")
             ? ": the run stopped before its first checkpoint, so there is nothing to continue; "
               "start it again with its command and --force (its configuration is in " +
                   (out / "traj.h5").string() + ", /parameters/config_toml)"
             : ""));
  common::FolderLock::checkAvailable(out, options.overwrite, "--restart", "", true);
  const Checkpoint ck = readCheckpoint(cpath.string());
  return resumeWith(
      out, overrides, options, ck.run, cpath.string() + ":/config_toml",
      [&ck](const MdConfig& cfg) { return std::make_unique<Engine>(cfg, ck); },
      /*folder_checked=*/true);
}

Simulation Simulation::resume(const fs::path& out, const std::vector<std::string>& overrides,
                              const RunOptions& options, const RunFields& run_fields,
                              const std::string& config_source,
                              const EngineFromCheckpoint& continue_engine) {
  checkResumeOverrides(overrides);
  return resumeWith(out, overrides, options, run_fields, config_source, continue_engine,
                    /*folder_checked=*/false);
}

Simulation Simulation::resumeWith(const fs::path& out, const std::vector<std::string>& overrides,
                                  const RunOptions& options, const RunFields& run_fields,
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
  {
    std::unique_ptr<RunEngine> engine = continue_engine(d->cfg);
    const std::int64_t at = engine->step();
    d->setUp(std::move(engine), run_fields.frames_written, at);
  }
  RunEngine& e = *d->engine;
  if (!folder_checked)
    onWritingRank(e,
                  [&] {
                    common::FolderLock::checkAvailable(out, options.overwrite, "--restart", "",
                                                       true);
                  });
  const bool before_checkpoint =
      d->epochs ? d->cfg.run.t_end < e.time() - d->tolerance() : d->last < e.step();
  if (before_checkpoint)  // (equal: a finished run; run() has nothing to do)
    throw std::invalid_argument(
        "run.t_end = " + common::formatReal(d->cfg.run.t_end) + " lies before the checkpoint in " +
        out.string() + " (t = " + common::formatReal(e.time()) + ", step " +
        std::to_string(e.step()) + "): give a later --set run.t_end=... to run further");
  if (d->atEnd()) {  // finished: nothing to open
    d->at_end = true;
    d->frames_at_end = run_fields.frames_written;
    return Simulation(std::move(d));
  }
  onWritingRank(e, [&] {
    // a stale lock of this host is taken over: its owner is gone (FolderLock.h)
    d->lock = common::FolderLock::acquire(out, options.command_line, options.overwrite,
                                          "--restart", "", true);
  });
  e.begin(out);
  d->trajectory->reopen(d->cfg.run.t_end, options.command_line, common::versionString());
  return Simulation(std::move(d));
}

void Simulation::addReporter(std::shared_ptr<Reporter> reporter) {
  m_impl->reporters.push_back(std::move(reporter));
}

RunSummary Simulation::run() {
  Impl& d = *m_impl;
  if (finished()) return {};  // resumed at run.t_end: no file is opened, nothing to do
  RunEngine& engine = *d.engine;
  const std::int64_t first_step = engine.step(), first_builds = engine.neighborBuilds(),
                     first_slow = engine.slowEvaluations();
  const auto loop_start = std::chrono::steady_clock::now();
  // the trajectory first, then the user's reporters, then the checkpoints (Reporter.h)
  std::vector<Reporter*> all = {d.trajectory.get()};
  for (const auto& r : d.reporters) all.push_back(r.get());
  all.push_back(d.checkpoints.get());
  d.checkpoints->setBeforeSave([this](std::int64_t step) {
    for (auto& r : m_impl->reporters) r->beforeCheckpoint(*this, step);
  });
  struct Unhook {  // no reporter is called back once run() is over
    CheckpointReporter& c;
    ~Unhook() { c.setBeforeSave({}); }
  } unhook{*d.checkpoints};
  struct Finish {  // the user's reporters hear of the end however run() ends
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
    while (!d.atEnd() && !stopRequested()) {
      if (d.epochs && engine.step() >= d.epoch_end) d.planEpoch();
      std::int64_t target = d.epochs ? d.epoch_end : d.last;
      for (const Reporter* r : all)
        if (const std::int64_t s = r->nextStep(*this); s > engine.step())
          target = std::min(target, s);
      engine.run(target - engine.step());
      bool needed = false;
      for (const Reporter* r : all) needed = r->needsObservables(*this) || needed;
      // observables() is collective, and a rank may carry reporters that another lacks (the
      // progress line lives on rank 0 only): every rank computes them if any rank needs them
      needed = engine.anyRank(needed);
      if (needed) d.observables = engine.observables();
      d.observables_step = needed ? engine.step() : d.observables_step;
      for (Reporter* r : all) r->report(*this);
    }
  } catch (const RunAborted& e) {
    d.trajectory->close(/*verify=*/false);
    const std::int64_t good = d.checkpoints->lastStep();
    throw RunAborted(std::string(e.what()) + ". Trajectory up to the last frame in " +
                     d.trajectoryFile().string() +
                     (good >= 0 ? "; last good checkpoint (step " + std::to_string(good) +
                                      ") kept in " + engine.checkpointPath(d.out).string()
                                : "; no checkpoint was written before the failure"));
  }
  RunSummary s;
  s.loop_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
  s.steps = engine.step() - first_step;
  s.neighbor_builds = engine.neighborBuilds() - first_builds;
  s.slow_evaluations = engine.slowEvaluations() - first_slow;
  s.stopped = !d.atEnd();
  s.observables = s.steps > 0 && d.observables_step == engine.step() ? d.observables
                                                                      : engine.observables();
  d.trajectory->check();
  d.checkpoints->save();
  d.trajectory->close();
  d.lock.reset();
  if (d.options.profile && engine.writesFiles())
    writeProfile(engine, d.out / "profile.csv", d.options.command_line, s.steps, s.loop_seconds,
                 s.neighbor_builds, s.slow_evaluations);
  return s;
}

void Simulation::writeCheckpoint() {
  if (finished()) return;
  // (outside run() the checkpoint reporter has no hook: call the reporters here)
  for (auto& r : m_impl->reporters) r->beforeCheckpoint(*this, m_impl->engine->step());
  m_impl->checkpoints->save();
}

std::int64_t Simulation::frameStep() const { return m_impl->trajectory->frameStep(); }

const std::string& Simulation::clearedStaleLock() const {
  static const std::string none;
  return m_impl->lock ? m_impl->lock->clearedStale() : none;
}

const std::string& Simulation::trajectoryRepair() const {
  return m_impl->trajectory->repairNote();
}

bool Simulation::finished() const { return m_impl->at_end; }

const RunEngine& Simulation::engine() const { return *m_impl->engine; }
const MdConfig& Simulation::config() const { return m_impl->cfg; }
const fs::path& Simulation::folder() const { return m_impl->out; }
fs::path Simulation::trajectoryPath() const { return m_impl->trajectoryFile(); }
fs::path Simulation::checkpointPath() const { return m_impl->engine->checkpointPath(m_impl->out); }
const std::string& Simulation::dtReason() const { return m_impl->dt_reason; }
std::int64_t Simulation::lastStep() const { return m_impl->last; }
bool Simulation::resumed() const { return m_impl->resumed; }
std::size_t Simulation::framesWritten() const {
  return m_impl->at_end ? m_impl->frames_at_end : m_impl->trajectory->framesWritten();
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
