/// \file PairStudy.cpp
/// The study's steps: folder, MD job pool with resume records, post-processing stages
/// (PairStudy.h).
#include "study/PairStudy.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "common/Csv.h"
#include "common/FolderLock.h"
#include "common/Interrupted.h"
#include "common/Strings.h"
#include "common/Version.h"
#include "study/JobPool.h"
#include "study/Process.h"
#include "study/Slurm.h"

namespace granagg::study {
namespace fs = std::filesystem;
using common::formatReal;

namespace {

/// `granagg analyze` arguments ([analysis] args) as md's [analysis] assignments: "--grid-spacing
/// 3" -> "analysis.grid_spacing=3", a flag "--no-grid" -> "analysis.no_grid=true", two values
/// "--fit-window 100 1000" -> "analysis.fit_window=[100, 1000]". md checks the keys (exit 2).
std::vector<std::string> analysisSets(const std::vector<std::string>& args) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < args.size();) {
    std::string key = args[i];
    if (key.rfind("--", 0) != 0)
      throw std::invalid_argument("[analysis] args: expected an option (--name), got '" + key +
                                  "'");
    key = key.substr(2);
    std::string value;
    const auto eq = key.find('=');
    std::vector<std::string> values;
    if (eq != std::string::npos) {
      values.push_back(key.substr(eq + 1));
      key = key.substr(0, eq);
    }
    ++i;
    while (i < args.size() && args[i].rfind("--", 0) != 0) values.push_back(args[i++]);
    std::replace(key.begin(), key.end(), '-', '_');
    if (values.empty()) {
      value = "true";
    } else if (values.size() == 1) {
      value = values.front();
    } else {
      value = "[";
      for (std::size_t k = 0; k < values.size(); ++k) value += (k ? ", " : "") + values[k];
      value += "]";
    }
    out.push_back("analysis." + key + "=" + value);
  }
  return out;
}

/// "[0, 5]": the K values as the log shows them.
std::string kList(const std::vector<double>& K) {
  std::string s;
  for (double k : K) s += (s.empty() ? "" : ", ") + formatReal(k);
  return "[" + s + "]";
}

/// What run.json and done.json of a run share: the spec it must match to count, and its identity.
nlohmann::ordered_json runRecord(const RunJob& j) {
  return {
      {"spec", j.spec}, {"K", j.K}, {"run", j.r}, {"seed", j.seed}, {"config", j.config.string()}};
}

/// Whether a run record (run.json, done.json) was made for this run's configuration and seed;
/// false when the file is missing or not a record.
bool recordOf(const fs::path& p, const RunJob& job) {
  if (!fs::exists(p)) return false;
  try {
    const std::string spec = nlohmann::json::parse(readText(p)).at("spec").get<std::string>();
    return spec == job.spec || spec == job.legacy_spec;
  } catch (const std::exception&) {
    return false;
  }
}

bool stageDone(const fs::path& marker, const std::string& spec) {
  return fs::exists(marker) && readText(marker) == spec;
}

}  // namespace

void PairStudy::say(const std::string& line, bool terminal) {
  appendText(m_out / "pair.log", "[" + common::utcTimestamp() + "] " + line + "\n");
  if (terminal && !m_a.quiet) {
    std::fprintf(stderr, "pair: %s\n", line.c_str());
  }
}

void PairStudy::prepareFolder() {
  const bool exists = fs::exists(m_out);
  if (exists && !fs::is_directory(m_out))
    throw std::invalid_argument("--out '" + m_out.string() + "' exists and is not a folder");
  // The study folder is locked by the command that runs the whole study; the array tasks of a
  // batch job (run_index) run side by side, each md run locking its own run folder. A stale lock
  // that a killed study left on this host is cleared: resuming is what pair does, and every run
  // is checked against its records. Another host's stale lock needs --force.
  const bool whole = m_a.run_index < 0;
  const std::optional<common::LockHolder> stale =
      whole ? common::FolderLock::staleHolder(m_out) : std::nullopt;
  const bool clear_stale = m_a.force || (stale && stale->deadHere());
  const std::string hint = "If that study has ended, delete " +
                           (m_out / common::FOLDER_LOCK_FILE).string() +
                           " (--force would start the study over)";
  if (whole) common::FolderLock::checkAvailable(m_out, clear_stale, "--out", hint);
  const bool is_pair = fs::exists(m_out / "config" / "pair.toml");
  if (exists && !fs::is_empty(m_out) && !is_pair && !m_a.force)
    throw std::invalid_argument(
        "output folder '" + m_out.string() +
        "' exists, is not empty and holds no pair study; choose another --out or pass --force");
  if (whole) {
    m_lock = common::FolderLock::acquire(m_out, m_s.command_line, clear_stale, "--out", hint);
    if (!m_lock->clearedStale().empty())
      say("cleared the stale lock of " + m_lock->clearedStale());
  }
  if (is_pair && m_a.force && whole) {
    // --force: start over (keep nothing this command made before), unless a run is being written
    common::FolderLock::checkTreeAvailable(m_out);
    for (const char* sub : {"runs", "analysis", "meanfield", "fit", "figures", "logs", "config"})
      fs::remove_all(m_out / sub);
    for (const char* f : {"summary.json", "report.html", "commands.txt", "batch.slurm", "pair.log"})
      fs::remove(m_out / f);
  }
  fs::create_directories(m_out / "config");
  fs::create_directories(m_out / "logs");
}

PairStudy::PairStudy(PairConfig config, StudyRequest request, StudyServices services)
    : m_c(std::move(config)),
      m_a(std::move(request)),
      m_s(std::move(services)),
      m_out(fs::absolute(m_a.out.empty() ? fs::path("pair-" + m_c.name) : fs::path(m_a.out))
                .lexically_normal()),
      m_cores(availableCores()),
      m_start(clock::now()) {
  validate(m_c);
  if (m_a.jobs < 0)
    throw std::invalid_argument("--jobs must be >= 1 (got " + std::to_string(m_a.jobs) + ")");
  if (m_a.threads < 0)
    throw std::invalid_argument("--threads must be >= 1 (got " + std::to_string(m_a.threads) + ")");
  if (!m_a.emit_batch.empty() && m_a.emit_batch != "slurm")
    throw std::invalid_argument("--emit-batch supports only 'slurm' (got '" + m_a.emit_batch +
                                "')");
  setUpLaunch();
  // every ensemble's MD configuration, resolved before anything is written (exit 2 on a bad key)
  const std::string base =
      m_c.md_preset.empty() ? m_c.md_config : m_s.find_md_preset(m_c.md_preset);
  for (std::size_t k = 0; k < m_c.K.size(); ++k) {
    const double K = m_c.K[k];
    std::vector<std::string> set = m_c.md_set;
    if (!m_launch.lammps()) {
      // analysed while they run (granagg md --analyze), with [analysis] args as [analysis] keys;
      // the analysis stage then reads their tables, not their frames
      set.push_back("output.analyze=true");
      set.push_back(std::string("output.trajectory=") +
                    (m_a.keep_trajectories ? "true" : "false"));
      for (const std::string& a : analysisSets(m_c.analysis_args)) set.push_back(a);
    }
    set.push_back("coulomb.K=" + formatReal(K));
    if (K > 0) {
      set.push_back("charging.Q=" + formatReal(m_c.charged_Q));
      set.insert(set.end(), m_c.charged_set.begin(), m_c.charged_set.end());
    }
    const MdPlan plan = m_s.resolve_md(base, set);
    const std::string name = kName(K);
    const fs::path path = m_out / "config" / ("md_" + name + ".toml");
    m_md[name] = plan;
    const std::string header = "# granagg md configuration of the K = " + formatReal(K) +
                               " runs of pair study '" + m_c.name + "' (resolved from " + base +
                               "; every run sets its own --seed)\n";
    m_md_text[path.string()] = header + plan.toml;  // written once the folder is prepared
    const std::string hash = fnv1a(plan.toml), legacy = fnv1a(plan.toml, LEGACY_HASH_BASIS);
    for (int r = 0; r < m_c.runs; ++r) {
      RunJob j;
      j.K = K;
      j.r = r;
      j.seed = m_c.seed + r;
      j.index = static_cast<int>(k) * m_c.runs + r;
      j.dir = m_out / "runs" / name / ("run" + std::to_string(r));
      j.config = path;
      j.log = m_out / "logs" / ("md-" + name + "-run" + std::to_string(r) + ".log");
      // granagg md's runs keep the spec they always had; another engine's runs are other runs
      const std::string engine = m_launch.lammps() ? " engine=" + m_launch.engine : "";
      j.spec = "md_config_fnv1a=" + hash + " seed=" + std::to_string(j.seed) + engine;
      j.legacy_spec = "md_config_fnv1a=" + legacy + " seed=" + std::to_string(j.seed) + engine;
      j.cost = static_cast<double>(plan.N) * plan.steps * (K > 0 ? 100.0 : 1.0);
      m_runs.push_back(j);
    }
  }
  if (m_a.run_index >= static_cast<int>(m_runs.size()))
    throw std::invalid_argument("--run-index " + std::to_string(m_a.run_index) +
                                " is out of range (the study has " + std::to_string(m_runs.size()) +
                                " runs: 0.." + std::to_string(m_runs.size() - 1) + ")");
}

/// The programs that run the MD: `granagg md`, or granagg-lammps beside the granagg binary under
/// the launcher (checked here, before anything is written: exit 2 with the key).
void PairStudy::setUpLaunch() {
  m_launch.engine = m_c.md_engine;
  m_launch.granagg = m_s.exe;
  if (!m_launch.lammps()) {
    if (!m_a.launcher.empty())
      throw std::invalid_argument("--launcher applies only to a study with md.engine = "
                                  "\"lammps\" (this one runs granagg md)");
    return;
  }
  m_launch.granagg_lammps = (fs::path(m_s.exe).parent_path() / "granagg-lammps").string();
  if (!findProgram(m_launch.granagg_lammps))
    throw std::invalid_argument(
        "md.engine = \"lammps\" runs the MD with granagg-lammps, which is not beside granagg (" +
        m_launch.granagg_lammps +
        " not found): it is built when liblammps-dev and Open MPI are found (scripts/setup.sh, "
        "docs/lammps.md)");
  const bool given = !m_a.launcher.empty();
  const std::string key = given ? "--launcher" : m_c.source + ": lammps.launcher";
  m_launch.launcher =
      launcherWords(given ? m_a.launcher : m_c.lammps_launcher, m_c.lammps_ranks, key);
  // the launcher runs here unless the study is only written out for a cluster
  if (m_a.emit_batch.empty() && !findProgram(m_launch.launcher[0]))
    throw std::invalid_argument(key + ": '" + m_launch.launcher[0] +
                                "' is not a program found in PATH (Open MPI's mpirun: "
                                "scripts/setup.sh)");
  m_s.backend = "LAMMPS through granagg-lammps, started as: " + joinCommand(m_launch.launcher);
}

std::string PairStudy::batchCommand() const {
  return shellQuote(m_s.exe) + " pair --config " +
         shellQuote((m_out / "config" / "pair.toml").string()) + " --out " +
         shellQuote(m_out.string());
}

void PairStudy::emitSlurm() {
  SlurmJob job;
  job.name = m_c.name;
  job.tasks = m_runs.size();
  job.runs_per_K = m_c.runs;
  job.K = m_c.K;
  job.threads = m_a.threads > 0 ? m_a.threads : 4;
  if (m_launch.lammps()) {  // every task holds the nodes of one granagg-lammps run
    job.nodes = m_c.lammps_nodes;
    job.tasks_per_node = m_c.lammps_tasks_per_node;
    std::vector<std::string> srun = launcherWords(
        m_c.lammps_slurm_launcher, 1LL * job.nodes * job.tasks_per_node, "lammps.slurm_launcher");
    srun.push_back("--nodes=" + std::to_string(job.nodes));
    srun.push_back("--ntasks-per-node=" + std::to_string(job.tasks_per_node));
    job.launcher = joinCommand(srun);
    job.task_options = "--launcher " + shellQuote(job.launcher);
  }
  job.out = m_out;
  job.study_command = batchCommand();
  job.written_by = m_s.command_line;
  const fs::path path = m_out / "batch.slurm";
  writeText(path, slurmScript(job));
  fs::permissions(path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
  say("wrote " + path.string() + " (" + std::to_string(m_runs.size()) +
      " array tasks + a follow-up job); submit with: bash " + path.string());
}

/// The runs still to do: those without a done.json of the same spec (finished ones are counted in
/// `done` and skipped), each marked to restart from its checkpoint where one belongs to it.
std::vector<RunJob> PairStudy::runsToDo(std::vector<RunJob>& all, int& done) {
  std::vector<RunJob> todo;
  done = 0;
  for (RunJob& j : all) {
    const fs::path marker = j.dir / "done.json";
    if (fs::exists(marker)) {
      if (recordOf(marker, j)) {
        ++done;
        say("md " + kName(j.K) + " run " + std::to_string(j.r) + ": finished already, skipped",
            false);
        continue;
      }
      if (!m_a.force)
        throw std::invalid_argument("run folder '" + j.dir.string() +
                                    "' holds a run made with another configuration; choose another "
                                    "--out or pass --force to redo it");
    }
    if (const auto holder = common::FolderLock::liveHolder(j.dir))
      throw std::invalid_argument("run folder '" + j.dir.string() + "' is in use by " +
                                  holder->describe() + ": wait for it to finish or stop it");
    j.restart = fs::exists(j.dir / checkpointFile(m_launch)) && fs::exists(j.dir / "traj.h5") &&
                recordOf(j.dir / "run.json", j);
    todo.push_back(j);
  }
  return todo;
}

void PairStudy::runMd(std::vector<RunJob> all) {
  int done = 0;
  std::vector<RunJob> todo = runsToDo(all, done);
  if (todo.empty()) {
    if (m_a.run_index < 0) say("md: all " + std::to_string(all.size()) + " runs finished already");
    return;
  }
  if (m_a.run_index < 0)
    say("md: " + std::to_string(todo.size()) + " of " + std::to_string(all.size()) + " runs to do" +
        (done ? " (" + std::to_string(done) + " finished already)" : ""));
  std::stable_sort(todo.begin(), todo.end(),
                   [](const RunJob& a, const RunJob& b) { return a.cost > b.cost; });

  // Default: two OpenMP threads per run. The engine's one-thread path is several times slower
  // per core than its two-thread path (N = 500 neutral: 1.9e5 against 1.2e6 particle-steps/s;
  // docs/pair.md), so one run per core loses on a 2-core machine.
  // A granagg-lammps run takes lammps.ranks cores.
  const int default_jobs =
      std::max(1, m_launch.lammps() ? m_cores / m_c.lammps_ranks : m_cores / 2);
  const int jobs = std::max(
      1, std::min<int>(m_a.jobs > 0 ? m_a.jobs : default_jobs, static_cast<int>(todo.size())));
  const int threads = m_a.threads > 0 ? m_a.threads : std::max(1, m_cores / jobs);
  std::vector<std::string> failed;
  const bool tty = !m_a.quiet && ::isatty(2);
  const auto t0 = clock::now();
  JobPoolCallbacks cb;
  cb.progress = [&](std::size_t finished, std::size_t running) {
    if (!tty) return;
    std::fprintf(stderr, "\rpair: md %zu/%zu runs done, %zu running (%d jobs x %d %s), %.0f s   ",
                 finished, todo.size(), running, jobs,
                 m_launch.lammps() ? m_c.lammps_ranks : threads,
                 m_launch.lammps() ? "ranks" : "threads",
                 std::chrono::duration<double>(clock::now() - t0).count());
    std::fflush(stderr);
  };
  cb.start = [&](std::size_t i) { return startRun(todo[i], threads, !tty); };
  cb.ended = [&](std::size_t i, int st, double wall) {
    RunJob& job = todo[i];
    const bool ok = WIFEXITED(st) && WEXITSTATUS(st) == 0;
    const std::string name = kName(job.K) + " run " + std::to_string(job.r);
    if (ok) {
      recordFinished(job, wall, threads);
      if (tty) std::fprintf(stderr, "\r%100s\r", "");
      say("md " + name + ": done in " + formatReal(std::round(wall * 10) / 10) + " s" +
          (job.restart ? " (restarted)" : ""));
      return false;
    }
    if (job.restart) {
      // The checkpoint could not be continued (e.g. a trajectory cut by a kill): start afresh.
      say("md " + name + ": restart failed (" + runLastLine(job) + "); starting it afresh", !tty);
      job.restart = false;
      return true;
    }
    const std::string why = WIFEXITED(st) ? "exit status " + std::to_string(WEXITSTATUS(st))
                                          : "killed by signal " + std::to_string(WTERMSIG(st));
    failed.push_back(name);
    if (tty) std::fprintf(stderr, "\r%100s\r", "");
    say("md " + name + ": FAILED (" + why + "): " + runLastLine(job) +
        " [log: " + job.log.string() + "]");
    return false;
  };
  // each run stops at the end of its chunk of steps with a checkpoint (granagg md handles the
  // signal); the next pair resumes it from there (RunJob::restart)
  cb.stop_requested = [&] { return stopped(); };
  bool first_stopped = true;
  cb.stop = [&](std::size_t, pid_t pid) { stopRun(pid); };
  cb.stopped = [&](std::size_t i) {
    if (first_stopped && tty) std::fprintf(stderr, "\n");
    first_stopped = false;
    say("md " + kName(todo[i].K) + " run " + std::to_string(todo[i].r) + ": stopped (" +
        runLastLine(todo[i]) + ")");
  };
  if (const int sig = runJobPool(todo.size(), jobs, cb)) {
    if (first_stopped && tty) std::fprintf(stderr, "\n");
    say("interrupted (signal " + std::to_string(sig) +
        "): finished runs are kept, stopped runs continue from their checkpoints; run the "
        "same command again to resume");
    throw common::Interrupted("pair: interrupted; run the same command again to resume", sig);
  }
  if (tty) std::fprintf(stderr, "\r%100s\r", "");
  m_timing["md"] += std::chrono::duration<double>(clock::now() - t0).count();
  if (!failed.empty()) {
    std::string list;
    for (const auto& f : failed) list += (list.empty() ? "" : ", ") + f;
    throw std::runtime_error(
        std::to_string(failed.size()) + " MD run(s) failed (" + list + "; logs in " +
        (m_out / "logs").string() +
        "); finished runs are kept: run the same command again to retry the others");
  }
}

/// Starts run `j` (its folder, run.json for a fresh start, the command in commands.txt and the log)
/// and returns its process; `echo` also prints the start to the terminal.
pid_t PairStudy::startRun(const RunJob& j, int threads, bool echo) {
  fs::create_directories(j.dir);
  if (!j.restart) {
    // A fresh start: clear what an interrupted attempt left behind.
    for (const char* f : {"traj.h5", "traj.xdmf", "checkpoint.h5", "checkpoint.toml", "done.json"})
      fs::remove(j.dir / f);
    nlohmann::ordered_json rec = runRecord(j);
    rec["started"] = common::utcTimestamp();
    writeText(j.dir / "run.json", rec.dump(2) + "\n");
  }
  const std::vector<std::string> argv = mdCommand(m_launch, j, threads);
  appendText(m_out / "commands.txt", joinCommand(argv) + "\n");
  appendText(j.log, "# " + common::utcTimestamp() + ": " + joinCommand(argv) + "\n");
  say("md " + kName(j.K) + " run " + std::to_string(j.r) + ": " +
          (j.restart ? "restarting from its checkpoint" : "started") + " (seed " +
          std::to_string(j.seed) + ")",
      echo);
  return spawn(argv, j.log);
}

/// done.json of a finished run: its record, wall time, threads or launcher, and this granagg; its
/// K is marked changed, so that the stages after the MD redo its analysis.
void PairStudy::recordFinished(const RunJob& job, double wall, int threads) {
  nlohmann::ordered_json rec = runRecord(job);
  rec["wall_seconds"] = wall;
  if (m_launch.lammps())
    rec["launcher"] = joinCommand(m_launch.launcher);
  else
    rec["threads"] = threads;
  rec["restarted"] = job.restart;
  rec["finished"] = common::utcTimestamp();
  rec["granagg"] = common::versionString();
  writeText(job.dir / "done.json", rec.dump(2) + "\n");
  m_changed_k.insert(kName(job.K));
}

/// What a run said last: granagg-lammps's last line, not the report mpirun appends after it.
std::string PairStudy::runLastLine(const RunJob& j) const {
  return m_launch.lammps() ? lastLine(j.log, "granagg-lammps: ") : lastLine(j.log);
}

/// Asks a running MD run to stop with a checkpoint: SIGTERM to `granagg md`; to a launched
/// granagg-lammps run, SIGTERM to its ranks on this machine and not to the launcher, because
/// Open MPI's mpirun answers SIGTERM by killing its ranks a second later
/// (odls_base_sigkill_timeout), before a large run has written its checkpoint. The ranks agree
/// on the stop, then exit, and mpirun with them. A launcher with no rank among its descendants
/// (srun: Slurm's daemons start the ranks) gets the signal and forwards it.
void PairStudy::stopRun(pid_t pid) {
  const std::vector<pid_t> ranks =
      m_launch.lammps() ? descendantsNamed(pid, "granagg-lammps") : std::vector<pid_t>{};
  if (ranks.empty()) ::kill(pid, SIGTERM);
  for (pid_t r : ranks) ::kill(r, SIGTERM);
}

/// Runs one post-processing command (blocking); returns its exit status (127: could not run).
int PairStudy::runStep(const std::string& label, std::vector<std::string> argv,
                       const std::string& logname, bool quiet_failure) {
  const fs::path log = m_out / "logs" / (logname + ".log");
  appendText(m_out / "commands.txt", joinCommand(argv) + "\n");
  appendText(log, "# " + common::utcTimestamp() + ": " + joinCommand(argv) + "\n");
  if (!m_a.quiet && ::isatty(2)) {
    std::fprintf(stderr, "\rpair: %s ...%40s\r", label.c_str(), "");
    std::fflush(stderr);
  }
  const pid_t pid = spawn(argv, log);
  int st = 0;
  while (::waitpid(pid, &st, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("waitpid failed");
    if (stopped()) {
      ::kill(pid, SIGTERM);
      ::waitpid(pid, nullptr, 0);
      throw common::Interrupted(
          "pair: interrupted during " + label + "; run the same command again to resume",
          stopped());
    }
  }
  if (!m_a.quiet && ::isatty(2)) std::fprintf(stderr, "\r%100s\r", "");
  const int rc = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  if (rc != 0 && !quiet_failure)
    say(label + ": FAILED (exit status " + std::to_string(rc) + "): " + lastLine(log) +
        " [log: " + log.string() + "]");
  return rc;
}

int PairStudy::runStageStep(const StageStep& step) {
  if (!step.redo && stageDone(step.marker, step.spec) && fs::exists(step.made))
    return STEP_SKIPPED;
  fs::remove(step.marker);
  if (!step.clear.empty()) fs::remove_all(step.clear);
  const int rc = runStep(step.label, step.argv, step.logname, step.quiet_failure);
  if (rc == 0) writeText(step.marker, step.spec);
  return rc;
}

void PairStudy::analyse() {
  const auto t0 = clock::now();
  for (double K : m_c.K) {
    const std::string name = kName(K);
    const fs::path dir = m_out / "analysis" / name, marker = m_out / "analysis" / (name + ".done");
    std::vector<std::string> argv{m_s.exe, "analyze"};
    std::string spec = "analyze";
    for (const RunJob& j : m_runs)
      if (j.K == K) {
        argv.push_back(j.dir.string());
        spec += " " + j.spec;
      }
    argv.insert(argv.end(), m_c.analysis_args.begin(), m_c.analysis_args.end());
    for (const auto& x : m_c.analysis_args) spec += " " + x;
    spec += "\n";
    argv.insert(argv.end(), {"--out", dir.string(), "--threads", std::to_string(m_cores), "-q"});
    const int rc = runStageStep({"analysis " + name, "analyze-" + name, argv, spec, marker,
                                 dir / "S_t.csv", dir, m_changed_k.count(name) > 0});
    if (rc == STEP_SKIPPED) {
      say("analysis " + name + ": up to date, skipped", false);
    } else if (rc == 0) {
      m_changed_k.insert(name);
      say("analysis " + name + ": done (" + dir.string() + ")");
    } else {
      ++m_failures;
      m_status["analysis " + name] = "failed";
    }
  }
  m_timing["analysis"] += std::chrono::duration<double>(clock::now() - t0).count();
}

void PairStudy::meanField() {
  const auto t0 = clock::now();
  const fs::path dir = m_out / "meanfield";
  fs::create_directories(dir);
  // Kinetic theory with the neutral runs' contact parameters (or the first K's).
  const MdPlan& ref = m_md.count(kName(0.0)) ? m_md.at(kName(0.0)) : m_md.at(kName(m_c.K.front()));
  double kappa = ref.kappa;
  for (double K : m_c.K)
    if (K > 0) kappa = m_md.at(kName(K)).kappa;
  double t_md = 0;
  for (const auto& [n, plan] : m_md) t_md = std::max(t_md, plan.t_end);
  struct Step {
    std::string label, file;
    std::vector<std::string> args;
  };
  std::vector<Step> steps;
  for (double b : m_c.betas)
    steps.push_back({"mean field S(t), beta = " + formatReal(b),
                     "S_beta" + formatReal(b) + ".csv",
                     {"smol", "--beta", formatReal(b), "--method", "sectional", "--t-end",
                      formatReal(m_c.mf_t_end), "--s-end", formatReal(m_c.mf_s_end)}});
  steps.push_back({"mean field z(beta)",
                   "zbeta.csv",
                   {"smol", "zbeta", "--beta-min", formatReal(m_c.zbeta_min), "--beta-max",
                    formatReal(m_c.zbeta_max), "--count", std::to_string(m_c.zbeta_count)}});
  steps.push_back({"kinetic theory: cooling",
                   "cooling.csv",
                   {"kinetic", "cooling", "--phi", formatReal(ref.phi), "--E", formatReal(ref.E),
                    "--D", formatReal(ref.D), "--t-end", formatReal(std::max(t_md, 1.0))}});
  steps.push_back({"kinetic theory: charging rate",
                   "charging.csv",
                   {"kinetic", "charging", "--kappa", formatReal(kappa)}});
  int ok = 0;
  for (const Step& s : steps) {
    const fs::path out = dir / s.file;
    std::string spec;
    for (const auto& x : s.args) spec += x + " ";
    spec += "\n";
    std::vector<std::string> argv{m_s.exe};
    argv.insert(argv.end(), s.args.begin(), s.args.end());
    argv.insert(argv.end(), {"--out", out.string(), "--force"});
    if (s.args[0] == "smol" && s.args[1] != "zbeta") argv.push_back("-q");
    const int rc =
        runStageStep({s.label, "meanfield", argv, spec, dir / (s.file + ".done"), out, {}});
    if (rc == 0 || rc == STEP_SKIPPED)
      ++ok;
    else
      ++m_failures;
  }
  m_status["meanfield"] =
      ok == static_cast<int>(steps.size()) ? "done" : "failed (see logs/meanfield.log)";
  say("mean field: " + m_status["meanfield"] + " (" + dir.string() + ")");
  m_timing["meanfield"] += std::chrono::duration<double>(clock::now() - t0).count();
}

void PairStudy::fitBeta() {
  const auto t0 = clock::now();
  if (!m_s.fit_available) {
    m_status["fit"] = "skipped: this granagg has no fit-beta subcommand";
    say("fit: skipped (this granagg build has no `fit-beta` subcommand; no beta is reported)");
    return;
  }
  int ok = 0;
  for (double K : m_c.K) {
    const std::string name = kName(K);
    const fs::path in = m_out / "analysis" / name, dir = m_out / "fit" / name,
                   marker = m_out / "fit" / (name + ".done");
    if (!fs::exists(in / "S_t.csv")) continue;
    std::vector<std::string> argv{m_s.exe, "fit-beta", in.string()};
    if (!m_c.fit_column.empty()) argv.insert(argv.end(), {"--column", m_c.fit_column});
    if (!m_c.fit_window.empty())
      argv.insert(argv.end(),
                  {"--window", formatReal(m_c.fit_window[0]), formatReal(m_c.fit_window[1])});
    const std::string spec = joinCommand(std::vector<std::string>(argv.begin() + 1, argv.end())) +
                             " " + readText(m_out / "analysis" / (name + ".done"));
    fs::create_directories(dir.parent_path());
    argv.insert(argv.end(), {"--out", dir.string(), "-q"});
    const int rc = runStageStep({"fit " + name, "fit-" + name, argv, spec, marker,
                                 dir / "fit_beta.json", dir, m_changed_k.count(name) > 0,
                                 /*quiet_failure=*/true});
    if (rc == STEP_SKIPPED) {
      ++ok;
      say("fit " + name + ": up to date, skipped", false);
    } else if (rc == 0) {
      ++ok;
      say("fit " + name + ": done (" + dir.string() + ")");
    } else if (rc == 2) {
      // fit-beta's "these data cannot be fitted" (e.g. S(t) that does not grow in a short run): a
      // result to report, not a failure of the study.
      std::string why = lastLine(m_out / "logs" / ("fit-" + name + ".log"));
      const std::string prefix = common::ERROR_PREFIX;
      if (why.rfind(prefix, 0) == 0) why = why.substr(prefix.size());
      m_fit_note[name] = "not possible for these data: " + why;
      say("fit " + name + ": not possible for these data (" + why + ")");
    } else {
      ++m_failures;
      say("fit " + name + ": FAILED (exit status " + std::to_string(rc) +
          ", log: " + (m_out / "logs" / ("fit-" + name + ".log")).string() + ")");
    }
  }
  const std::size_t fitted = static_cast<std::size_t>(ok), nK = m_c.K.size();
  m_status["fit"] = fitted == nK                      ? "done"
                    : fitted + m_fit_note.size() < nK ? "failed for some K (see logs/fit-*.log)"
                    : fitted > 0
                        ? "done where the data allow a fit"
                        : "not possible for these data (see each ensemble's fit_beta note)";
  m_timing["fit"] += std::chrono::duration<double>(clock::now() - t0).count();
}

/// One Python stage (scripts/<script> with the study folder as its argument) that writes `made`;
/// its failure is counted, not fatal.
void PairStudy::pythonStage(const std::string& stage, const std::string& script,
                            const fs::path& made) {
  const auto t0 = clock::now();
  const fs::path path = m_s.scripts / script;
  if (!fs::exists(path)) {
    m_status[stage] = "skipped: " + path.string() + " not found (set GRANAGG_SCRIPTS)";
    say(stage + ": " + m_status[stage]);
  } else if (runStep(stage, {m_s.python, path.string(), m_out.string()}, stage) == 0) {
    m_status[stage] = "done";
    say(stage + ": done (" + made.string() + ")");
  } else {
    m_status[stage] = "failed (see logs/" + stage + ".log)";
    ++m_failures;
  }
  m_timing[stage] = std::chrono::duration<double>(clock::now() - t0).count();
}

/// The figures (scripts/plot_figures.py), then the summary, written once, then report.html
/// (scripts/make_report.py), which is made from that summary and so comes after it: the
/// summary says so, and the report's outcome is in pair.log and the printed summary. Python
/// from Debian.
void PairStudy::figuresAndReport() {
  if (m_a.no_figures) {
    m_status["figures"] = m_status["report"] = "skipped (--no-figures)";
    writeSummary();
    return;
  }
  pythonStage("figures", "plot_figures.py", m_out / "figures");
  m_status["report"] =
      "made from this summary after it (report.html; its outcome: pair.log and the printed "
      "summary)";
  writeSummary();
  pythonStage("report", "make_report.py", m_out / "report.html");
}

void PairStudy::run() {
  prepareFolder();
  for (const auto& [path, text] : m_md_text)
    if (!fs::exists(path) || readText(path) != text) writeText(path, text);
  const std::string resolved = toToml(m_c);
  const fs::path cfgpath = m_out / "config" / "pair.toml";
  if (m_a.run_index < 0 && (!fs::exists(cfgpath) || readText(cfgpath) != resolved))
    writeText(cfgpath, resolved);
  if (m_a.run_index >= 0 && !fs::exists(cfgpath)) writeText(cfgpath, resolved);

  if (m_a.emit_batch == "slurm") {
    emitSlurm();
    return;
  }
  if (m_a.run_index >= 0) {  // one array task of a batch job
    runMd({m_runs[static_cast<std::size_t>(m_a.run_index)]});
    return;
  }
  say("study '" + m_c.name + "' -> " + m_out.string() + " (" + common::versionString() +
      "; K = " + kList(m_c.K) + ", " + std::to_string(m_c.runs) + " runs each, " +
      std::to_string(m_cores) + " cores)" +
      (m_launch.lammps() ? "; MD by " + joinCommand(m_launch.launcher) + " granagg-lammps" : ""));
  runMd(m_runs);
  analyse();
  meanField();
  fitBeta();
  m_status["md"] = "done";
  figuresAndReport();  // with the summary, written once
  printSummary();
  if (m_failures > 0)
    throw std::runtime_error(std::to_string(m_failures) + " post-processing step(s) failed (see " +
                             (m_out / "pair.log").string() +
                             "); run the same command again to retry them");
}

}  // namespace granagg::study
