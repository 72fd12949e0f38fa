#pragma once
// Charge configurations shared by the Coulomb tests (test_ewald.cpp, test_pppm.cpp): ionic
// crystals with nearest-neighbour distance 1, whose Madelung constants are published; and the
// rms force difference the accuracy tests compare with.
#include <cmath>
#include <vector>

#include "md/coulomb/Ewald.h"

namespace granagg::md::testing {

struct Charges {
  std::vector<double> x, y, z, q;
  double L = 0.0;
  void add(double a, double b, double c, double charge) {
    x.push_back(a);
    y.push_back(b);
    z.push_back(c);
    q.push_back(charge);
  }
  double sumQ2() const {
    double s = 0.0;
    for (double v : q) s += v * v;
    return s;
  }
};

/// Rock salt with nearest-neighbour distance 1: ions on the integer lattice, charge (-1)^(i+j+k),
/// `cells` conventional cells (edge 2) per side.
inline Charges nacl(int cells) {
  Charges c;
  const int n = 2 * cells;
  c.L = n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) c.add(i, j, k, (i + j + k) % 2 ? -1.0 : 1.0);
  return c;
}

/// Caesium chloride with nearest-neighbour distance 1: simple cubic cells of edge a = 2/sqrt(3),
/// +1 at the corner and -1 at the body centre.
inline Charges cscl(int cells) {
  Charges c;
  const double a = 2.0 / std::sqrt(3.0);
  c.L = cells * a;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j)
      for (int k = 0; k < cells; ++k) {
        c.add(i * a, j * a, k * a, 1.0);
        c.add((i + 0.5) * a, (j + 0.5) * a, (k + 0.5) * a, -1.0);
      }
  return c;
}

/// The rms over particles of |F_a - F_b|.
inline double rmsDifference(const CoulombResult& a, const CoulombResult& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.fx.size(); ++i) {
    const double dx = a.fx[i] - b.fx[i], dy = a.fy[i] - b.fy[i], dz = a.fz[i] - b.fz[i];
    s += dx * dx + dy * dy + dz * dz;
  }
  return std::sqrt(s / static_cast<double>(a.fx.size()));
}

}  // namespace granagg::md::testing
