#pragma once
/// \file PhaseTimer.h
/// Wall time of the MD step by phase: where the time goes (`granagg md --profile`).
/// What no phase covers (observables, output, checkpoints, the Coulomb list rebuilt for an energy)
/// is the loop's time minus their sum. Opt-in: a disabled timer (the default) reads no clock and
/// synchronises nothing. Enabled, each scope waits for the device before reading the clock on the
/// CUDA backend (kernels and cuFFT run asynchronously), so the phases add up to the loop's time at
/// the price of those waits; the CPU backend's Thrust algorithms return when done. Timing changes
/// no result.
#include <array>
#include <chrono>
#include <string>
#include <utility>
#include <vector>

#ifdef __CUDACC__
#include <cuda_runtime.h>
#endif

namespace granagg::md {

class PhaseTimer {
 public:
  /// The phases of a step (Engine.cpp, EngineCoulomb.cpp, Pppm.cpp), in the order of the report.
  enum Phase {
    ContactPass,      ///< contact forces + fast Coulomb pairs (+ the fused kick/drift)
    KickDrift,        ///< velocity-Verlet kicks and drift outside the contact pass
    ContactList,      ///< contact neighbour list builds (cell sort included)
    CoulombList,      ///< Coulomb real-space list builds
    CoulombReal,      ///< slow real-space Coulomb pairs
    PppmSort,         ///< PPPM: particles sorted by stencil cell, weights
    PppmAssign,       ///< PPPM: charge assignment
    PppmFft,          ///< PPPM: the four FFTs
    PppmKspace,       ///< PPPM: energy and field spectra (influence function products)
    PppmInterpolate,  ///< PPPM: forces interpolated back to the particles
    COUNT
  };

  static const char* name(Phase p) {
    static const char* const names[COUNT] = {
        "contact pass", "kick + drift",    "contact list", "Coulomb list", "Coulomb real (slow)",
        "PPPM sort",    "PPPM assignment", "PPPM FFTs",    "PPPM k-space", "PPPM interpolation"};
    return names[p];
  }

  void enable(bool on) { m_on = on; }
  bool enabled() const { return m_on; }

  /// Seconds per phase so far (zeros when never enabled).
  std::vector<std::pair<std::string, double>> seconds() const {
    std::vector<std::pair<std::string, double>> out;
    for (int p = 0; p < COUNT; ++p) out.emplace_back(name(static_cast<Phase>(p)), m_s[p]);
    return out;
  }

  /// Adds the time from construction to destruction to one phase (when the timer is enabled).
  class Scope {
   public:
    Scope(PhaseTimer* t, Phase p) : m_t(t && t->m_on ? t : nullptr), m_p(p) {
      if (m_t) m_start = now();
    }
    ~Scope() {
      if (m_t) m_t->m_s[m_p] += std::chrono::duration<double>(now() - m_start).count();
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    static std::chrono::steady_clock::time_point now() {
#ifdef __CUDACC__
      cudaDeviceSynchronize();
#endif
      return std::chrono::steady_clock::now();
    }
    PhaseTimer* m_t;
    Phase m_p;
    std::chrono::steady_clock::time_point m_start;
  };

 private:
  bool m_on = false;
  std::array<double, COUNT> m_s{};
};

}  // namespace granagg::md
