#include "common/FolderLock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <ctime>
#include <stdexcept>
#include <system_error>

#include "common/Strings.h"

namespace granagg::common {
namespace fs = std::filesystem;

namespace {

std::string thisHost() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

std::string readAll(int fd) {
  std::string text;
  char buf[512];
  off_t at = 0;
  for (;;) {
    const ssize_t n = ::pread(fd, buf, sizeof buf, at);
    if (n <= 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    at += n;
  }
  return text;
}

/// The lock file's text: "key = value" lines (pid, host, command, since).
std::optional<LockHolder> parseHolder(const std::string& text) {
  LockHolder h;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    const std::size_t eq = line.find(" = ");
    if (eq == std::string::npos) continue;
    const std::string key = line.substr(0, eq), value = line.substr(eq + 3);
    if (key == "pid")
      h.pid = std::strtol(value.c_str(), nullptr, 10);
    else if (key == "host")
      h.host = value;
    else if (key == "command")
      h.command = value;
    else if (key == "since")
      h.since = value;
  }
  if (h.pid <= 0) return std::nullopt;  // empty, or not written to the end: names nobody
  return h;
}

std::string holderText(const std::string& command_line) {
  return "pid = " + std::to_string(static_cast<long>(::getpid())) + "\nhost = " + thisHost() +
         "\ncommand = " + command_line + "\nsince = " + utcTimestamp() + "\n";
}

bool pidRuns(long pid) { return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM; }

std::invalid_argument inUse(const fs::path& folder, const std::string& option,
                            const std::optional<LockHolder>& h) {
  const std::string who = h ? h->describe() : "another process (its lock file names nobody)";
  const std::string stop = h ? " or stop it (kill -TERM " + std::to_string(h->pid) + ")" : "";
  return std::invalid_argument(option + " '" + folder.string() + "' is in use by " + who +
                               ": wait for it to finish" + stop +
                               ", or choose another " + option);
}

std::invalid_argument stale(const fs::path& folder, const std::string& option,
                            const LockHolder& h, const std::string& clear_hint) {
  const bool here = h.host == thisHost();
  const std::string why =
      here ? (pidRuns(h.pid) ? "that process no longer holds it (its pid was reused)"
                             : "that process no longer runs")
           : "it cannot be checked from host " + thisHost();
  return std::invalid_argument(option + " '" + folder.string() + "' holds a stale lock (" +
                               FOLDER_LOCK_FILE + ") of " + h.describe() + ": " + why +
                               "; it ended without releasing the folder, which may hold a "
                               "partial output. " +
                               (clear_hint.empty() ? std::string("Pass --force to clear the lock")
                                                   : clear_hint));
}

/// The holder named by the lock file of `folder` and whether a process holds its flock now.
struct LockProbe {
  bool exists = false;
  bool live = false;
  std::optional<LockHolder> holder;
};

LockProbe probe(const fs::path& folder) {
  LockProbe p;
  const fs::path path = folder / FOLDER_LOCK_FILE;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return p;
  p.exists = true;
  if (::flock(fd, LOCK_SH | LOCK_NB) != 0)
    p.live = errno == EWOULDBLOCK;
  else
    ::flock(fd, LOCK_UN);
  p.holder = parseHolder(readAll(fd));
  ::close(fd);
  return p;
}

}  // namespace

std::string LockHolder::describe() const {
  std::string s = "pid " + std::to_string(pid) + " on host " + host;
  std::string detail = command;
  if (!since.empty()) detail += (detail.empty() ? "" : ", ") + std::string("since ") + since;
  if (!detail.empty()) s += " (" + detail + ")";
  return s;
}

bool LockHolder::deadHere() const { return host == thisHost() && !pidRuns(pid); }

FolderLock FolderLock::acquire(const fs::path& folder, const std::string& command_line,
                               bool clear_stale, const std::string& option,
                               const std::string& clear_hint, bool take_over_dead) {
  std::error_code ec;
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec))
    throw std::invalid_argument(option + " '" + folder.string() +
                                "' is a file, not a folder; give a folder");
  FolderLock lock;
  lock.m_folder = folder;
  lock.m_created = !fs::exists(folder, ec);
  fs::create_directories(folder, ec);
  if (ec)
    throw std::invalid_argument(option + " '" + folder.string() +
                                "': cannot create the folder (" + ec.message() + ")");
  const fs::path path = folder / FOLDER_LOCK_FILE;
  for (;;) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
      throw std::invalid_argument(option + " '" + folder.string() + "': cannot write in it (" +
                                  std::strerror(errno) + ")");
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      const std::optional<LockHolder> h = parseHolder(readAll(fd));
      ::close(fd);
      if (err == EWOULDBLOCK) throw inUse(folder, option, h);
      throw std::runtime_error(option + " '" + folder.string() + "': cannot lock " +
                               path.string() + " (" + std::strerror(err) + ")");
    }
    // The path must still name the file locked here: a holder that released its lock removed it.
    struct stat locked {}, named {};
    if (::fstat(fd, &locked) != 0 || ::stat(path.c_str(), &named) != 0 ||
        locked.st_ino != named.st_ino || locked.st_dev != named.st_dev) {
      ::close(fd);
      continue;
    }
    if (const std::optional<LockHolder> h = parseHolder(readAll(fd))) {
      // (the flock is ours: the process the file names no longer holds it)
      if (!clear_stale && !(take_over_dead && h->host == thisHost())) {
        ::close(fd);  // the stale file stays as it was found
        throw stale(folder, option, *h, clear_hint);
      }
      lock.m_cleared = h->describe();
    }
    const std::string text = holderText(command_line);
    if (::ftruncate(fd, 0) != 0 ||
        ::pwrite(fd, text.data(), text.size(), 0) != static_cast<ssize_t>(text.size())) {
      const int err = errno;
      ::close(fd);
      throw std::runtime_error("cannot write " + path.string() + " (" + std::strerror(err) + ")");
    }
    lock.m_fd = fd;
    return lock;
  }
}

std::optional<LockHolder> FolderLock::liveHolder(const fs::path& folder) {
  const LockProbe p = probe(folder);
  if (!p.live) return std::nullopt;
  return p.holder ? p.holder : LockHolder{};
}

std::optional<LockHolder> FolderLock::staleHolder(const fs::path& folder) {
  const LockProbe p = probe(folder);
  if (p.live) return std::nullopt;
  return p.holder;
}

void FolderLock::checkAvailable(const fs::path& folder, bool clear_stale,
                                const std::string& option, const std::string& clear_hint,
                                bool take_over_dead) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return;
  const LockProbe p = probe(folder);
  if (p.live) throw inUse(folder, option, p.holder);
  if (p.holder && !clear_stale && !(take_over_dead && p.holder->host == thisHost()))
    throw stale(folder, option, *p.holder, clear_hint);
}

void FolderLock::checkTreeAvailable(const fs::path& root, const std::string& option) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return;
  for (auto it = fs::recursive_directory_iterator(root, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (it->path().filename() != FOLDER_LOCK_FILE) continue;
    const fs::path dir = it->path().parent_path();
    if (dir == root) continue;  // the caller's own folder
    const LockProbe p = probe(dir);
    if (p.live) throw inUse(dir, option + " (a folder inside it)", p.holder);
  }
}

FolderLock::FolderLock(FolderLock&& other) noexcept
    : m_folder(std::move(other.m_folder)),
      m_fd(other.m_fd),
      m_created(other.m_created),
      m_cleared(std::move(other.m_cleared)) {
  other.m_fd = -1;
}

FolderLock& FolderLock::operator=(FolderLock&& other) noexcept {
  if (this != &other) {
    release();
    m_folder = std::move(other.m_folder);
    m_fd = other.m_fd;
    m_created = other.m_created;
    m_cleared = std::move(other.m_cleared);
    other.m_fd = -1;
  }
  return *this;
}

FolderLock::~FolderLock() { release(); }

void FolderLock::release() {
  if (m_fd < 0) return;
  // Removed while still locked: whoever opens the name afterwards gets a new file.
  std::error_code ec;
  fs::remove(m_folder / FOLDER_LOCK_FILE, ec);
  ::close(m_fd);
  m_fd = -1;
}

}  // namespace granagg::common
