/// `granagg md`: run the MD engine from a TOML configuration, write an H5MD trajectory,
/// observables and checkpoints into an output folder; `--restart DIR` continues a run.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Version.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"
#include "md/io/Checkpoint.h"
#include "md/io/H5mdWriter.h"
#include "md/io/InitialState.h"

namespace granagg::cli {
namespace fs = std::filesystem;

namespace {

struct MdArgs {
  std::string config;
  std::string preset;
  std::vector<std::string> set;
  std::string out;
  std::string restart;
  long long seed = -1;
  int threads = 0;
  bool force = false;
  bool quiet = false;
  bool profile = false;
};

std::string presetPath(const std::string& name) {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("GRANAGG_DATA")) dirs.push_back(std::string(env) + "/presets");
  dirs.push_back(std::string(GRANAGG_DATA_DIR) + "/presets");
  for (const auto& d : dirs) {
    const fs::path p = fs::path(d) / (name + ".toml");
    if (fs::exists(p)) return p.string();
  }
  throw std::invalid_argument("--preset: no preset named '" + name + "' in " + dirs.back() +
                              " (available: quick, paper, haff)");
}

/// Steps at which frames are written: t = 0, log-spaced (frames_per_decade from t = 0.01, or from
/// dt if larger) and linear (frame_interval), and the last step.
std::vector<std::int64_t> frameSteps(const md::MdConfig& c, double dt, std::int64_t last) {
  std::set<std::int64_t> s{0, last};
  if (c.output.frames_per_decade > 0) {
    const double t0 = std::max(0.01, dt);
    const double k = std::pow(10.0, 1.0 / c.output.frames_per_decade);
    for (double t = t0; t < c.run.t_end * (1 + 1e-12); t *= k) s.insert(std::min<std::int64_t>(last, std::llround(t / dt)));
  }
  if (c.output.frame_interval > 0.0)
    for (double t = c.output.frame_interval; t < c.run.t_end * (1 + 1e-12); t += c.output.frame_interval)
      s.insert(std::min<std::int64_t>(last, std::llround(t / dt)));
  return {s.begin(), s.end()};
}

/// The frame to write: the engine's state, with its per-particle forces when output.write_forces.
md::Frame outputFrame(const md::Engine& engine, const md::MdConfig& cfg) {
  md::Frame f = engine.frame(md::StateKind::Physical);
  if (cfg.output.write_forces) {
    const std::vector<double> all = engine.forces(md::StateKind::Physical);
    const std::size_t N = engine.size();
    f.fx.assign(all.begin(), all.begin() + N);
    f.fy.assign(all.begin() + N, all.begin() + 2 * N);
    f.fz.assign(all.begin() + 2 * N, all.end());
  }
  return f;
}

std::vector<std::pair<std::string, double>> observableRow(const md::Observables& o) {
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

class Progress {
 public:
  Progress(bool enabled, double t_end) : m_on(enabled && ::isatty(2)), m_t_end(t_end), m_start(clock::now()), m_last(m_start) {}
  void update(double t, std::int64_t steps_done, double T) {
    if (!m_on) return;
    const auto now = clock::now();
    if (std::chrono::duration<double>(now - m_last).count() < 0.5) return;
    m_last = now;
    const double el = std::chrono::duration<double>(now - m_start).count();
    const double rate = steps_done / std::max(el, 1e-9);
    const double frac = t / m_t_end;
    const double eta = frac > 0 ? el * (1 - frac) / frac : 0.0;
    std::fprintf(stderr, "\rmd: t = %.4g / %.4g  T_g = %.4g  %.3g steps/s  ETA %.0f s   ", t, m_t_end, T, rate, eta);
    std::fflush(stderr);
  }
  void done() {
    if (m_on) std::fprintf(stderr, "\n");
  }

 private:
  using clock = std::chrono::steady_clock;
  bool m_on;
  double m_t_end;
  clock::time_point m_start, m_last;
};

/// `--profile`: wall time by phase of the MD loop, printed (stderr) and written to `path` as one
/// row (seconds per phase; `other` = the loop's time not in any phase: observables, output,
/// checkpoints). Benchmarks read the CSV (scripts/bench_coulomb_lammps.sh), people the table.
void writeProfile(const md::Engine& engine, const fs::path& path, const CliContext& ctx,
                  std::int64_t steps, double loop_seconds) {
  const auto phases = engine.phaseSeconds();
  std::vector<std::string> columns = {"steps", "N", "loop_s"};
  std::vector<double> row = {static_cast<double>(steps), static_cast<double>(engine.size()),
                             loop_seconds};
  double sum = 0.0;
  std::fprintf(stderr, "md: time by phase (--profile), %lld steps, loop %.4g s:\n",
               static_cast<long long>(steps), loop_seconds);
  auto line = [&](const std::string& name, double s) {
    std::fprintf(stderr, "md:   %-22s %10.4g s  %5.1f %%  %8.3g us/step\n", name.c_str(), s,
                 loop_seconds > 0 ? 100.0 * s / loop_seconds : 0.0,
                 steps > 0 ? 1e6 * s / steps : 0.0);
  };
  for (const auto& [name, s] : phases) {
    std::string col;  // "PPPM k-space" -> "pppm_k_space_s"
    for (char c : name)
      col += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(c)) : '_';
    while (col.find("__") != std::string::npos) col.erase(col.find("__"), 1);
    if (!col.empty() && col.back() == '_') col.pop_back();
    columns.push_back(col + "_s");
    row.push_back(s);
    sum += s;
    if (s > 0.0) line(name, s);
  }
  columns.push_back("other_s");
  row.push_back(loop_seconds - sum);
  line("other (output, obs.)", loop_seconds - sum);
  common::Provenance prov(ctx.command_line);
  prov.add("version", common::versionString());
  prov.add("backend", md::Engine::backendDescription());
  common::CsvWriter w(path.string(), prov, columns, /*overwrite=*/true);
  w.row(row);
  w.close();
}

void runMd(const MdArgs& a, const CliContext& ctx) {
  if (a.threads < 0) throw std::invalid_argument("--threads must be >= 1.");
  if (a.threads > 0) md::Engine::setThreads(a.threads);
  const bool restart = !a.restart.empty();
  md::MdConfig cfg;
  md::Checkpoint ck;
  fs::path out;
  if (restart) {
    if (!a.config.empty() || !a.preset.empty() || a.seed >= 0)
      throw std::invalid_argument("--restart continues a run with its own configuration: do not combine it with --config, --preset or --seed.");
    for (const auto& s : a.set)
      if (s.rfind("run.t_end=", 0) != 0)
        throw std::invalid_argument("--restart accepts only --set run.t_end=... (to run further); got --set " + s);
    out = a.restart;
    const fs::path cpath = out / "checkpoint.h5";
    if (!fs::exists(cpath)) throw std::invalid_argument("--restart: no checkpoint at " + cpath.string());
    ck = md::readCheckpoint(cpath.string());
    cfg = md::parseConfigString(ck.extra.config_toml, cpath.string() + ":/config_toml", a.set);
  } else {
    if (a.config.empty() == a.preset.empty()) throw std::invalid_argument("give exactly one of --config FILE or --preset NAME (or --restart DIR).");
    std::vector<std::string> overrides = a.set;
    if (a.seed >= 0) overrides.push_back("system.seed=" + std::to_string(a.seed));
    cfg = md::parseConfigFile(a.config.empty() ? presetPath(a.preset) : a.config, overrides);
    out = a.out.empty() ? fs::path("md-out") : fs::path(a.out);
    if (fs::exists(out) && !fs::is_empty(out) && !a.force)
      throw std::invalid_argument("output folder '" + out.string() + "' exists and is not empty; choose another --out or pass --force to overwrite it");
    fs::create_directories(out);
  }
  md::validateConfig(cfg);

  // initial state
  md::Frame init;
  if (restart) {
    init = ck.state;
  } else if (cfg.system.initial == "random") {
    init = md::Engine::randomInitialState(cfg);
  } else {
    init = md::readInitialState(cfg.system.initial, md::boxLength(cfg.system));
    if (static_cast<int>(init.size()) != cfg.system.N)
      throw std::invalid_argument("system.initial '" + cfg.system.initial + "' holds " + std::to_string(init.size()) +
                                  " particles but system.N = " + std::to_string(cfg.system.N));
    md::Engine::assignInitialCharges(cfg, init);
  }
  md::Engine engine(cfg, init, /*allow_contacts=*/restart);
  engine.enableProfile(a.profile);
  if (restart) {
    std::vector<double> f = ck.extra.fx;
    f.insert(f.end(), ck.extra.fy.begin(), ck.extra.fy.end());
    f.insert(f.end(), ck.extra.fz.begin(), ck.extra.fz.end());
    const auto it = ck.extra.int_scalars.find("collisions");
    const auto design = ck.extra.real_scalars.find("coulomb_sum_q2_design");
    if (design != ck.extra.real_scalars.end()) engine.useCoulombDesign(design->second);
    md::EngineExtra extra;
    extra.arrays = ck.extra.arrays;
    extra.ints = ck.extra.int_scalars;
    extra.reals = ck.extra.real_scalars;
    engine.restore(ck.state, f, it == ck.extra.int_scalars.end() ? 0 : it->second, extra);
  }
  std::string dt_reason;
  md::Engine::chooseTimeStep(cfg, &dt_reason);
  const double dt = engine.dt();
  const auto last = static_cast<std::int64_t>(std::llround(cfg.run.t_end / dt));

  const bool quiet = a.quiet;
  if (!quiet) {
    std::printf("md: %s\n", common::versionString().c_str());
    std::printf("md: backend: %s\n", md::Engine::backendDescription().c_str());
    std::printf("md: N = %d, phi = %g, box L = %.6g, contact model %s, seed %llu\n", cfg.system.N, cfg.system.phi,
                engine.box(), cfg.contact.model.c_str(), static_cast<unsigned long long>(cfg.system.seed));
    std::printf("md: dt = %.6g (%s); %lld steps to t_end = %g\n", dt, dt_reason.c_str(), static_cast<long long>(last),
                cfg.run.t_end);
    if (const md::CoulombSetup* cs = engine.coulombSetup())
      std::printf("md: Coulomb K = %g, %s: alpha = %.6g, r_cut = %.6g, %s; estimated relative force error %.2g (for sum q^2 = %.4g)\n",
                  cfg.coulomb.K, cs->method.c_str(), cs->alpha, cs->r_cut,
                  cs->method == "pppm" ? ("mesh " + std::to_string(cs->mesh) + "^3, order " + std::to_string(cs->order)).c_str()
                                       : ("k_max " + std::to_string(cs->k_max)).c_str(),
                  cs->estimated_error, cs->sum_q2_design);
    if (const md::CoulombSetup* cs = engine.coulombSetup(); cs && cs->r_fast > 0.0)
      std::printf(
          "md: multiple time stepping: slow Coulomb part every %d steps%s; pair force within "
          "r_fast = %g every step\n",
          cs->every,
          cs->every_max > cs->every
              ? (", growing to at most " + std::to_string(cs->every_max) + " as the gas cools")
                    .c_str()
              : "",
          cs->r_fast);
    if (restart) std::printf("md: restarting from step %lld of %s\n", static_cast<long long>(engine.step()), out.c_str());
  }

  // trajectory
  const fs::path traj = out / "traj.h5";
  std::unique_ptr<md::H5mdWriter> writer;
  if (restart) {
    writer = std::make_unique<md::H5mdWriter>(md::H5mdWriter::reopen(traj.string(), engine.size(), engine.step(),
                                                                     cfg.output.write_velocities, cfg.output.write_forces));
  } else {
    auto params = md::flatten(cfg);
    params.emplace_back("version", common::versionString());
    params.emplace_back("command", ctx.command_line);
    params.emplace_back("backend", md::Engine::backendDescription());
    params.emplace_back("dt", common::formatReal(dt));
    params.emplace_back("dt_reason", dt_reason);
    if (const md::CoulombSetup* cs = engine.coulombSetup()) {  // the parameters chosen for coulomb.accuracy
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
    writer = std::make_unique<md::H5mdWriter>(traj.string(), engine.size(), params, md::toToml(cfg), a.force,
                                              cfg.output.write_velocities, cfg.output.write_forces);
  }
  const auto frames = frameSteps(cfg, dt, last);
  auto nextFrame = std::upper_bound(frames.begin(), frames.end(), engine.step());
  if (!restart) {
    writer->writeObservables(0, 0.0, observableRow(engine.observables()));
    writer->writeFrame(outputFrame(engine, cfg));
  }

  const fs::path cpath = out / "checkpoint.h5";
  auto checkpoint = [&]() {
    writer->flush();
    const md::Frame state = engine.frame();
    const std::vector<double> f = engine.forces();
    const std::size_t N = engine.size();
    md::CheckpointExtra c;
    c.fx.assign(f.begin(), f.begin() + N);
    c.fy.assign(f.begin() + N, f.begin() + 2 * N);
    c.fz.assign(f.begin() + 2 * N, f.end());
    c.dt = dt;
    c.config_toml = md::toToml(cfg);
    c.seed = cfg.system.seed;
    c.frames_written = writer->frames();
    c.next_frame_index = static_cast<std::uint64_t>(nextFrame - frames.begin());
    c.int_scalars["collisions"] = engine.observables().collisions;
    if (const md::CoulombSetup* cs = engine.coulombSetup()) c.real_scalars["coulomb_sum_q2_design"] = cs->sum_q2_design;
    md::EngineExtra extra = engine.extraState();
    c.arrays = std::move(extra.arrays);
    c.int_scalars.insert(extra.ints.begin(), extra.ints.end());
    c.real_scalars.insert(extra.reals.begin(), extra.reals.end());
    md::writeCheckpoint(cpath.string(), state, c);
  };
  auto lastCheckpoint = std::chrono::steady_clock::now();
  std::int64_t last_checkpoint_step = engine.step();

  Progress progress(!quiet, cfg.run.t_end);
  const std::int64_t obs_every = cfg.output.observable_interval;
  const std::int64_t first_step = engine.step();
  const std::int64_t first_builds = engine.neighborBuilds();
  const auto loop_start = std::chrono::steady_clock::now();
  try {
    while (engine.step() < last) {
      std::int64_t target = std::min(last, (engine.step() / obs_every + 1) * obs_every);
      if (nextFrame != frames.end()) target = std::min(target, *nextFrame);
      if (cfg.output.checkpoint_interval > 0)
        target = std::min(target, (engine.step() / cfg.output.checkpoint_interval + 1) * cfg.output.checkpoint_interval);
      engine.run(target - engine.step());
      const auto o = engine.observables();
      if (engine.step() % obs_every == 0 || engine.step() == last) writer->writeObservables(o.step, o.time, observableRow(o));
      if (nextFrame != frames.end() && engine.step() == *nextFrame) {
        writer->writeFrame(outputFrame(engine, cfg));
        ++nextFrame;
      }
      const bool by_steps = cfg.output.checkpoint_interval > 0 && engine.step() % cfg.output.checkpoint_interval == 0;
      const bool by_wall = cfg.output.checkpoint_wall_seconds > 0 &&
                           std::chrono::duration<double>(std::chrono::steady_clock::now() - lastCheckpoint).count() >
                               cfg.output.checkpoint_wall_seconds;
      if (by_steps || by_wall) {
        checkpoint();
        lastCheckpoint = std::chrono::steady_clock::now();
        last_checkpoint_step = engine.step();
      }
      progress.update(o.time, engine.step() - first_step, o.temperature);
    }
  } catch (const md::RunAborted& e) {
    progress.done();
    writer->close();
    throw std::runtime_error(std::string(e.what()) + ". Trajectory up to the last frame in " + traj.string() +
                             (fs::exists(cpath) ? "; last good checkpoint (step " + std::to_string(last_checkpoint_step) +
                                                      ") kept in " + cpath.string()
                                                : "; no checkpoint was written before the failure"));
  }
  progress.done();
  const double loop_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
  checkpoint();
  writer->close();
  if (a.profile)
    writeProfile(engine, out / "profile.csv", ctx, engine.step() - first_step, loop_seconds);
  if (!quiet) {
    const auto o = engine.observables();
    const std::int64_t steps = engine.step() - first_step, builds = engine.neighborBuilds() - first_builds;
    std::printf("md: %lld steps in %.4g s (%.3g particle-steps/s incl. output); neighbour list rebuilt %lld times (every %.3g steps)\n",
                static_cast<long long>(steps), loop_seconds,
                loop_seconds > 0 ? static_cast<double>(steps) * engine.size() / loop_seconds : 0.0,
                static_cast<long long>(builds), builds > 0 ? static_cast<double>(steps) / builds : 0.0);
    std::printf("md: done at t = %g: T_g = %.6g, %lld collisions, %.3g contacts per particle, max overlap %.3g\n", o.time,
                o.temperature, static_cast<long long>(o.collisions), o.contacts_per_particle, o.max_overlap);
    if (const md::CoulombSetup* cs = engine.coulombSetup(); cs && cs->r_fast > 0.0)
      std::printf(
          "md: slow Coulomb part evaluated %lld times (every %.3g steps on average; interval "
          "now %d steps)\n",
          static_cast<long long>(engine.slowEvaluations()),
          engine.slowEvaluations() > 0 ? static_cast<double>(steps) / engine.slowEvaluations()
                                       : 0.0,
          engine.slowInterval());
    std::printf("md: wrote %s (%zu frames), %s\n", traj.c_str(), writer->frames(), cpath.c_str());
  }
}

}  // namespace

void registerMdCommand(CLI::App& app, const CliContext& ctx) {
  auto a = std::make_shared<MdArgs>();
  CLI::App* md = app.add_subcommand(
      "md", "Run the MD engine (viscoelastic or spring-dashpot granular gas) and write an H5MD trajectory,\n"
            "observables and a checkpoint into an output folder. Reduced units d = m = T0 = 1.");
  md->add_option("-c,--config", a->config, "TOML configuration (keys: docs/config.md)");
  md->add_option("--preset", a->preset, "Preset from data/presets: quick, paper, haff");
  md->add_option("--set", a->set, "Override a key, e.g. --set system.N=5000 (repeatable)");
  md->add_option("-o,--out", a->out, "Output folder (default md-out); must not exist or be empty unless --force");
  md->add_option("--restart", a->restart,
                 "Continue the run whose output folder (with checkpoint.h5) is given; --set run.t_end=T runs it further");
  md->add_option("--seed", a->seed, "Random seed (overrides system.seed)");
  md->add_option("--threads", a->threads, "OpenMP threads (default: all cores; OMP_NUM_THREADS)");
  md->add_flag("--force", a->force, "Overwrite an existing output folder");
  md->add_flag("-q,--quiet", a->quiet, "No progress line or summary");
  md->add_flag(
      "--profile", a->profile,
      "Time the MD loop by phase (contact pass, lists, Coulomb, PPPM parts); prints a table "
      "and writes OUT/profile.csv. Changes no result");
  md->callback([a, ctx]() { runMd(*a, ctx); });
}

}  // namespace granagg::cli
