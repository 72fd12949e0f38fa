#pragma once
/// \file ProgressLine.h
/// Progress of a long loop on stderr, for people at a terminal and for logs alike. On a terminal
/// the line is rewritten in place at most twice a second; into a file (a background run with its
/// log redirected) a full line is written at most every `log_interval` seconds, so that `tail`
/// shows where the run is. Silent when disabled (-q).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace granagg::common {

class ProgressLine {
 public:
  /// \param prefix e.g. "md" (lines read "md: <text>"); \param enabled false: nothing is shown;
  /// \param log_interval seconds between lines when stderr is not a terminal.
  ProgressLine(std::string prefix, bool enabled, double log_interval = 60.0)
      : m_prefix(std::move(prefix)),
        m_enabled(enabled),
        m_tty(::isatty(2) != 0),
        m_interval(m_tty ? 0.5 : log_interval),
        m_last(Clock::now()) {}
  ~ProgressLine() { finish(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// True when a line is due now (the caller may skip composing the text otherwise).
  bool due() const {
    return m_enabled && std::chrono::duration<double>(Clock::now() - m_last).count() >= m_interval;
  }
  /// Shows `text` if a line is due.
  void show(const std::string& text) {
    if (!due()) return;
    m_last = Clock::now();
    if (m_tty) {
      std::fprintf(stderr, "\r%s: %s   ", m_prefix.c_str(), text.c_str());
      m_open = true;
    } else {
      std::fprintf(stderr, "%s: %s\n", m_prefix.c_str(), text.c_str());
    }
    std::fflush(stderr);
  }
  /// Ends an in-place terminal line, so that what follows starts on a clean line.
  void finish() {
    if (!m_open) return;
    std::fprintf(stderr, "\n");
    m_open = false;
  }
  bool terminal() const { return m_tty; }

 private:
  using Clock = std::chrono::steady_clock;
  std::string m_prefix;
  bool m_enabled, m_tty;
  double m_interval;
  Clock::time_point m_last;
  bool m_open = false;
};

}  // namespace granagg::common
