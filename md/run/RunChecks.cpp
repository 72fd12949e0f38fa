#include "md/run/RunChecks.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "common/Strings.h"
#include "md/engine/Engine.h"

namespace granagg::md {

namespace {

// Bounds of what a run may ask for: beyond them a typo (t_end = 1e300, a frame every
// 1e-12) would overflow the step counter or hang in building the frame schedule.
constexpr double MAX_STEPS = 1e12;  // ~30 years at 1e3 steps/s
constexpr double MAX_FRAMES = 1e6;  // ~a petabyte at N = 50016

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
        " of memory (at least " + common::formatShort(per_particle) +
        " bytes per particle for the engine's " + what + "), more than this machine's " +
        gigabytes(machine) + ": lower system.N (to at most " +
        common::formatShort(std::floor(machine / per_particle)) + " here)");
}

}  // namespace

void checkSchedule(const MdConfig& c) {
  std::string why;
  const double dt = Engine::chooseTimeStep(c, &why);
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("integrator.dt: the time step is " + common::formatShort(dt) +
                                " (" + why +
                                "): it must be positive and finite; check contact.* or give "
                                "integrator.dt");
  const double steps = c.run.t_end / dt;
  if (!(steps <= MAX_STEPS))
    throw std::invalid_argument(
        "run.t_end = " + common::formatShort(c.run.t_end) + " at dt = " + common::formatShort(dt) +
        " is " + common::formatShort(steps) + " steps, more than 1e12: lower run.t_end");
  double frames = 0.0;
  if (c.output.frames_per_decade > 0) {
    const double t0 = std::max(0.01, dt);
    frames += c.output.frames_per_decade * std::max(0.0, std::log10(c.run.t_end / t0));
  }
  if (c.output.frame_interval > 0.0) frames += c.run.t_end / c.output.frame_interval;
  if (!(frames <= MAX_FRAMES))
    throw std::invalid_argument(
        "output.frames_per_decade = " + std::to_string(c.output.frames_per_decade) +
        " and output.frame_interval = " + common::formatShort(c.output.frame_interval) +
        " ask for " + common::formatShort(std::round(frames)) + " frames up to run.t_end = " +
        common::formatShort(c.run.t_end) + ", more than 1e6: space them further apart");
  checkMemory(c);
}

}  // namespace granagg::md
