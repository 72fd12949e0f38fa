/// The corpus replay driver: runs a fuzz harness's LLVMFuzzerTestOneInput over files and folders
/// of inputs without libFuzzer (the role of LLVM's StandaloneFuzzTargetMain and SQLite's
/// fuzzcheck), so that the README test command replays every committed input, under the sanitizer
/// build too, and a crash once fixed stays fixed.
///
///   usage: fuzz_replay_NAME PATH...   (a folder: every regular file in it, in name order)
///
/// An input that runs longer than REPLAY_TIMEOUT_S is reported as a hang (libFuzzer's own limit
/// is 1 s; the sanitizer build is several times slower).
#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

constexpr unsigned REPLAY_TIMEOUT_S = 20;
const char* g_current = "";

void onAlarm(int) {
  const char msg[] = "fuzz replay: HANG (over 20 s): ";
  (void)!::write(2, msg, sizeof msg - 1);
  (void)!::write(2, g_current, std::char_traits<char>::length(g_current));
  (void)!::write(2, "\n", 1);
  std::_Exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> inputs;
  for (int a = 1; a < argc; ++a) {
    const fs::path p(argv[a]);
    if (fs::is_directory(p)) {
      std::vector<fs::path> in_dir;
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file()) in_dir.push_back(e.path());
      std::sort(in_dir.begin(), in_dir.end());
      inputs.insert(inputs.end(), in_dir.begin(), in_dir.end());
    } else if (fs::is_regular_file(p)) {
      inputs.push_back(p);
    } else {
      std::fprintf(stderr, "fuzz replay: '%s' is neither a file nor a folder\n", argv[a]);
      return 2;
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "fuzz replay: no inputs (usage: %s PATH...)\n", argv[0]);
    return 2;
  }
  std::signal(SIGALRM, onAlarm);
  for (const auto& p : inputs) {
    std::ifstream in(p, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
    const std::string name = p.string();
    g_current = name.c_str();
    std::fprintf(stderr, "fuzz replay: %s (%zu bytes)\n", name.c_str(), bytes.size());
    ::alarm(REPLAY_TIMEOUT_S);
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    ::alarm(0);
  }
  std::printf("fuzz replay: %zu inputs, 0 defects\n", inputs.size());
  return 0;
}
