/// `granagg md`: run the MD engine from a TOML configuration, write an H5MD trajectory,
/// observables and checkpoints into an output folder; `--restart DIR` continues a run.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/ProgressLine.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"
#include "md/run/Simulation.h"

namespace granagg::cli {
namespace fs = std::filesystem;

namespace {

struct MdArgs {
  std::string config;
  std::string preset;
  std::vector<std::string> set;
  std::string out;
  std::string restart;
  std::string seed;  // "" = not given; else an integer in [0, 2^64) (checked in runMd)
  int threads = 0;
  bool force = false;
  bool quiet = false;
  bool profile = false;
};

/// The progress line on a terminal (stderr), at most twice a second.
/// The progress line (common/ProgressLine.h): in place on a terminal, a line a minute in a log.
class ProgressReporter : public md::Reporter {
 public:
  explicit ProgressReporter(const md::Simulation& sim)
      : m_line("md", true),
        m_t_end(sim.config().run.t_end),
        m_t_start(sim.engine().time()),
        m_first_step(sim.engine().step()),
        m_start(Clock::now()) {}
  void report(const md::Simulation& sim) override {
    if (!m_line.due()) return;
    const md::Engine& e = sim.engine();
    const double el = std::chrono::duration<double>(Clock::now() - m_start).count();
    const double rate = static_cast<double>(e.step() - m_first_step) / std::max(el, 1e-9);
    const double done = (e.time() - m_t_start) / std::max(m_t_end - m_t_start, 1e-300);
    const double eta = done > 0 ? el * (1 - done) / done : 0.0;
    char buf[200];
    std::snprintf(buf, sizeof buf, "t = %.4g / %.4g  T_g = %.4g  %.3g particle-steps/s  ETA %s",
                  e.time(), m_t_end, sim.lastObservables().temperature,
                  rate * static_cast<double>(e.size()), duration(eta).c_str());
    m_line.show(buf);
  }
  void finish(const md::Simulation&) override { m_line.finish(); }

 private:
  using Clock = std::chrono::steady_clock;
  static std::string duration(double s) {
    char b[32];
    if (s < 120)
      std::snprintf(b, sizeof b, "%.0f s", s);
    else if (s < 7200)
      std::snprintf(b, sizeof b, "%.0f min", s / 60);
    else
      std::snprintf(b, sizeof b, "%.1f h", s / 3600);
    return b;
  }
  common::ProgressLine m_line;
  double m_t_end, m_t_start;
  std::int64_t m_first_step;
  Clock::time_point m_start;
};

/// `--profile`: the loop's wall time by phase, as a table on stderr (profile.csv has the same).
void printProfile(const md::Engine& engine, std::int64_t steps, double loop_seconds) {
  std::fprintf(stderr, "md: time by phase (--profile), %lld steps, loop %.4g s:\n",
               static_cast<long long>(steps), loop_seconds);
  auto line = [&](const std::string& name, double s) {
    std::fprintf(stderr, "md:   %-22s %10.4g s  %5.1f %%  %8.3g us/step\n", name.c_str(), s,
                 loop_seconds > 0 ? 100.0 * s / loop_seconds : 0.0,
                 steps > 0 ? 1e6 * s / steps : 0.0);
  };
  double sum = 0.0;
  for (const auto& [name, s] : engine.phaseSeconds()) {
    sum += s;
    if (s > 0.0) line(name, s);
  }
  line("other (output, obs.)", loop_seconds - sum);
}

void printStart(const md::Simulation& sim) {
  const md::Engine& e = sim.engine();
  const md::MdConfig& cfg = sim.config();
  std::fprintf(stderr, "md: %s\n", common::versionString().c_str());
  // the hint belongs in the log, not in the outputs that store the description
#ifdef GRANAGG_CUDA
  const char* hint = "";
#else
  const char* hint = " (set OMP_NUM_THREADS or --threads to change)";
#endif
  std::fprintf(stderr, "md: backend: %s%s\n", md::Engine::backendDescription().c_str(), hint);
  std::fprintf(stderr, "md: N = %d, phi = %g, box L = %.6g, contact model %s, seed %llu\n",
               cfg.system.N, cfg.system.phi, e.box(), cfg.contact.model.c_str(),
               static_cast<unsigned long long>(cfg.system.seed));
  const double t_last = static_cast<double>(sim.lastStep()) * e.dt();
  char ends[96] = "";
  if (t_last != cfg.run.t_end)  // time = step * dt: the run ends on the step nearest t_end
    std::snprintf(ends, sizeof ends, " (ends at t = %.6g, the whole step nearest t_end)", t_last);
  std::fprintf(stderr, "md: dt = %.6g (%s); %lld steps to t_end = %g%s\n", e.dt(),
               sim.dtReason().c_str(), static_cast<long long>(sim.lastStep()), cfg.run.t_end, ends);
  if (const md::CoulombSetup* cs = e.coulombSetup()) {
    const std::string mesh = cs->method == "pppm" ? "mesh " + std::to_string(cs->mesh) +
                                                        "^3, order " + std::to_string(cs->order)
                                                  : "k_max " + std::to_string(cs->k_max);
    std::fprintf(stderr,
                 "md: Coulomb K = %g, %s: alpha = %.6g, r_cut = %.6g, %s; estimated relative "
                 "force error %.2g (for sum q^2 = %.4g)\n",
                 cfg.coulomb.K, cs->method.c_str(), cs->alpha, cs->r_cut, mesh.c_str(),
                 cs->estimated_error, cs->sum_q2_design);
    if (cs->r_fast > 0.0)
      std::fprintf(
          stderr,
          "md: multiple time stepping: slow Coulomb part every %d steps%s; pair force within "
          "r_fast = %g every step\n",
          cs->every,
          cs->every_max > cs->every
              ? (", growing to at most " + std::to_string(cs->every_max) + " as the gas cools")
                    .c_str()
              : "",
          cs->r_fast);
  }
  if (sim.resumed())
    std::fprintf(stderr, "md: restarting from step %lld of %s\n", static_cast<long long>(e.step()),
                 sim.folder().c_str());
}

void printSummary(const md::Simulation& sim, const md::RunSummary& s) {
  const md::Engine& e = sim.engine();
  const md::Observables o = e.observables();
  std::fprintf(stderr,
               "md: %lld steps in %.4g s (%.3g particle-steps/s incl. output); neighbour list "
               "rebuilt %lld times (every %.3g steps)\n",
               static_cast<long long>(s.steps), s.loop_seconds,
               s.loop_seconds > 0 ? static_cast<double>(s.steps) * e.size() / s.loop_seconds : 0.0,
               static_cast<long long>(s.neighbor_builds),
               s.neighbor_builds > 0 ? static_cast<double>(s.steps) / s.neighbor_builds : 0.0);
  std::fprintf(stderr,
               "md: done at t = %g: T_g = %.6g, %lld collisions, %.3g contacts per particle, max "
               "overlap %.3g\n",
               o.time, o.temperature, static_cast<long long>(o.collisions), o.contacts_per_particle,
               o.max_overlap);
  if (const md::CoulombSetup* cs = e.coulombSetup(); cs && cs->r_fast > 0.0)
    std::fprintf(stderr,
                 "md: slow Coulomb part evaluated %lld times (every %.3g steps on average; "
                 "interval now %d steps)\n",
                 static_cast<long long>(s.slow_evaluations),
                 s.slow_evaluations > 0 ? static_cast<double>(s.steps) / s.slow_evaluations : 0.0,
                 e.slowInterval());
  std::fprintf(stderr, "md: wrote %s (%zu frames), %s\n", sim.trajectoryPath().c_str(),
               sim.framesWritten(), sim.checkpointPath().c_str());
}

/// --seed as given, if it is an integer in [0, 2^64) (system.seed's range, docs/config.md): a
/// long long option turned -1 into "not given" and clamped seeds above 2^63 - 1.
std::string checkedSeed(const std::string& s) {
  errno = 0;
  char* end = nullptr;
  const bool digits =
      !s.empty() && s.size() <= 20 && s.find_first_not_of("0123456789") == std::string::npos;
  if (digits) std::strtoull(s.c_str(), &end, 10);
  if (!digits || errno == ERANGE)
    throw std::invalid_argument("--seed must be an integer in [0, 2^64) (got '" + s + "')");
  return s;
}

void runMd(const MdArgs& a, const CliContext& ctx) {
  if (a.threads < 0) throw std::invalid_argument("--threads must be >= 1.");
  if (a.threads > 0) md::Engine::setThreads(a.threads);
  md::RunOptions options;
  options.command_line = ctx.command_line;
  options.overwrite = a.force;
  options.profile = a.profile;
  catchStopSignals();  // SIGINT / SIGTERM: stop at the end of a chunk with a checkpoint
  options.stop = stopSignal();
  std::optional<md::Simulation> sim;
  if (!a.restart.empty()) {
    if (!a.out.empty())
      throw std::invalid_argument(
          "--out cannot be combined with --restart: the run continues in "
          "its own folder " +
          a.restart);
    if (!a.config.empty() || !a.preset.empty() || !a.seed.empty())
      throw std::invalid_argument(
          "--restart continues a run with its own configuration: do not "
          "combine it with --config, --preset or --seed.");
    sim.emplace(md::Simulation::resume(a.restart, a.set, options));
  } else {
    if (!a.config.empty() && !a.preset.empty())
      throw std::invalid_argument("give one of --config FILE and --preset NAME, not both.");
    std::vector<std::string> overrides = a.set;
    if (!a.seed.empty()) overrides.push_back("system.seed=" + checkedSeed(a.seed));
    // neither: every key has a default (docs/config.md), --set changes them
    const md::MdConfig cfg =
        a.config.empty() && a.preset.empty()
            ? md::parseConfigString("", "(defaults)", overrides)
            : md::parseConfigFile(
                  a.config.empty() ? findPreset("presets", a.preset, "--preset") : a.config,
                  overrides);
    sim.emplace(md::Simulation::start(cfg, a.out.empty() ? "md-out" : a.out, options));
  }
  if (!a.quiet) {
    printStart(*sim);
    sim->addReporter(std::make_shared<ProgressReporter>(*sim));
  }
  const md::RunSummary s = sim->run();
  if (a.profile) printProfile(sim->engine(), s.steps, s.loop_seconds);
  if (!a.quiet) printSummary(*sim, s);
  if (s.stopped) {
    const int sig = *stopSignal();
    char t[32];
    std::snprintf(t, sizeof t, "%.6g", sim->engine().time());
    throw Interrupted(std::string("md: ") + (sig == SIGINT ? "SIGINT" : "SIGTERM") + " at step " +
                          std::to_string(sim->engine().step()) + " (t = " + t + " of " +
                          common::formatReal(sim->config().run.t_end) +
                          "); checkpoint and trajectory written; continue with: granagg md "
                          "--restart " +
                          sim->folder().string(),
                      sig);
  }
}

}  // namespace

void registerMdCommand(CLI::App& app, const CliContext& ctx) {
  auto a = std::make_shared<MdArgs>();
  CLI::App* md = app.add_subcommand(
      "md",
      "Run the MD engine (viscoelastic or spring-dashpot granular gas) and write an H5MD "
      "trajectory,\n"
      "observables and a checkpoint into an output folder. Reduced units d = m = T0 = 1.");
  md->add_option("-c,--config", a->config, "TOML configuration (keys: docs/config.md)");
  md->add_option("--preset", a->preset, "Preset from data/presets: quick, paper, haff");
  md->add_option("--set", a->set, "Override a key, e.g. --set system.N=5000 (repeatable)");
  md->add_option("-o,--out", a->out,
                 "Output folder (default md-out); must not exist or be empty unless --force");
  md->add_option("--restart", a->restart,
                 "Continue the run whose output folder (with checkpoint.h5) is given; --set "
                 "run.t_end=T runs it further");
  md->add_option("--seed", a->seed, "Random seed, an integer in [0, 2^64) (overrides system.seed)");
  md->add_option("--threads", a->threads, "OpenMP threads (default: all cores; OMP_NUM_THREADS)")
      ->check(CLI::Range(1, 4096));
  md->add_flag("--force", a->force, "Overwrite an existing output folder");
  md->add_flag("-q,--quiet", a->quiet, "No progress line or summary");
  md->add_flag(
      "--profile", a->profile,
      "Time the MD loop by phase (contact pass, lists, Coulomb, PPPM parts); prints a table "
      "and writes OUT/profile.csv. Changes no result");
  md->callback([a, ctx]() { runMd(*a, ctx); });
}

}  // namespace granagg::cli
