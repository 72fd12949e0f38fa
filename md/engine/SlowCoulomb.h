#pragma once
/// \file SlowCoulomb.h
/// The engine's Coulomb solvers and the slow force they give (Engine.h, "multiple time
/// stepping"; docs/coulomb.md): PPPM's mesh part plus its real space beyond r_fast over the
/// Coulomb list, or plain Ewald (the host reference: all of it, at every evaluation); the pair
/// tables of the near/far split; and the force and energy of the last evaluation, per slot.
/// The engine keeps the neighbour lists, the storage order and the schedule of evaluations
/// (md/integrate/SlowSchedule.h); this object computes what it is asked to.
#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "common/Box.h"
#include "md/compute/CoulombRealSpace.h"
#include "md/coulomb/CoulombDesign.h"
#include "md/coulomb/Ewald.h"
#include "md/coulomb/Pppm.h"
#include "md/coulomb/RealSpace.h"
#include "md/engine/ParticleData.h"
#include "md/engine/PhaseTimer.h"
#include "md/neighbor/NeighborList.h"

namespace granagg::md {

class SlowCoulomb {
 public:
  /// The solvers of design `d` (md/coulomb/CoulombDesign.h: PPPM or plain Ewald, as
  /// config.method says) for n particles in a box of edge L, with coupling config.K; the mesh's
  /// phases are timed into `timer` (may be null). The force starts at zero.
  SlowCoulomb(const CoulombDesign& d, const CoulombConfig& config, double L, std::size_t n,
              PhaseTimer* timer);

  const CoulombSetup& setup() const { return m_setup; }
  /// The near/far split (r2 = 0: none; the whole pair force is slow).
  const RealSpaceSwitch& fastSwitch() const { return m_fast_switch; }
  /// The fast pair force tabulated for the contact pass; false: no table (no split).
  bool fastTable(PairTable& table) const;
  /// PPPM (with a Coulomb list of reach r_cut), or else plain Ewald (no list).
  bool usesMesh() const { return m_pppm != nullptr; }

  /// Evaluates the slow force of the current positions into force() and energy(). `list`: the
  /// Coulomb list, current (PPPM; ignored for plain Ewald).
  void evaluate(const ParticleData& p, const NeighborList* list, const common::Box& box,
                PhaseTimer* timer);
  /// The Coulomb energy of the current positions, the forces untouched: `evaluated_here` when
  /// the last evaluation was of these positions (its energy is reused). `list` as evaluate().
  double energyNow(const ParticleData& p, const NeighborList* list, const common::Box& box,
                   bool evaluated_here) const;

  /// The slow force of the last evaluation, component a = 0, 1, 2, per slot: the impulse
  /// integrator applies it until the next evaluation, so it moves with its particles (the
  /// engine permutes it) and a checkpoint carries it.
  DVec<double>& force(int a) { return m_f[a]; }
  const DVec<double>& force(int a) const { return m_f[a]; }
  /// Energy of the last evaluation: PPPM mesh + self + background; plain Ewald everything.
  double energy() const { return m_energy; }
  /// A checkpoint's force (in slot order) and energy of the last evaluation.
  void restore(const std::vector<double>& fx, const std::vector<double>& fy,
               const std::vector<double>& fz, double energy);
  /// a += c F, per slot (a: the velocities or the forces).
  void addScaled(DVec<Vec3>& a, double c) const;

 private:
  CoulombRealParams realParams() const;
  CoulombResult ewaldOnHost(const ParticleData& p) const;

  CoulombSetup m_setup;
  double m_K;  // coulomb.K
  RealSpaceSwitch m_fast_switch{};
  std::unique_ptr<Pppm> m_pppm;
  std::unique_ptr<EwaldReference> m_ewald;
  // the slow and fast pair forces tabulated (PairTable), and the pair energy for the observables
  DVec<double> m_slow_table, m_fast_table, m_energy_table;
  std::array<DVec<double>, 3> m_f;
  double m_energy = 0.0;
};

}  // namespace granagg::md
