#pragma once
/// \file Msd.h
/// Mean-squared displacement from unwrapped positions (position + image * L; docs/ARCHITECTURE.md,
/// "Files and formats": image counts are required, unwrapping from jumps fails whenever a particle
/// moves more than L/2 between frames).
///
/// MsdFromOrigin: <|r(t) - r(t0)|^2> with t0 the first frame. The freely cooling gas ages, so time
/// origins are not equivalent and this is the primary MSD (docs/model.md section 10).
/// MsdAllOrigins: average over all time origins for evenly spaced frames, by the FFT method
/// (Kneller, Keiner, Kneller & Schiller, Comput. Phys. Commun. 91, 191 (1995); Calandrini et al.,
/// Collection SFN 12, 201 (2011)): MSD(m) = S1(m) - 2 S2(m) with S2 the position autocorrelation
/// from a zero-padded FFT (FFTW) and S1 from a running sum, O(F log F) per particle.
/// It keeps every frame's unwrapped positions (24 N F bytes), within a memory budget.
#include <cstddef>
#include <string>
#include <vector>

#include "analysis/io/Frame.h"

namespace granagg::analysis {

class MsdFromOrigin {
 public:
  /// Adds a frame; the first one is the origin. Throws std::invalid_argument when the frame has
  /// no image counts or a different particle count than the origin.
  void accumulate(const Frame& f);
  const std::vector<double>& times() const { return m_t; }
  /// MSD per frame, in d^2.
  const std::vector<double>& msd() const { return m_msd; }
  void reset();
  /// What it carries between frames (RunAnalysis::saveState), and back.
  struct State {
    std::vector<double> origin, t, msd;
  };
  State state() const { return {m_origin, m_t, m_msd}; }
  void restore(State s);

 private:
  std::vector<double> m_origin, m_t, m_msd;
};

class MsdAllOrigins {
 public:
  /// `max_bytes`: memory allowed for the stored positions; once exceeded the accumulator gives
  /// up (available() turns false) and releases its memory.
  explicit MsdAllOrigins(std::size_t max_bytes = std::size_t(1) << 30);
  /// Stores a frame's unwrapped positions (frames without image counts make it unavailable).
  void accumulate(const Frame& f);
  /// True while the stored frames are evenly spaced (relative tolerance 1e-6), have images and fit
  /// the budget.
  bool available() const { return m_available && m_frames >= 2; }
  /// Why it is unavailable ("" when available).
  const std::string& reason() const { return m_reason; }
  /// Computes MSD(lag m * dt), m = 0..F-1; lag times in `lag`. Throws std::logic_error when
  /// unavailable.
  std::vector<double> compute(std::vector<double>& lag) const;
  void reset();
  /// What it carries between frames (RunAnalysis::saveState), and back (the budget stays).
  struct State {
    std::size_t n = 0, frames = 0;
    bool available = true;
    std::string reason;
    double t0 = 0.0, dt = 0.0;
    std::vector<double> xyz;
  };
  State state() const { return {m_n, m_frames, m_available, m_reason, m_t0, m_dt, m_xyz}; }
  void restore(State s);

 private:
  void giveUp(const std::string& why);
  std::size_t m_max_bytes, m_n = 0, m_frames = 0;
  bool m_available = true;
  std::string m_reason;
  double m_t0 = 0.0, m_dt = 0.0;
  std::vector<double> m_xyz;  // [frame][particle][3]
};

/// Reference O(F^2) all-origins MSD of one-particle series x[frame][3] (tests).
std::vector<double> msdAllOriginsDirect(const std::vector<std::vector<double>>& x);

}  // namespace granagg::analysis
