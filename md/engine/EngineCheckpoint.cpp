/// \file EngineCheckpoint.cpp
/// md::Engine and its checkpoint (md/io/Checkpoint.h): what the engine records beyond the state
/// (the time-step origin, the slow Coulomb force and schedule, the resolved split) and the
/// restart that continues a run from it to the bit. The per-step core is in Engine.cpp.
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/Csv.h"
#include "md/engine/Engine.h"
#include "md/engine/EngineImpl.h"

namespace granagg::md {

using engine_detail::toHostById;

namespace {
// What "auto" means for a checkpoint that does not record its every_max (an older checkpoint
// format; docs/coulomb.md): the cap that wrote it, so that it continues as it ran.
constexpr int SLOW_INTERVAL_GROWTH_BEFORE_RECORDED = 4;
// coulomb.r_fast = "auto" is R_FAST_AUTO (md/coulomb/CoulombDesign.h). What "auto" means for a
// checkpoint that does not record its split (an older format): the split that wrote it.
constexpr double R_FAST_AUTO_BEFORE_RECORDED = 3.5;

/// The run's configuration with the multiple-time-step split that wrote `ck`: its "auto"
/// r_fast and every_max are resolved as recorded in the checkpoint (older ones: as "auto" was
/// resolved then), so a restart continues with the split it was written with even if a later
/// granagg resolves "auto" differently.
MdConfig withRecordedSplit(MdConfig c, const Checkpoint& ck) {
  if (!(c.coulomb.K > 0.0)) return c;
  const auto& reals = ck.engine.reals;
  const auto& ints = ck.engine.ints;
  if (!(c.coulomb.r_fast > 0.0)) {
    const auto r = reals.find("coulomb_r_fast");
    c.coulomb.r_fast = r != reals.end() ? r->second : R_FAST_AUTO_BEFORE_RECORDED;
  }
  if (c.coulomb.every_max == 0) {
    const auto m = ints.find("coulomb_every_max");
    c.coulomb.every_max = m != ints.end() ? static_cast<int>(m->second)
                                          : SLOW_INTERVAL_GROWTH_BEFORE_RECORDED *
                                                Engine::coulombEvery(c, Engine::chooseTimeStep(c));
  }
  return c;
}
}  // namespace

Engine::Engine(const MdConfig& config, const Checkpoint& ck)
    : Engine(withRecordedSplit(config, ck), ck.state, /*allow_contacts=*/true) {
  const EngineState& e = ck.engine;
  Impl& d = *m_impl;
  // The Coulomb parameters first, designed for the "auto" step's slow interval as in the run that
  // wrote it: restore() sizes the multiple-time-step state for them.
  if (const auto design = e.reals.find("coulomb_sum_q2_design"); design != e.reals.end())
    useCoulombDesign(design->second);
  if (config.integrator.adaptive) {
    // the step in force when it was written, and where it took effect (changeTimeStep); a
    // checkpoint of a fixed step (no change recorded: t = step dt) continues adaptively from it
    if (!(ck.dt > 0.0 && std::isfinite(ck.dt)))
      throw std::invalid_argument(
          "integrator.dt = \"adaptive\": the checkpoint lacks the time step in force (dt)");
    const auto t0 = e.reals.find("time_origin");
    const auto s0 = e.ints.find("step_origin");
    d.dt = ck.dt;
    d.time_origin = t0 != e.reals.end() ? t0->second : 0.0;
    d.step_origin = s0 != e.ints.end() ? s0->second : 0;
    d.slowBoundsForStep();
  } else if (ck.dt > 0.0 && ck.dt != d.dt) {
    // a fixed step: the configuration must give the step the checkpoint was written at, or a
    // build whose automatic step differs would continue the run silently on another
    throw std::invalid_argument(
        "integrator.dt: the checkpoint was written at dt = " + common::formatReal(ck.dt) +
        ", and its configuration now gives " + common::formatReal(d.dt) +
        "; continue it with the granagg that wrote it");
  }
  const auto collisions = e.ints.find("collisions");
  restore(ck.state, ck.forces, collisions == e.ints.end() ? 0 : collisions->second, e);
}

void Engine::saveCheckpoint(const std::filesystem::path& folder, const RunFields& run_fields) {
  Checkpoint ck = checkpoint();
  ck.run = run_fields;
  writeCheckpoint(checkpointPath(folder).string(), ck);
}

Checkpoint Engine::checkpoint() const {
  Checkpoint ck;
  ck.state = frame(StateKind::Integrator);
  ck.forces = forces(StateKind::Integrator);
  ck.dt = dt();
  ck.engine = engineState();
  ck.engine.ints["collisions"] = m_impl->collisions;
  if (const CoulombSetup* cs = coulombSetup())
    ck.engine.reals["coulomb_sum_q2_design"] = cs->sum_q2_design;
  return ck;
}

EngineState Engine::engineState() const {
  const Impl& d = *m_impl;
  EngineState e;
  if (d.cfg.integrator.adaptive) {
    e.reals["time_origin"] = d.time_origin;
    e.ints["step_origin"] = d.step_origin;
    e.ints["fresh_start"] = d.fresh_start ? 1 : 0;  // (a checkpoint before the first step)
  }
  if (!d.coulomb) return e;
  e.arrays["coulomb_fx"] = toHostById(d.slow_coulomb->force(0), d.p.id);
  e.arrays["coulomb_fy"] = toHostById(d.slow_coulomb->force(1), d.p.id);
  e.arrays["coulomb_fz"] = toHostById(d.slow_coulomb->force(2), d.p.id);
  d.slow.save(e);
  e.reals["coulomb_energy_ext"] = d.slow_coulomb->energy();
  // the split as resolved (withRecordedSplit): a restart keeps it whatever "auto" means then
  e.reals["coulomb_r_fast"] = d.slow_coulomb->setup().r_fast;
  return e;
}

void Engine::restore(const Frame& s, const Forces& forces, std::int64_t collisions,
                     const EngineState& extra) {
  Impl& d = *m_impl;
  const std::size_t N = d.p.size();
  if (s.size() != N || forces.x.size() != N || forces.y.size() != N || forces.z.size() != N ||
      s.charge.size() != N || s.ix.size() != N)
    throw std::invalid_argument("checkpoint has " + std::to_string(s.size()) +
                                " particles, the run " + std::to_string(N));
  d.upload(s);  // storage in id order again
  packVec3(forces.x, forces.y, forces.z, d.p.force);
  d.step = s.step;
  d.time = d.time_origin + static_cast<double>(s.step - d.step_origin) * d.dt;
  d.collisions = collisions;
  d.close_pending = false;
  // v(t) holds the closing half of the last step's impulse, unless no step was taken yet
  const auto fresh = extra.ints.find("fresh_start");
  d.fresh_start = fresh != extra.ints.end() && fresh->second != 0;
  if (d.coulomb) {
    // the Coulomb force of the last evaluation: the impulse integrator uses it until the next one
    const auto fx = extra.arrays.find("coulomb_fx"), fy = extra.arrays.find("coulomb_fy"),
               fz = extra.arrays.find("coulomb_fz");
    const auto at = extra.ints.find("coulomb_eval_step");
    const auto en = extra.reals.find("coulomb_energy_ext");
    const bool have = fx != extra.arrays.end() && fy != extra.arrays.end() &&
                      fz != extra.arrays.end() && at != extra.ints.end() && en != extra.reals.end();
    if (have) {
      for (const auto* a : {&fx->second, &fy->second, &fz->second})
        if (a->size() != N)
          throw std::invalid_argument("checkpoint: Coulomb force arrays have the wrong length");
      d.slow_coulomb->restore(fx->second, fy->second, fz->second, en->second);
      d.slow.load(extra);  // (older checkpoints have no intervals: fixed, as configured)
    } else if (d.slow.every == 1) {
      d.slow.eval_step = -1;  // evaluated afresh at the next step, as every step
    } else {
      throw std::invalid_argument(
          "checkpoint lacks the Coulomb forces of the multiple-time-step integrator "
          "(coulomb.every > 1): it was written by an older granagg; restart with coulomb.every = "
          "1");
    }
  }
  d.rebuildList(true);  // storage in cell order from the first step on, as after any build
}

}  // namespace granagg::md
