#pragma once
/// \file FolderLock.h
/// The lock every output folder of granagg carries while a command writes it, so that a second
/// command never deletes, truncates or creates a file under a running one.
///
/// Design. The lock is an advisory `flock` (LOCK_EX) on `FOLDER/.granagg.lock`, a small text
/// file that names its holder (pid, host, command, start time). The kernel releases a flock when
/// its process dies, however it dies, so a live lock always belongs to a live process; the text
/// is for the message that names the holder, and for the one case flock cannot settle alone: a
/// file left by a process that was killed (SIGKILL, a node lost) names a pid that no longer holds
/// it. Such a stale lock is reported and cleared only when the user says so (--force): the folder
/// may hold a run that ended in the middle of a write. The exception is a caller that checks the
/// folder itself before it writes (`granagg md --restart`: the checkpoint it continues is
/// written atomically, and the trajectory is checked against it): with `take_over_dead` it takes
/// over a stale lock of this host, whose owner is known to be gone (its flock is free, and the
/// kernel frees a flock only when its process ends), so that a job resubmitted after a SIGKILL (a
/// time limit, an out-of-memory kill) continues without a person. A lock of another host may
/// belong to a process that still runs there, and still needs --force.
///
/// The file is removed when the lock is released. A process that opened the file just before
/// and locks it just after would then hold a lock on a removed file, so acquire() checks, after
/// locking, that the path still names the file it locked, and starts over when it does not.
///
/// Folders on a network file system shared by several hosts: Linux maps flock onto the NFS
/// byte-range locks, which the server arbitrates; a lock file that names another host, on a
/// flock that succeeds, is treated as stale of that host (it cannot be checked from here).
#include <filesystem>
#include <optional>
#include <string>

namespace granagg::common {

/// Who holds (or held) a folder's lock, as its lock file says.
struct LockHolder {
  long pid = 0;
  std::string host;
  std::string command;
  std::string since;  ///< UTC, ISO 8601
  /// "pid 123 on host h (granagg md ..., since 2026-...)"
  std::string describe() const;
  /// True if it names this host and a pid that no longer runs here.
  bool deadHere() const;
};

/// The name of the lock file inside a locked folder.
inline constexpr const char* FOLDER_LOCK_FILE = ".granagg.lock";

class FolderLock {
 public:
  /// Locks `folder` for the command `command_line`, creating the folder (and its parents) when
  /// it does not exist. `option` names the option that gave the folder ("--out") in messages.
  /// Throws std::invalid_argument (exit 2), before anything in the folder is touched, when a live
  /// process holds it (naming the holder), or when a stale lock is found and `clear_stale` is
  /// false (naming it and --force). With `clear_stale` a stale lock is taken over;
  /// clearedStale() then describes it for the log.
  /// `clear_hint` replaces "Pass --force to clear the lock" where --force means more.
  /// `take_over_dead`: also take over, without `clear_stale`, a stale lock of this host (above).
  static FolderLock acquire(const std::filesystem::path& folder, const std::string& command_line,
                            bool clear_stale, const std::string& option = "--out",
                            const std::string& clear_hint = "", bool take_over_dead = false);

  /// The live holder of `folder`'s lock, if any (the folder and its lock file are not created).
  static std::optional<LockHolder> liveHolder(const std::filesystem::path& folder);

  /// The holder a stale lock file of `folder` names (no live flock), if any.
  static std::optional<LockHolder> staleHolder(const std::filesystem::path& folder);

  /// Throws what acquire() would throw for `folder`, without taking the lock or creating
  /// anything: for the checks a command makes before its expensive set-up.
  static void checkAvailable(const std::filesystem::path& folder, bool clear_stale,
                             const std::string& option = "--out",
                             const std::string& clear_hint = "", bool take_over_dead = false);

  /// Throws std::invalid_argument if any folder below `root` (or `root` itself) is held by a
  /// live process: for a command about to delete a tree of outputs (`pair --force`).
  static void checkTreeAvailable(const std::filesystem::path& root,
                                 const std::string& option = "--out");

  FolderLock(FolderLock&& other) noexcept;
  FolderLock& operator=(FolderLock&& other) noexcept;
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  ~FolderLock();

  /// Releases the lock now (removes the lock file); the destructor does it otherwise.
  void release();

  const std::filesystem::path& folder() const { return m_folder; }
  /// True if acquire() created the folder (a command that fails may remove it again).
  bool createdFolder() const { return m_created; }
  /// The stale lock that acquire() took over ("" if none), for the command's log.
  const std::string& clearedStale() const { return m_cleared; }

 private:
  FolderLock() = default;
  std::filesystem::path m_folder;
  int m_fd = -1;
  bool m_created = false;
  std::string m_cleared;
};

}  // namespace granagg::common
