#include "study/JobPool.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <map>
#include <stdexcept>
#include <string>

namespace granagg::study {

int runJobPool(std::size_t n, int slots, const JobPoolCallbacks& cb) {
  using clock = std::chrono::steady_clock;
  struct Running {
    std::size_t index;
    clock::time_point start;
  };
  std::deque<std::size_t> pending;
  for (std::size_t i = 0; i < n; ++i) pending.push_back(i);
  std::map<pid_t, Running> running;
  std::size_t finished = 0;
  while (!pending.empty() || !running.empty()) {
    while (!cb.stop_requested() && static_cast<int>(running.size()) < slots &&
           !pending.empty()) {
      const std::size_t i = pending.front();
      pending.pop_front();
      running[cb.start(i)] = {i, clock::now()};
    }
    if (cb.progress) cb.progress(finished, running.size());
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, WNOHANG);
    if (const int sig = cb.stop_requested()) {
      for (auto& [p, r] : running) cb.stop(r.index, p);
      for (auto& [p, r] : running) {
        int child = 0;
        while (::waitpid(p, &child, 0) < 0 && errno == EINTR) {
        }
        cb.stopped(r.index);
      }
      return sig;
    }
    if (pid == 0 || (pid < 0 && errno == EINTR)) {
      ::usleep(200000);
      continue;
    }
    if (pid < 0) throw std::runtime_error("waitpid failed: " + std::string(std::strerror(errno)));
    const auto it = running.find(pid);
    if (it == running.end()) continue;  // not one of ours
    const Running r = it->second;
    running.erase(it);
    const double wall = std::chrono::duration<double>(clock::now() - r.start).count();
    if (cb.ended(r.index, status, wall))
      pending.push_front(r.index);
    else
      ++finished;
  }
  return 0;
}

}  // namespace granagg::study
