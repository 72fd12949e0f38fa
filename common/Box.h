#pragma once
/// \file Box.h
/// Cubic periodic box [0, L)^3 and the minimum-image convention (docs/model.md section 5).
#include <cmath>
#include <cstdint>
#include <limits>

#include "common/HostDevice.h"

namespace granagg::common {

struct Box {
  double L = 1.0;  ///< edge length, in particle diameters d

  /// Minimum-image component: dx shifted by a multiple of L into [-L/2, L/2].
  HD double minimumImage(double dx) const { return dx - L * rint(dx / L); }
  /// Minimum image of the difference of two wrapped coordinates (both in [0, L), so |dx| < L):
  /// at most one shift, no division. Equal to minimumImage(dx) for such dx except possibly at the
  /// tie |dx| = L/2, where both are valid minimum images (the MD hot loops use it: a division and
  /// a rounding per component cost more than the rest of a contact test).
  HD double minimumImageWrapped(double dx) const {
    const double h = 0.5 * L;
    return dx > h ? dx - L : (dx < -h ? dx + L : dx);
  }
  /// minimumImageWrapped without branches, equal to it to the bit (x - L * 1.0 == x - L): for
  /// loops where differences across the faces are frequent and unpredictable (the cell search next
  /// to a face), where a branch per component would be mispredicted.
  HD double minimumImageWrappedBranchless(double dx) const {
    const double h = 0.5 * L;
    return dx - L * static_cast<double>((dx > h) - (dx < -h));
  }
  /// Whether three coordinates all lie inside [0, L), in one test: |x - L/2| < L/2 holds only
  /// inside (x - L/2 is exact for x in [L/2, L], and rounds to at most -L/2 for x < 0). x = 0 and
  /// NaN report false: the caller's full path (wrap) handles them.
  HD_INLINE bool insideAll(double a, double b, double c) const {
    const double h = 0.5 * L;
    const double da = fabs(a - h), db = fabs(b - h), dc = fabs(c - h);
    return (da > db ? da : db) < h && dc < h;
  }
  /// Wraps a coordinate into [0, L) and returns the number of box lengths removed
  /// (added to the image count, so that unwrapped = wrapped + image * L).
  HD_INLINE int wrap(double& x) const {
    if (x >= 0.0 && x < L) return 0;  // inside: nearly always (inlined into the drift loops)
    return wrapOutside(x);
  }
  /// wrap() for x outside [0, L).
  HD int wrapOutside(double& x) const {
    // fast path: a particle crosses at most one face per step (the result is the same as below)
    if (x >= L && x < 2.0 * L) {  // x - L is exact here (Sterbenz), so it lies in [0, L)
      x -= L;
      return 1;
    }
    if (x < 0.0 && x >= -L) {
      const double y = x + L;  // may round up to L for a tiny negative x: then the general case
      if (y < L) {
        x = y;
        return -1;
      }
    }
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

/// Wraps x into [0, box) and adds the box lengths removed to `image`, exactly: a coordinate
/// already inside is left bit for bit. Returns false, leaving both untouched, if x is not finite
/// or the image count would overflow int32. For readers and writers (host only); the MD hot
/// loops use Box::wrap.
inline bool wrapCoordinate(double& x, std::int32_t& image, double box) {
  if (!std::isfinite(x)) return false;
  if (x >= 0.0 && x < box) return true;  // already wrapped: leave it bit for bit
  const double shift = std::floor(x / box);
  const double img = static_cast<double>(image) + shift;
  // +-1 headroom for the round-off corrections below
  if (!(std::fabs(img) < static_cast<double>(std::numeric_limits<std::int32_t>::max()) - 1.0))
    return false;
  double w = x - shift * box;
  std::int64_t im = static_cast<std::int64_t>(img);
  // x / box may round across an integer: bring w back into [0, box). A tiny negative w becomes
  // box after adding box and is then mapped to 0 (the nearest wrapped value).
  if (w < 0.0) {
    w += box;
    --im;
  }
  if (w >= box) {
    w -= box;
    ++im;
  }
  if (w < 0.0) w = 0.0;
  x = w;
  image = static_cast<std::int32_t>(im);
  return true;
}

}  // namespace granagg::common
