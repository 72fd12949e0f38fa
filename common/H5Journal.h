#pragma once
/// \file H5Journal.h
/// Crash-safe writing of an HDF5 file that a killed process can leave at any moment.
///
/// HDF5 writes a frame as new raw data at the end of the file plus updates of metadata in place
/// (chunk index, object headers, superblock), in an order that its metadata cache chooses. A
/// process killed half-way through those writes can leave pointers to blocks that were never
/// written: HDF5 then cannot open the file at all (tests/faults/test_h5_journal.cpp shows it,
/// killing a writer at every write of one frame). HDF5 has no journal of its own; its SWMR mode
/// orders the flushes instead but forbids creating objects while writing.
///
/// This driver makes every commit atomic, as SQLite's rollback journal does: it is HDF5's POSIX
/// driver ("sec2": pread/pwrite on one descriptor) plus an undo journal `<file>.journal`.
/// - commit() marks the file's state (right after H5Fflush, when the file is complete) as the
///   one to come back to, and empties the journal;
/// - before a write overwrites bytes that the last commit holds, their old content is appended to
///   the journal (a header with the committed size, then entries {address, length, bytes,
///   checksum}); writes past the committed size need no journal, a rollback truncates them;
/// - recover() undoes an unfinished transaction: it writes the saved bytes back, last first,
///   truncates the file to its committed size, syncs, and removes the journal.
/// Every complete entry is in the journal before the write it protects is issued, so whatever
/// moment a kill picks, recover() returns the file to its last commit. The cost is a copy of the
/// overwritten metadata: a few kB per frame, against frames of N x 24 bytes per array.
///
/// Scope: process death (SIGKILL, an out-of-memory kill, a batch system's time limit) and failed
/// writes (a full disk). The journal is not fsync'ed before each overwrite, so after a power
/// cut the operating system may have written the file's pages without the journal's.
///
/// The files are plain HDF5: the driver stores nothing in them, and readers open them with the
/// default driver. A writer holds an exclusive flock(2) on the file while it is open, which is
/// how recover() and the readers tell a live writer from a dead one.
#include <cstdint>
#include <string>

namespace granagg::common::h5journal {

/// `<path>.journal`.
std::string journalPathFor(const std::string& path);

/// A new file-access property list (an hid_t; close it with H5Pclose) that selects the journaled
/// driver, for H5Fcreate and H5Fopen with H5F_ACC_RDWR. Opening a file whose journal holds an
/// unfinished transaction fails (call recover() first); creating one (H5F_ACC_TRUNC) discards it.
std::int64_t fileAccess();

/// Makes the current content of `file` (an open hid_t of a file opened through fileAccess()) the
/// state a rollback returns to. Call it right after H5Fflush succeeded. Throws
/// std::runtime_error if the journal cannot be emptied, std::invalid_argument if `file` does not
/// use this driver.
void commit(std::int64_t file);

/// "" while every write to `file` (an open hid_t through fileAccess()) succeeded; after a failed
/// write, its message ("writing 'X' failed: the disk is full (...)"). A failed write freezes the
/// file and later writes are dropped, and HDF5 does not report every failure to its caller (a
/// dataset closed by a destructor flushes without a return value anyone reads): a writer checks
/// this before it calls its file complete.
std::string writeFailure(std::int64_t file);

/// Flushes `file` and throws std::runtime_error(writeFailure(file)) if any write failed: what a
/// writer calls before it closes a file it will call complete. The file still closes cleanly
/// afterwards (it is frozen at its last commit).
void requireWritten(std::int64_t file);

/// True when `<path>.journal` holds an unfinished transaction (a header and at least one complete
/// entry, or a file longer than its committed size): `path` may be torn until recover() runs.
bool pending(const std::string& path);

/// What recover() did.
struct Recovery {
  bool repaired = false;             ///< an unfinished transaction was rolled back
  std::size_t entries = 0;           ///< journal entries written back
  std::uint64_t bytes_restored = 0;  ///< bytes written back in place
  std::uint64_t size_before = 0;     ///< file size found
  std::uint64_t size_after = 0;      ///< file size after the rollback (the committed size)
  /// One line for the command's log, e.g. "rolled back the unfinished write of 'traj.h5' that an
  /// interrupted run left (3 blocks, 1.2 kB restored; 7.9 kB cut off)"; "" if nothing was done.
  std::string summary(const std::string& path) const;
};

/// Returns `path` to its last commit if its journal holds an unfinished transaction, and removes
/// a journal with nothing to undo. Throws std::runtime_error if a live process still holds the
/// file open for writing (its flock), or if the file cannot be opened for writing.
Recovery recover(const std::string& path);

}  // namespace granagg::common::h5journal
