/// \file RunLog.cpp
/// The run's log lines and progress reporter (RunLog.h).
#include "md/run/RunLog.h"

#include <algorithm>

#include "common/Csv.h"
#include "common/Strings.h"
#include "common/Version.h"
#include "md/engine/Engine.h"

namespace granagg::md {
using common::printfString;

std::vector<std::string> runStartLines(const Simulation& sim) {
  const RunEngine& e = sim.engine();
  const MdConfig& cfg = sim.config();
  std::vector<std::string> out;
  out.push_back("md: " + common::versionString());
  // the hint belongs in the log, not in the outputs that store the description; it is about
  // granagg's own engine on the CPU (LAMMPS's ranks are mpirun's -np)
#ifdef GRANAGG_CUDA
  const char* hint = "";
#else
  const char* hint =
      dynamic_cast<const Engine*>(&e) ? " (set OMP_NUM_THREADS or --threads to change)" : "";
#endif
  out.push_back("md: backend: " + e.description() + hint);
  out.push_back(printfString("md: N = %d, phi = %g, box L = %.6g, contact model %s, seed %llu",
                             cfg.system.N, cfg.system.phi, e.box(), cfg.contact.model.c_str(),
                             static_cast<unsigned long long>(cfg.system.seed)));
  if (cfg.integrator.adaptive) {
    out.push_back(printfString("md: dt = %.6g now, %s; to t_end = %g", e.dt(),
                               sim.dtReason().c_str(), cfg.run.t_end));
  } else {
    const double t_last = static_cast<double>(sim.lastStep()) * e.dt();
    std::string ends;
    if (t_last != cfg.run.t_end)  // time = step * dt: the run ends on the step nearest t_end
      ends = printfString(" (ends at t = %.6g, the whole step nearest t_end)", t_last);
    out.push_back(printfString("md: dt = %.6g (%s); %lld steps to t_end = %g%s", e.dt(),
                               sim.dtReason().c_str(), static_cast<long long>(sim.lastStep()),
                               cfg.run.t_end, ends.c_str()));
  }
  if (const CoulombSetup* cs = e.coulombSetup()) {
    const std::string mesh = cs->method == "pppm" ? "mesh " + std::to_string(cs->mesh) +
                                                        "^3, order " + std::to_string(cs->order)
                                                  : "k_max " + std::to_string(cs->k_max);
    out.push_back(printfString(
        "md: Coulomb K = %g, %s: alpha = %.6g, r_cut = %.6g, %s; estimated relative force error "
        "%.2g (for sum q^2 = %.4g)",
        cfg.coulomb.K, cs->method.c_str(), cs->alpha, cs->r_cut, mesh.c_str(), cs->estimated_error,
        cs->sum_q2_design));
    if (cs->r_fast > 0.0) {
      const std::string growing =
          cs->every_max > cs->every
              ? ", growing to at most " + std::to_string(cs->every_max) + " as the gas cools"
              : "";
      out.push_back(printfString(
          "md: multiple time stepping: slow Coulomb part every %d steps%s; pair force within "
          "r_fast = %g every step",
          cs->every, growing.c_str(), cs->r_fast));
    }
  }
  if (sim.resumed())
    out.push_back(printfString("md: restarting from step %lld of %s",
                               static_cast<long long>(e.step()), sim.folder().c_str()));
  return out;
}

std::vector<std::string> runSummaryLines(const Simulation& sim, const RunSummary& s) {
  const RunEngine& e = sim.engine();
  const Observables& o = s.observables;  // (the engine's observables() may be collective)
  std::vector<std::string> out;
  out.push_back(printfString(
      "md: %lld steps in %.4g s (%.3g particle-steps/s incl. output); neighbour list rebuilt %lld "
      "times (every %.3g steps)",
      static_cast<long long>(s.steps), s.loop_seconds,
      s.loop_seconds > 0 ? static_cast<double>(s.steps) * e.size() / s.loop_seconds : 0.0,
      static_cast<long long>(s.neighbor_builds),
      s.neighbor_builds > 0 ? static_cast<double>(s.steps) / s.neighbor_builds : 0.0));
  out.push_back(printfString(
      "md: %s at t = %g: T_g = %.6g, %lld collisions, %.3g contacts per particle, max overlap "
      "%.3g",
      s.stopped ? "stopped" : "done", o.time, o.temperature,
      static_cast<long long>(o.collisions), o.contacts_per_particle,
      o.max_overlap));
  if (const CoulombSetup* cs = e.coulombSetup(); cs && cs->r_fast > 0.0)
    out.push_back(printfString(
        "md: slow Coulomb part evaluated %lld times (every %.3g steps on average; interval now "
        "%d steps)",
        static_cast<long long>(s.slow_evaluations),
        s.slow_evaluations > 0 ? static_cast<double>(s.steps) / s.slow_evaluations : 0.0,
        e.slowInterval()));
  out.push_back(printfString("md: wrote %s (%zu frames), %s", sim.trajectoryPath().c_str(),
                             sim.framesWritten(), sim.checkpointPath().c_str()));
  return out;
}

std::vector<std::string> profileLines(const RunEngine& engine, std::int64_t steps,
                                      double loop_seconds) {
  std::vector<std::string> out;
  out.push_back(printfString("md: time by phase (--profile), %lld steps, loop %.4g s:",
                             static_cast<long long>(steps), loop_seconds));
  auto line = [&](const std::string& name, double s) {
    out.push_back(printfString("md:   %-22s %10.4g s  %5.1f %%  %8.3g us/step", name.c_str(), s,
                               loop_seconds > 0 ? 100.0 * s / loop_seconds : 0.0,
                               steps > 0 ? 1e6 * s / steps : 0.0));
  };
  double sum = 0.0;
  for (const auto& [name, s] : engine.phaseSeconds()) {
    sum += s;
    if (s > 0.0) line(name, s);
  }
  line("other (output, obs.)", loop_seconds - sum);
  return out;
}

namespace {
std::string duration(double s) {
  if (s < 120) return printfString("%.0f s", s);
  if (s < 7200) return printfString("%.0f min", s / 60);
  return printfString("%.1f h", s / 3600);
}
}  // namespace

ProgressReporter::ProgressReporter(const Simulation& sim)
    : m_line("md", true),
      m_t_end(sim.config().run.t_end),
      m_t_start(sim.engine().time()),
      m_first_step(sim.engine().step()),
      m_start(Clock::now()) {}

void ProgressReporter::report(const Simulation& sim) {
  if (!m_line.due()) return;
  const RunEngine& e = sim.engine();
  const double el = std::chrono::duration<double>(Clock::now() - m_start).count();
  const double rate = static_cast<double>(e.step() - m_first_step) / std::max(el, 1e-9);
  const double done = (e.time() - m_t_start) / std::max(m_t_end - m_t_start, 1e-300);
  const double eta = done > 0 ? el * (1 - done) / done : 0.0;
  m_line.show(printfString("t = %.4g / %.4g  T_g = %.4g  %.3g particle-steps/s  ETA %s", e.time(),
                           m_t_end, sim.lastObservables().temperature,
                           rate * static_cast<double>(e.size()), duration(eta).c_str()));
}

void ProgressReporter::finish(const Simulation&) { m_line.finish(); }

}  // namespace granagg::md
