/// \file Process.cpp
/// Child processes, command lines and whole-file writes (Process.h).
#include "study/Process.h"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace granagg::study {
namespace fs = std::filesystem;

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const fs::path& p, const std::string& text) {
  const fs::path tmp = p.string() + ".tmp";
  if (p.has_parent_path()) fs::create_directories(p.parent_path());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, p);  // atomic: a marker is either complete or absent
}

void appendText(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::app);
  out << text;
}

std::string fnv1a(const std::string& s, std::uint64_t basis) {
  std::uint64_t h = basis;
  for (unsigned char ch : s) {
    h ^= ch;
    h *= 1099511628211ULL;  // the 64-bit FNV prime
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

int availableCores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

std::string selfExe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("granagg") : p.string();
}

bool findProgram(const std::string& program) {
  if (program.empty()) return false;
  if (program.find('/') != std::string::npos) return ::access(program.c_str(), X_OK) == 0;
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const fs::path p = fs::path(dir.empty() ? "." : dir) / program;
    if (fs::is_regular_file(p) && ::access(p.c_str(), X_OK) == 0) return true;
  }
  return false;
}

std::vector<pid_t> descendantsNamed(pid_t root, const std::string& name) {
  // every process's parent and name from /proc/PID/stat: "pid (comm) state ppid ..."; comm may
  // hold blanks and parentheses, so it ends at the last ')'
  std::map<pid_t, std::vector<pid_t>> children;
  std::map<pid_t, std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", ec)) {
    const std::string id = entry.path().filename().string();
    if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string stat = readText(entry.path() / "stat");
    const std::size_t open = stat.find('('), close = stat.rfind(')');
    if (open == std::string::npos || close == std::string::npos || close < open) continue;
    std::istringstream rest(stat.substr(close + 1));
    std::string state;
    long ppid = 0;
    if (!(rest >> state >> ppid)) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(id));
    children[static_cast<pid_t>(ppid)].push_back(pid);
    names[pid] = stat.substr(open + 1, close - open - 1);
  }
  std::vector<pid_t> found, todo{root};
  while (!todo.empty()) {
    const pid_t p = todo.back();
    todo.pop_back();
    for (pid_t c : children[p]) {
      if (names[c] == name.substr(0, 15))
        found.push_back(c);  // not below it: its forks carry its name until they exec
      else
        todo.push_back(c);
    }
  }
  std::sort(found.begin(), found.end());
  return found;
}

std::string shellQuote(const std::string& a) {
  if (!a.empty() &&
      a.find_first_not_of(
          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=/.,:@%") ==
          std::string::npos)
    return a;
  std::string o = "'";
  for (char ch : a) o += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return o + "'";
}

std::string joinCommand(const std::vector<std::string>& argv) {
  std::string s;
  for (const auto& a : argv) s += (s.empty() ? "" : " ") + shellQuote(a);
  return s;
}

/// fork + exec with stdout and stderr into `log` (appended); the child dies with its parent.
pid_t spawn(const std::vector<std::string>& argv, const fs::path& log) {
  std::vector<char*> a;
  for (const auto& s : argv) a.push_back(const_cast<char*>(s.c_str()));
  a.push_back(nullptr);
  const std::string logpath = log.string();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed: " + std::string(std::strerror(errno)));
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    ::setpgid(0, 0);
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    const int fd = ::open(logpath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    const int nul = ::open("/dev/null", O_RDONLY);
    if (nul >= 0) ::dup2(nul, 0);
    ::execvp(a[0], a.data());
    std::fprintf(stderr, "cannot run %s: %s\n", a[0], std::strerror(errno));
    ::_exit(127);
  }
  return pid;
}

std::string lastLine(const fs::path& log) {
  const std::string t = readText(log);
  std::size_t end = t.find_last_not_of("\n\r ");
  if (end == std::string::npos) return "";
  std::size_t begin = t.find_last_of('\n', end);
  std::string l = t.substr(begin == std::string::npos ? 0 : begin + 1,
                           end - (begin == std::string::npos ? 0 : begin + 1) + 1);
  if (const auto cr = l.find_last_of('\r'); cr != std::string::npos) l = l.substr(cr + 1);
  return l;
}

std::string lastLine(const fs::path& log, const std::string& prefix) {
  std::istringstream in(readText(log));
  std::string found;
  for (std::string l; std::getline(in, l);) {
    if (const auto cr = l.find_last_of('\r'); cr != std::string::npos) l = l.substr(cr + 1);
    if (l.rfind(prefix, 0) == 0) found = l;
  }
  return found.empty() ? lastLine(log) : found;
}

}  // namespace granagg::study
