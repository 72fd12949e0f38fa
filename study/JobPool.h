#pragma once
/// \file JobPool.h
/// Child processes, at most a number of slots at a time: the fork/wait loop of `granagg pair`'s
/// MD stage. Jobs start in order as slots free up; one that asks to run again goes to the front
/// of the queue; a stop request stops the running jobs and waits for them. What a job is, how it
/// starts and what its end means are the caller's (PairStudy::runMd).
#include <sys/types.h>

#include <cstddef>
#include <functional>

namespace granagg::study {

struct JobPoolCallbacks {
  /// Starts job `index` (0 .. n-1) and returns its process id.
  std::function<pid_t(std::size_t index)> start;
  /// Job `index` exited with wait status `status` after `wall_seconds`. Return true to run it
  /// again (it goes to the front of the queue).
  std::function<bool(std::size_t index, int status, double wall_seconds)> ended;
  /// The stop request: 0 for none, else the signal number.
  std::function<int()> stop_requested;
  /// Asks running job `index` (process `pid`) to stop; the pool then waits for it to exit.
  std::function<void(std::size_t index, pid_t pid)> stop;
  /// Job `index` exited after a stop request.
  std::function<void(std::size_t index)> stopped;
  /// Called about five times a second while jobs run: finished and running counts.
  std::function<void(std::size_t finished, std::size_t running)> progress;
};

/// Runs jobs 0 .. n-1, at most `slots` at a time. Returns 0 when every job has ended, or the
/// signal number of a stop request once the running jobs have stopped (no new job starts after
/// the request). Throws std::runtime_error when waitpid fails.
int runJobPool(std::size_t n, int slots, const JobPoolCallbacks& callbacks);

}  // namespace granagg::study
