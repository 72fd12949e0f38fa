#pragma once
/// \file RunChecks.h
/// What a run's configuration asks of the machine, checked before anything is built or written.
#include "md/config/MdConfig.h"

namespace granagg::md {

/// The time step, the schedule and the memory that `config` asks for: a positive finite dt, a
/// step count that fits (at most 1e12 steps), a bounded number of frames (at most 1e6), and a
/// system.N whose engine fits in this machine's memory. Throws std::invalid_argument naming the
/// key and the bound.
void checkSchedule(const MdConfig& config);

}  // namespace granagg::md
