#pragma once
/// \file FuzzTarget.h
/// What every fuzz harness (tests/fuzz/fuzz_*.cpp; docs/robustness.md) holds a reader to. An input
/// either reads, or fails with the errors that the CLI turns into one line (cli/main.cpp):
/// std::invalid_argument (bad input, exit 2) or std::runtime_error (a damaged file, exit 1),
/// with a message of one non-empty line (the configuration parser reports up to 10 errors at once,
/// one per line, and says how many more). Anything else is a defect and aborts, so that libFuzzer
/// and the replay driver report it with the input: std::bad_alloc (a size taken from the file
/// unchecked), std::length_error and std::out_of_range (an index taken from the file unchecked),
/// another exception, a crash or a sanitizer report. Hangs (over 1 s) and more than 1 GB of
/// memory are libFuzzer's limits (-timeout, -rss_limit_mb, -malloc_limit_mb).
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>
#include <typeinfo>

#include "common/Hdf5.h"

namespace granagg::fuzz {

[[noreturn]] inline void defect(const char* kind, const char* what) {
  std::fprintf(stderr, "fuzz: DEFECT: %s: %s\n", kind, what);
  std::abort();
}

/// Runs one input through `read`, enforcing the contract above.
/// Whether a message is clear: 1 to 11 non-empty lines. (Bytes of the input that a message quotes
/// may be control characters: the CLIs print every message through common::terminalSafe.)
inline bool clearMessage(const std::string& m) {
  if (m.empty() || m.front() == '\n' || m.back() == '\n') return false;
  std::size_t lines = 1;
  for (std::size_t k = 0; k + 1 < m.size(); ++k) {
    if (m[k] != '\n') continue;
    if (m[k + 1] == '\n') return false;
    ++lines;
  }
  return lines <= 11;
}

template <class F>
void guarded(F&& read) {
  try {
    read();
  } catch (const std::invalid_argument& e) {
    if (!clearMessage(e.what())) defect("unclear message", e.what());
  } catch (const std::out_of_range& e) {
    defect("std::out_of_range (an unchecked index)", e.what());
  } catch (const std::length_error& e) {
    defect("std::length_error (an unchecked size)", e.what());
  } catch (const std::runtime_error& e) {
    if (!clearMessage(e.what())) defect("unclear message", e.what());
  } catch (const std::bad_alloc& e) {
    defect("std::bad_alloc (a size from the file, unchecked)", e.what());
  } catch (const std::exception& e) {
    defect(typeid(e).name(), e.what());
  }
}

/// The input as a file that readers open by path, without touching a disk: an anonymous memory
/// file (memfd_create), reached as /proc/self/fd/N.
class MemFile {
 public:
  MemFile(const std::uint8_t* data, std::size_t size) {
    m_fd = ::memfd_create("granagg-fuzz", 0);
    if (m_fd < 0) defect("memfd_create", std::strerror(errno));
    std::size_t off = 0;
    while (off < size) {
      const ssize_t w = ::write(m_fd, data + off, size - off);
      if (w <= 0) defect("write to memfd", std::strerror(errno));
      off += static_cast<std::size_t>(w);
    }
    m_path = "/proc/self/fd/" + std::to_string(m_fd);
  }
  ~MemFile() { ::close(m_fd); }
  MemFile(const MemFile&) = delete;
  MemFile& operator=(const MemFile&) = delete;
  const std::string& path() const { return m_path; }

 private:
  int m_fd = -1;
  std::string m_path;
};

/// The input as a named file in shared memory (/dev/shm, else $TMPDIR or /tmp), for readers
/// that HDF5 opens by name: HDF5 resolves a file's real path, which a memfd does not have.
class ShmFile {
 public:
  ShmFile(const std::uint8_t* data, std::size_t size) {
    const char* tmp = std::getenv("TMPDIR");
    const std::string dir = ::access("/dev/shm", W_OK) == 0 ? "/dev/shm" : (tmp ? tmp : "/tmp");
    m_path = dir + "/granagg-fuzz-" + std::to_string(::getpid()) + ".h5";
    std::FILE* f = std::fopen(m_path.c_str(), "wb");
    if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0)
      defect("cannot write the input to", m_path.c_str());
  }
  ~ShmFile() { std::remove(m_path.c_str()); }
  ShmFile(const ShmFile&) = delete;
  ShmFile& operator=(const ShmFile&) = delete;
  const std::string& path() const { return m_path; }

 private:
  std::string m_path;
};

/// Reads values off the front of the input, for the structure-aware harnesses (the idea of
/// LLVM's FuzzedDataProvider, which g++ builds of the replay driver do not have). Past the end it
/// yields zeros.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : m_p(data), m_n(size) {}
  std::uint8_t byte() {
    if (m_n == 0) return 0;
    --m_n;
    return *m_p++;
  }
  /// An integer in [lo, hi].
  std::uint64_t range(std::uint64_t lo, std::uint64_t hi) {
    std::uint64_t v = 0;
    for (int k = 0; k < 8 && (hi - lo) >> (8 * k); ++k) v = (v << 8) | byte();
    if (hi - lo == UINT64_MAX) return v;  // the whole range: hi - lo + 1 would wrap to 0
    return hi == lo ? lo : lo + v % (hi - lo + 1);
  }
  bool flag() { return byte() & 1; }
  /// A double: mostly ordinary values, and the special ones a file can hold (NaN, inf, huge).
  double real() {
    switch (byte() % 8) {
      case 0: {
        double d;
        std::uint64_t u = range(0, UINT64_MAX);
        std::memcpy(&d, &u, sizeof d);  // any bit pattern
        return d;
      }
      case 1:
        return static_cast<double>(static_cast<std::int64_t>(range(0, 2000))) - 1000.0;
      default:
        return static_cast<double>(range(0, 1 << 20)) / 4096.0;
    }
  }
  std::size_t left() const { return m_n; }

 private:
  const std::uint8_t* m_p;
  std::size_t m_n;
};

}  // namespace granagg::fuzz
