#pragma once
/// \file Ewald.h
/// Plain Ewald summation of the periodic Coulomb interaction: the reference for the mesh method
/// (docs/model.md section 4). Host-only, double precision, written to be obviously correct
/// rather than fast: O(N^2) real space over all images within r_cut and an explicit reciprocal sum.
///
/// For N charges q_i in a periodic cube of edge L (volume V = L^3) with coupling K and tinfoil
/// (conducting) boundary conditions, the energy (Frenkel & Smit, sec. 12.1; Kolafa & Perram 1992)
///
///     E = E_real + E_recip + E_self + E_background
///     E_real  = (K/2) sum_{i,j} sum_{n: |r_ij + nL| < r_cut}' q_i q_j erfc(alpha r) / r   (' : no
///     i = j, n = 0) E_recip = (K / 2V) sum_{k != 0, |k| <= k_max 2pi/L} (4 pi / k^2) exp(-k^2 / 4
///     alpha^2) |S(k)|^2,
///               S(k) = sum_j q_j exp(i k.r_j)
///     E_self  = -K alpha / sqrt(pi) sum_i q_i^2
///     E_background = -K pi Q^2 / (2 alpha^2 V),  Q = sum_i q_i   (uniform neutralising background;
///               zero for neutral systems; Hummer, Pratt & Garcia, J. Phys. Chem. 100, 1206 (1996))
///
/// and the forces F_i = -dE/dr_i (the background adds no force). No dipole (surface) term: tinfoil.
#include <cstddef>
#include <vector>

#include "md/coulomb/EwaldParams.h"

namespace granagg::md {

/// Energies (in T0) and per-particle forces (in T0 / d) of a Coulomb evaluation.
struct CoulombResult {
  double energy = 0.0;             ///< total: real + kspace + self + background
  double energy_real = 0.0;        ///< real-space sum
  double energy_kspace = 0.0;      ///< reciprocal (or mesh) sum
  double energy_self = 0.0;        ///< -K alpha / sqrt(pi) sum q^2
  double energy_background = 0.0;  ///< -K pi Q^2 / (2 alpha^2 V)
  std::vector<double> fx, fy, fz;  ///< total forces, in the input order
};

class EwaldReference {
 public:
  /// \param params alpha > 0, r_cut > 0 (any value; images beyond the minimum one are summed),
  ///        k_max >= 1 (e.g. from chooseEwaldParams)
  /// \param L box edge (> 0), in d; \param K coupling constant l_B / d (>= 0)
  /// Throws std::invalid_argument naming the offending value.
  EwaldReference(const EwaldParams& params, double L, double K);

  /// Energy and forces of charges q at positions (x, y, z) (any real coordinates; periodic).
  /// Throws std::invalid_argument if the arrays differ in length.
  CoulombResult compute(const std::vector<double>& x, const std::vector<double>& y,
                        const std::vector<double>& z, const std::vector<double>& q) const;

  /// Real-space part alone, O(n^2) over all images within r_cut (the minimum image only when
  /// r_cut <= L/2): adds the forces to fx, fy, fz and returns E_real. Used by the tests to add the
  /// real-space part to Pppm's mesh part with the same RealSpace.h functions the engine uses.
  static double realSpace(const double* x, const double* y, const double* z, const double* q,
                          std::size_t n, double L, double K, double alpha, double r_cut, double* fx,
                          double* fy, double* fz);

  /// Self energy -K alpha / sqrt(pi) sum_q2.
  static double selfEnergy(double alpha, double K, double sum_q2);
  /// Neutralising-background energy -K pi q_total^2 / (2 alpha^2 L^3).
  static double backgroundEnergy(double alpha, double K, double L, double q_total);

  const EwaldParams& params() const { return m_params; }

 private:
  EwaldParams m_params;
  double m_L;
  double m_K;
};

}  // namespace granagg::md
