#pragma once
/// \file VelocityVerlet.h
/// Velocity Verlet for unit masses (device source): kick v += (dt/2) f; drift x += dt v with
/// periodic wrapping and image counting; forces; kick. Symplectic and time-reversible for
/// conservative forces: energy errors O(dt^2), no drift (Swope et al., J. Chem. Phys. 76, 637 (1982)).
#include "common/Box.h"
#include "md/engine/ParticleData.h"

namespace granagg::md {

/// v += half_dt * f
void kick(ParticleData& p, double half_dt);
/// xp = x; x += dt v; wrap into [0, L) and update the image counts.
void drift(ParticleData& p, double dt, const common::Box& box);

}  // namespace granagg::md
