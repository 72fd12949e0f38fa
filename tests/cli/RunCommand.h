#pragma once
// Runs a shell command for the CLI tests: exit status and stdout+stderr together.
#include <sys/wait.h>
#include <array>
#include <cstdio>
#include <stdexcept>
#include <string>

struct Run {
  int status;          ///< exit status (-1 if killed by a signal)
  std::string output;  ///< standard output and standard error, interleaved
};

inline Run sh(const std::string& cmd) {
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) throw std::runtime_error("popen failed for: " + cmd);
  std::string out;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
  const int st = pclose(p);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

/// The granagg binary under test (GRANAGG_BINARY, set by CMake) with `args`.
inline Run runGranagg(const std::string& args) {
  return sh(std::string(GRANAGG_BINARY) + " " + args);
}
