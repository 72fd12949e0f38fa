#pragma once
// Helpers shared by every test suite: scratch files and folders, whole-file reads, and the
// bit-for-bit comparisons behind the determinism claims (README, docs/ARCHITECTURE.md).
// Include as "TestUtil.h" (tests/ is on each suite's include path).
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace granagg::test {

/// A scratch file name /tmp/granagg_test_<pid>_<name>: unique per test process, so suites that
/// run side by side (ctest -j) never share a file. The file is not created.
inline std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("granagg_test_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

/// An empty scratch folder (removed and re-created), named as tempPath().
inline std::filesystem::path tempDir(const std::string& name) {
  const std::filesystem::path d = tempPath(name);
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

/// The whole file as bytes ("" if it cannot be read).
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Writes `bytes` to `path`, replacing it.
inline void spit(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Whether the test binary was started with --write-reference (tests/catch_main.cpp): golden-value
/// tests then rewrite their reference files from this build instead of checking them.
bool writeReference();

/// Same values to the bit (so -0.0 != 0.0 and NaN payloads count): what "bit for bit" means.
template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

inline bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace granagg::test
