#pragma once
/// The test interface of md::Engine: diagnostics that only tests read (the engine's friend), so
/// that the engine's public API is what a run uses.
#include "md/engine/Engine.h"

namespace granagg::md {

struct EngineProbe {
  /// Skin of the current contact list (it follows the gas where neighbor.skin is "auto").
  static double contactListSkin(const Engine& e) { return e.contactListSkin(); }
  /// Skin of the current Coulomb (PPPM real-space) list, 0 without Coulomb.
  static double coulombListSkin(const Engine& e) { return e.coulombListSkin(); }
};

}  // namespace granagg::md
