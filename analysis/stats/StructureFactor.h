#pragma once
/// \file StructureFactor.h
/// The static structure factor S(k) of the particle positions and the characteristic length of
/// the density field derived from it: a measure of clustering that needs no grid of occupied
/// sites and no contact criterion, as studies of clustering in freely cooling granular gases use
/// (Goldhirsch & Zanetti, PRL 70, 1619 (1993); Brito & Ernst, Europhys. Lett. 43, 497 (1998);
/// Das & Puri, PRE 68, 011302 (2003); Paul & Das, PRE 96, 012105 (2017)). docs/model.md
/// section 10 gives the definitions.
///
///     S(k) = < |rho_k|^2 > / N,   rho_k = sum_j exp(-i k . r_j),   k = (2 pi / L) n, n != 0
///
/// averaged over the wave vectors of a spherical shell |k| in [k_m - dk/2, k_m + dk/2), dk =
/// 2 pi / L, k_m = m dk. An ideal gas has S(k) = 1 at every k != 0; clusters raise S at small k.
///
/// Method. The positions are assigned to an M^3 mesh by cloud-in-cell (CIC) and transformed with
/// FFTW (real to complex). The mesh's |rho_k|^2 is divided by the CIC window's aliased sum for
/// uncorrelated particles, C(k) = prod_a [1 - (2/3) sin^2(k_a h / 2)] (Jing, ApJ 620, 559 (2005),
/// eq. 20, p = 2), so that an ideal gas gives S = 1 exactly in expectation at every k below the
/// mesh's Nyquist wavenumber; for correlated positions the correction is exact to O((k h)^2)
/// relative. The mesh spacing is h = L / M <= h_max (default 1/2 d), so that the cut-off
/// k_c = pi / d of the length below lies at half the Nyquist wavenumber pi / h or lower.
///
/// Characteristic length. The first moment of S over the shells up to the cut-off k_c,
///
///     k_1 = sum_{k_m <= k_c} k_m S(k_m) / sum_{k_m <= k_c} S(k_m),   l = 2 pi / k_1,
///
/// (Das & Puri 2003, their eq. 8, with shells weighted equally). An ideal gas, S = 1, gives the
/// baseline l_0 = 2 pi / mean(k_m) ~ 4 pi / k_c = 4 d at k_c = pi; clusters larger than that
/// raise l towards the box size. The first zero of the density correlation function C(r) was
/// the alternative; it has no value for an unclustered gas (C is noise around zero from the
/// first bin on), where the first moment has its stated baseline, so the first moment is used.
#include <cstddef>
#include <memory>
#include <vector>

#include "analysis/io/Frame.h"

namespace granagg::analysis {

struct StructureFactorOptions {
  double h_max = 0.5;                     ///< largest mesh spacing [d]
  double k_cut = 3.14159265358979323846;  ///< k_c of the first moment [1/d]
  std::size_t max_mesh = 512;  ///< largest M (memory: ~8 M^3 bytes); h may then exceed h_max
};

/// S(k) in spherical shells, and l.
struct StructureFactor {
  std::vector<double> k;  ///< shell centres k_m = m 2 pi / L, m = 1 .. (shells below Nyquist)
  std::vector<double> S;  ///< S(k_m), the mean over the shell's independent wave vectors
  std::vector<std::size_t> modes;  ///< independent wave vectors in the shell (one of each +-k)
  std::size_t mesh = 0;            ///< M
  double k_cut = 0.0;              ///< k_c used (at most the largest shell centre)
  double k1 = 0.0;      ///< first moment over k_m <= k_c (NaN when no shell: L < 2 pi / k_c)
  double length = 0.0;  ///< l = 2 pi / k_1
};

/// The FFTW mesh of structureFactor (one in-place transform buffer, ~8 M^3 bytes, and the plan;
/// velocityStructure adds ~4 M^3 bytes, kept between frames),
/// kept between calls of the same mesh size M, so that a trajectory's frames share one pair of
/// buffers. Allocated afresh per frame, they grow glibc's heap by about their size at every frame
/// (its mmap threshold rises to the freed size, and smaller allocations in between take the freed
/// space): 1.4 GB for the 70 frames of one paper-scale run, 28 GB for the 20-run ensemble.
class StructureFactorMesh {
 public:
  StructureFactorMesh();
  ~StructureFactorMesh();
  StructureFactorMesh(const StructureFactorMesh&) = delete;
  StructureFactorMesh& operator=(const StructureFactorMesh&) = delete;
  struct Buffers;
  /// The buffers and plan for mesh size M (re-made only when M changes).
  Buffers& forSize(long M);

 private:
  std::unique_ptr<Buffers> m_buffers;
};

/// S(k) and l of the positions of `frame` (wrapped into [0, L)), on `mesh`'s buffers. Throws
/// std::invalid_argument for an empty frame or bad options.
StructureFactor structureFactor(const Frame& frame, const StructureFactorOptions& options,
                                StructureFactorMesh& mesh);
/// The same on a mesh of its own (one frame).
StructureFactor structureFactor(const Frame& frame, const StructureFactorOptions& options = {});

/// The structure of the velocity field, on the mesh and in the shells of S(k): with the peculiar
/// velocities c_j = v_j - <v> and u(k) = sum_j c_j exp(-i k . r_j), its longitudinal part
/// k^ (k^ . u) and its transverse (shear, vorticity) part u - k^ (k^ . u) give
///
///     S_par(k) = < |k^ . u|^2 > / (N T_g),   S_perp(k) = < |u - k^ (k^ . u)|^2 > / (2 N T_g),
///
/// both 1 for velocities uncorrelated with each other and with the positions (an ideal gas);
/// T_g = <|c|^2> / 3. The shells' first moments over k_m <= k_c give the lengths l_par and l_perp
/// (the vortex length) as l = 2 pi / k_1 does for S(k) (van Noije, Ernst, Brito & Orza, PRL 79,
/// 411 (1997): vorticity dominates the velocity correlations of the cooling gas; Orza et al.
/// (1997): the mean vortex diameter grows as t^(1/2)). Each component is assigned by CIC with its
/// velocity as weight and corrected by Jing's aliased window as S(k) is (exact in expectation for
/// uncorrelated particles). k^ . u is accumulated in single precision.
struct VelocityStructure {
  std::vector<double> k;        ///< shell centres k_m = m 2 pi / L
  std::vector<double> S_long;   ///< S_par(k_m)
  std::vector<double> S_trans;  ///< S_perp(k_m)
  std::vector<std::size_t> modes;
  std::size_t mesh = 0;
  double k_cut = 0.0;
  double T_g = 0.0;           ///< granular temperature of the frame
  double length_long = 0.0;   ///< l_par = 2 pi / k_1 of S_par
  double length_trans = 0.0;  ///< l_perp = 2 pi / k_1 of S_perp
};

/// S_par, S_perp and their lengths for `frame` (which must hold velocities), on `mesh`'s buffers
/// (shared with structureFactor). Throws std::invalid_argument for a frame without velocities.
VelocityStructure velocityStructure(const Frame& frame, const StructureFactorOptions& options,
                                    StructureFactorMesh& mesh);

}  // namespace granagg::analysis
