#pragma once
/// \file SlowSchedule.h
/// The schedule of the slow Coulomb force in the impulse multiple-time-step integrator
/// (md/engine/Engine.h): when it was last evaluated, the interval in force and the one before, the
/// interval's bounds, and the next change of the time step. One typed value, saved whole into a
/// checkpoint and loaded from it, as jax-md makes an integrator's state explicit. The slow force
/// itself (per-particle device buffers) stays with the engine; so does the choice of the next
/// interval from the gas's speeds (it reads the velocities), which clamp() bounds.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "md/io/Checkpoint.h"

namespace granagg::md {

struct SlowSchedule {
  int every = 1;  ///< steps from the last evaluation to the next
  /// the interval's bounds in steps: between every_base and every_cap when it follows the gas
  /// (coulomb.every_max > every), equal when fixed
  int every_base = 1, every_cap = 1;
  /// every_base and every_cap at the "auto" step: what the Coulomb set-up is designed for and a
  /// checkpoint records as coulomb_every_max (an adaptive step rescales the bounds, not these)
  int design_base = 1, design_cap = 1;
  /// the interval that ended at the last evaluation, in steps of the current dt (not a whole
  /// number after a change of dt)
  double every_prev = 1.0;
  /// every_base and every_cap in time units at the "auto" step: an adaptive step keeps the
  /// interval's bounds in time (boundsFor)
  double base_time = 0.0, cap_time = 0.0;
  std::int64_t eval_step = -1;     ///< step of the last evaluation (-1: none yet)
  std::int64_t interval_end = -1;  ///< step of the next change of dt (-1: none announced)

  /// The schedule of a new run at step dt: the interval k (coulomb.every resolved), growing to
  /// at most `cap` steps (<= k: fixed).
  static SlowSchedule start(int k, int cap, double dt) {
    SlowSchedule s;
    s.every = s.every_base = s.every_cap = k;
    s.every_prev = k;
    if (k > 1) s.every_cap = std::max(k, cap);
    s.design_base = s.every_base;
    s.design_cap = s.every_cap;
    s.base_time = s.every_base * dt;
    s.cap_time = s.every_cap * dt;
    return s;
  }

  /// True when the interval may vary between every_base and every_cap.
  bool follows() const { return every_cap > every_base; }

  /// Weight of the slow force in the force of step `at` (Engine.h): at an evaluation step the
  /// mean of the interval that ends there and the one that starts (k when the interval is fixed:
  /// the impulse k dt F, half closing each interval and half opening the next; a fresh start has
  /// only the opening half); 0 between evaluations; 1 at every step when k = 1.
  double weight(std::int64_t at) const {
    if (at != eval_step) return 0.0;
    return 0.5 * (every_prev + static_cast<double>(every));
  }

  /// Velocity offset of the impulse integrator against the smooth trajectory at `step`, per unit
  /// slow force: (k/2 - j) dt at j = 1..k-1 steps after an evaluation; at the evaluation itself
  /// half the difference of the two intervals' halves (v(t) holds half the mean weight where
  /// the closing half of the interval that ended would hold half of that interval); 0 with k = 1.
  double velocityOffset(std::int64_t step, double dt) const {
    if ((every == 1 && every_prev == 1) || eval_step < 0) return 0.0;
    const std::int64_t j = step - eval_step;
    return j == 0 ? 0.25 * (every - every_prev) * dt
                  : (0.5 * every - static_cast<double>(j)) * dt;
  }

  /// The interval's bounds in steps of dt, from their lengths in time.
  void boundsFor(double dt) {
    if (every_cap <= 1) return;  // (k = 1 throughout, or plain Ewald)
    every_base = std::max(1, static_cast<int>(std::floor(base_time / dt + 1e-9)));
    every_cap = std::max(every_base, static_cast<int>(std::floor(cap_time / dt + 1e-9)));
  }

  /// `k` (a proposal from the gas, or every_base) within [every_base, every_cap], and never past
  /// the announced change of dt, from `step`.
  int clamp(double k, std::int64_t step) const {
    int out = static_cast<int>(std::min<double>(every_cap, std::max<double>(every_base, k)));
    if (interval_end > step)
      out = static_cast<int>(std::min<std::int64_t>(out, interval_end - step));
    return out;
  }

  /// Into a checkpoint's EngineState (names as Engine::engineState documents).
  void save(EngineState& e) const {
    e.ints["coulomb_eval_step"] = eval_step;
    e.ints["coulomb_every"] = every;  // the slow interval in force and the one before it
    e.ints["coulomb_every_prev"] = static_cast<std::int64_t>(every_prev);
    e.reals["coulomb_every_prev"] = every_prev;  // (not whole after a change of dt)
    // the split as resolved (Engine.cpp, withRecordedSplit): a restart keeps it
    e.ints["coulomb_every_max"] = design_cap;
  }

  /// The evaluation step and intervals of a checkpoint, checked against this run's bounds
  /// (std::invalid_argument); false if it has none (an older format: a fixed interval).
  bool load(const EngineState& e) {
    const auto at = e.ints.find("coulomb_eval_step");
    if (at != e.ints.end()) eval_step = at->second;
    const auto k = e.ints.find("coulomb_every"), kp = e.ints.find("coulomb_every_prev");
    if (k == e.ints.end() || kp == e.ints.end()) return false;
    if (k->second < 1 || k->second > every_cap || kp->second < 0)
      throw std::invalid_argument("checkpoint: slow Coulomb interval " +
                                  std::to_string(k->second) + " outside this run's 1.." +
                                  std::to_string(every_cap));
    every = static_cast<int>(k->second);
    const auto kp_real = e.reals.find("coulomb_every_prev");
    every_prev =
        kp_real != e.reals.end() ? kp_real->second : static_cast<double>(kp->second);
    return true;
  }
};

}  // namespace granagg::md
