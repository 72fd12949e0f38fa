#pragma once
/// \file Box.h
/// Cubic periodic box [0, L)^3 and the minimum-image convention (design.md section 2).
#include <cmath>

#include "common/HostDevice.h"

namespace granagg::common {

struct Box {
  double L = 1.0;  ///< edge length, in particle diameters d

  /// Minimum-image component: dx shifted by a multiple of L into [-L/2, L/2].
  HD double minimumImage(double dx) const { return dx - L * rint(dx / L); }
  /// Wraps a coordinate into [0, L) and returns the number of box lengths removed
  /// (added to the image count, so that unwrapped = wrapped + image * L).
  HD int wrap(double& x) const {
    const double n = floor(x / L);
    x -= n * L;
    if (x >= L) {  // rounding: x = L - tiny can land on L
      x -= L;
      return static_cast<int>(n) + 1;
    }
    if (x < 0.0) {
      x += L;
      return static_cast<int>(n) - 1;
    }
    return static_cast<int>(n);
  }
};

}  // namespace granagg::common
