#include "cli/CliContext.h"

#include <signal.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <system_error>

namespace granagg::cli {
namespace fs = std::filesystem;

namespace {
volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void onStopSignal(int sig) { g_stop_signal = sig; }
}  // namespace

void catchStopSignals() {
  struct sigaction sa {};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  // no SA_RESETHAND: a second signal (Slurm signals every process of a step, and pair forwards
  // the signal to its runs as well) must not kill a run while it writes its checkpoint
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
  // A file-size limit (ulimit -f, a batch system's) then fails the write with EFBIG, as a full
  // disk fails it with ENOSPC, instead of killing the run without a word: both end with the
  // error line, the last checkpoint and the trajectory's journal (docs/robustness.md).
  ::signal(SIGXFSZ, SIG_IGN);
}

const volatile std::sig_atomic_t* stopSignal() { return &g_stop_signal; }

std::vector<std::string> dataDirs() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("GRANAGG_DATA")) dirs.emplace_back(env);
  dirs.emplace_back(GRANAGG_DATA_DIR);
  return dirs;
}

std::string findPreset(const std::string& sub, const std::string& name, const std::string& what) {
  std::set<std::string> available;
  for (const auto& d : dataDirs()) {
    const fs::path p = fs::path(d) / sub / (name + ".toml");
    if (fs::is_regular_file(p)) return p.string();
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::path(d) / sub, ec))
      if (e.path().extension() == ".toml") available.insert(e.path().stem().string());
  }
  std::string list;
  for (const auto& a : available) list += (list.empty() ? "" : ", ") + a;
  throw std::invalid_argument(what + ": no preset named '" + name + "' in " + dataDirs().back() +
                              "/" + sub + " (available: " + list + ")");
}

const common::PaperValues& paperValues() {
  static const common::PaperValues values = [] {
    for (const auto& d : dataDirs()) {
      const fs::path p = fs::path(d) / "reference" / "paper.json";
      if (fs::is_regular_file(p)) return common::readPaperValues(p.string());
    }
    throw std::runtime_error("no reference/paper.json in " + dataDirs().back());
  }();
  return values;
}

}  // namespace granagg::cli
