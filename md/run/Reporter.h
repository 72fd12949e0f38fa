#pragma once
/// \file Reporter.h
/// What looks at a run between chunks of steps (OpenMM's reporters are the model): the run's own
/// outputs (md/run/OutputReporters.h: trajectory, checkpoints), the progress line
/// (md/run/RunLog.h), a collision log (md/lammps/CollisionLog.h), a user's callback.
#include <cstdint>
#include <limits>

namespace granagg::md {

class Simulation;

/// Called by md::Simulation::run() after each chunk of steps, in order: the trajectory, the
/// reporters added with Simulation::addReporter, then the checkpoints, so that a checkpoint
/// follows every reporter's view of its step (an in-situ analysis has seen the frame a checkpoint
/// is written at, and saves its own state in beforeCheckpoint). A reporter never changes
/// the physics of the run; under MPI every rank holds the same reporters and calls them in the
/// same order, so that their collective engine calls match.
class Reporter {
 public:
  virtual ~Reporter() = default;
  /// The step at which this reporter next wants to be called; the run then stops there. The
  /// default has no wish: report() is still called after every chunk (at most
  /// output.observable_interval steps).
  virtual std::int64_t nextStep(const Simulation&) const {
    return std::numeric_limits<std::int64_t>::max();
  }
  /// Whether report() at the engine's present step reads Simulation::lastObservables(). The run
  /// computes the observables at a chunk's end (a collective call that may evaluate the Coulomb
  /// energy: about ten steps' worth in a charged gas) only when some reporter says yes, so that a
  /// reporter which asks for short chunks (a Python callback's signal check) costs no
  /// observables. Decide from the step alone, so that every rank decides alike.
  virtual bool needsObservables(const Simulation&) const { return true; }
  /// Called after each chunk of steps, with the engine at the chunk's end.
  virtual void report(const Simulation& sim) = 0;
  /// Called once when run() ends (normally or not), after the final checkpoint.
  virtual void finish(const Simulation&) {}
  /// Called just before every checkpoint is written, with its step: a reporter that carries state
  /// across a restart saves it here (a kill between the two leaves the previous checkpoint, so
  /// keep the previous state as well). Under MPI, on every rank.
  virtual void beforeCheckpoint(const Simulation&, std::int64_t /*step*/) {}
};

}  // namespace granagg::md
