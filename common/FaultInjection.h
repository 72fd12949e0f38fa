#pragma once
/// \file FaultInjection.h
/// The test hook of the crash and full-disk trials (tests/faults, docs/robustness.md), in the
/// way SQLite builds its crash tests into the library: a named point in the I/O code that a test
/// can turn into a SIGKILL or a failed write, so that a failure at an exact moment can be forced
/// and replayed. Off unless the environment variable GRANAGG_FAULT is set:
///
///     GRANAGG_FAULT=<action>:<site>:<K>
///       action  kill    raise SIGKILL at the K-th passage through faultPoint(site)
///               enospc  the K-th and every later passage report a full disk (faultPoint
///                       returns true; the caller fails its write with ENOSPC)
///               count   nothing fails; at exit, stderr gets "granagg: fault point <site>
///                       passed <n> times" (K is ignored), which is how a trial picks K
///       site    h5write     every write call of the journaled HDF5 driver (common/H5Journal.h)
///               checkpoint  half-way through writing a checkpoint's temporary file
///       K       1, 2, ...   counted from the start of the process
///
/// A malformed GRANAGG_FAULT is reported once on stderr and ignored: a hook must never change a
/// run that was not asked to fail.
namespace granagg::common {

/// Passes the fault point `site`; kills the process or returns true (a simulated full disk)
/// when GRANAGG_FAULT names this site and passage. Thread-safe; costs one atomic increment.
bool faultPoint(const char* site);

}  // namespace granagg::common
