#pragma once
/// \file Interrupted.h
/// The exception of a command stopped by a signal after saving what it had.
#include <stdexcept>
#include <string>

namespace granagg::common {

/// A command stopped by SIGINT or SIGTERM after saving what it had (a checkpoint, finished runs):
/// main() prints the message on one line and exits with status(), 128 + the signal number, as
/// a shell reports a command killed by it (130 for SIGINT, 143 for SIGTERM).
class Interrupted : public std::runtime_error {
 public:
  Interrupted(const std::string& what, int signal)
      : std::runtime_error(what), m_status(128 + signal) {}
  int status() const { return m_status; }

 private:
  int m_status;
};

}  // namespace granagg::common
