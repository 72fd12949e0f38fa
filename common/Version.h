#pragma once
/// \file Version.h
/// Version and build provenance, written into every output file granagg makes.
#include <string>

namespace granagg::common {
/// Semantic version of granagg (from the top-level CMakeLists.txt).
const char* version();
/// `git describe --always --dirty` of the source tree the binary was built from ("unknown" outside
/// git).
const char* gitCommit();
/// "granagg <version> (<commit>)", the string written into provenance headers.
inline std::string versionString() {
  return std::string("granagg ") + version() + " (" + gitCommit() + ")";
}
/// What the granagg executable puts before an error on stderr (cli/main.cpp), and what a program
/// that runs it strips from its last line (study/PairStudy.cpp).
inline constexpr const char* ERROR_PREFIX = "granagg: error: ";
}  // namespace granagg::common
