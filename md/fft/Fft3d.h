#pragma once
/// \file Fft3d.h
/// Real-to-complex 3-D FFT on device memory behind one small interface (docs/ARCHITECTURE.md):
/// FFTW3 with its OpenMP threads in the CPU build (Fft3dFftw.cpp), cuFFT in the CUDA build
/// (Fft3dCufft.cu). No Thrust or CUDA types here, so any translation unit may include it.
///
/// Layout (row major, as FFTW and cuFFT): real array r[(ix * ny + iy) * nz + iz]; complex array of
/// nx * ny * (nz/2 + 1) values c[(ix * ny + iy) * (nz/2 + 1) + iz], stored as interleaved
/// (re, im) doubles. Both directions are unnormalised:
///     forward:  c(k) = sum_r r(x) exp(-i k.x)
///     backward: r(x) = sum_k c(k) exp(+i k.x)   (over the full spectrum, Hermitian symmetry
///     implied)
/// so backward(forward(r)) = nx ny nz r.
///
/// Arrays must be aligned as malloc aligns them (16 bytes; every device_vector is): the FFTW plans
/// use SIMD codelets, which need it (std::logic_error otherwise).
///
/// Plans are made once in the constructor (FFTW's planner is not thread-safe; a global lock
/// serialises construction). A plan's result does not depend on the caller's thread count at
/// execution time.
#include <cstddef>
#include <memory>

namespace granagg::md {

class Fft3d {
 public:
  /// Plans transforms of an nx * ny * nz real mesh. Throws std::invalid_argument for sizes < 1
  /// and std::runtime_error if the backend cannot make a plan.
  Fft3d(int nx, int ny, int nz);
  ~Fft3d();
  Fft3d(const Fft3d&) = delete;
  Fft3d& operator=(const Fft3d&) = delete;

  /// Real -> complex (in: nx ny nz doubles, preserved; out: 2 complexSize() doubles), device
  /// pointers.
  void forward(const double* in, double* out);
  /// Complex -> real (in: 2 complexSize() doubles, overwritten; out: nx ny nz doubles), device
  /// pointers.
  void backward(double* in, double* out);

  std::size_t realSize() const;     ///< nx ny nz
  std::size_t complexSize() const;  ///< nx ny (nz/2 + 1) complex values
  /// "FFTW3 (OpenMP threads)" or "cuFFT": for logs.
  static const char* backendName();

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace granagg::md
