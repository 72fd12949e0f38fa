#pragma once
/// \file Pppm.h
/// Particle-particle particle-mesh Ewald (P3M / PPPM; Hockney & Eastwood, Computer Simulation
/// Using Particles, 1988; Deserno & Holm, J. Chem. Phys. 109, 7678 (1998)): the mesh (k-space)
/// part of the Coulomb interaction, plus the self and neutralising-background energies. The
/// real-space part is the engine's, over its neighbour list, with md/coulomb/RealSpace.h.
///
/// Method (docs/coulomb.md): charges are assigned to an M^3 mesh with the order-P cardinal
/// B-spline (P = 2..7 points per dimension), Fourier transformed, multiplied by Hockney and
/// Eastwood's optimal influence function for ik-differentiation (aliases |m| <= 2), differentiated
/// by ik in k space (three inverse FFTs), and the field is interpolated back to the particles with
/// the same weights. Energy E_k = (K / 2V) sum_k G_opt(k) |Q(k)|^2.
///
/// One source for both backends (Pppm.cpp: Thrust functors, device vectors, Fft3d). Determinism:
/// particles are sorted by (mesh cell, particle id), and the charge assignment is one of two
/// (PppmParams::assignment, the backend's faster one by default). Tiles (CPU): the mesh is cut
/// into tiles at least P cells wide, and tiles of one parity colour (8 passes) scatter their
/// particles' charges with plain adds, since their stencils cannot overlap. Fixed point (GPU):
/// one thread per particle adds its terms as 64-bit integers (the charge in units of a power of
/// two below the round-off of the mesh sums) with atomics, whose sum no order changes. The
/// interpolation is a per-particle gather; energies are block sums added in a fixed order.
/// Results do not depend on the thread count, nor (given ids) on the storage order of the
/// particles. The energy carries the mean P3M
/// self-energy correction (Ballenegger, Cerda & Holm 2012), so that a lone charge's energy
/// averages to the exact Ewald value.
///
/// This header has no Thrust in it (pimpl), so host-only code (tests, CLI) can use it in a CUDA
/// build.
#include <cstddef>
#include <memory>
#include <vector>

#include "md/coulomb/Ewald.h"
#include "md/coulomb/EwaldParams.h"

namespace granagg::md {

/// Energies of the last Pppm evaluation, in T0.
struct PppmEnergies {
  double kspace = 0.0;  ///< mesh sum (K / 2V) sum_k G_opt |Q(k)|^2 + mean self-energy correction
  double self = 0.0;    ///< -K alpha / sqrt(pi) sum q^2
  double background = 0.0;  ///< -K pi Q^2 / (2 alpha^2 V) (zero for a neutral system)
  double total() const { return kspace + self + background; }
};

class PhaseTimer;

class Pppm {
 public:
  /// Precomputes the influence function and plans the FFTs. \param params alpha > 0, mesh >= order,
  /// order 2..7 (e.g. from choosePppmParams); \param L box edge (> 0), in d; \param K coupling
  /// constant l_B / d (>= 0). Throws std::invalid_argument naming the offending value.
  Pppm(const PppmParams& params, double L, double K);
  ~Pppm();
  Pppm(const Pppm&) = delete;
  Pppm& operator=(const Pppm&) = delete;

  /// Adds the mesh forces to fx, fy, fz and returns the mesh + self + background energy.
  /// All pointers are device pointers (host memory in the CPU build), n entries each. Positions
  /// may lie anywhere (they are wrapped into the box). `id` (optional, values 0..n-1, a
  /// permutation) orders the charges within a mesh cell, so that results do not depend on the
  /// storage order; without it the slot index is used. fx, fy and fz all null: the energy alone
  /// (charge assignment and one FFT; none of the field's three inverse FFTs and interpolation).
  double compute(const double* x, const double* y, const double* z, const double* q, std::size_t n,
                 double* fx, double* fy, double* fz, const int* id = nullptr);

  /// The same for the engine's packed layout: pos4 holds n records of 4 doubles (x, y, z, q), the
  /// Scalar4 of md/engine/ParticleData.h (device pointer).
  double compute(const double* pos4, std::size_t n, double* fx, double* fy, double* fz,
                 const int* id = nullptr);

  /// Host convenience (copies in and out): the mesh forces alone (fx, fy, fz) and energies
  /// (energy_kspace, energy_self, energy_background; energy_real = 0; energy = their sum).
  CoulombResult computeHost(const std::vector<double>& x, const std::vector<double>& y,
                            const std::vector<double>& z, const std::vector<double>& q);

  /// Energies of the last compute(); throws std::logic_error before the first one.
  const PppmEnergies& lastEnergies() const;
  const PppmParams& params() const;
  double boxLength() const;
  /// Times the phases of compute() into `timer` (md/engine/PhaseTimer.h; null: none).
  void setPhaseTimer(PhaseTimer* timer);

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::md
