/// \file Fft3dFftw.cpp
/// Fft3d on FFTW3 with fftw3_omp threads (CPU build only; md/CMakeLists.txt).
#include <fftw3.h>
#include <omp.h>

#include <mutex>
#include <sstream>
#include <stdexcept>

#include "md/fft/Fft3d.h"

namespace granagg::md {

namespace {
/// FFTW's planner (and fftw_init_threads) is not thread-safe: one lock for all plan creation and
/// destruction in the process.
std::mutex& plannerMutex() {
  static std::mutex m;
  return m;
}
}  // namespace

struct Fft3d::Impl {
  int nx, ny, nz;
  fftw_plan r2c = nullptr;
  fftw_plan c2r = nullptr;
  int alignment = 0;  ///< fftw_alignment_of the planning arrays: execution needs the same

  /// The plans apply only to arrays aligned as the planning arrays (see the constructor).
  void checkAlignment(const double* in, const double* out) const {
    if (fftw_alignment_of(const_cast<double*>(in)) != alignment ||
        fftw_alignment_of(const_cast<double*>(out)) != alignment)
      throw std::logic_error(
          "Fft3d: arrays not aligned as FFTW's plan needs (allocate them with malloc or "
          "device_vector, not at an offset)");
  }
};

Fft3d::Fft3d(int nx, int ny, int nz) : m_impl(new Impl{nx, ny, nz}) {
  if (nx < 1 || ny < 1 || nz < 1) {
    std::ostringstream msg;
    msg << "Fft3d requires positive mesh sizes (got " << nx << " x " << ny << " x " << nz << ").";
    throw std::invalid_argument(msg.str());
  }
  std::lock_guard<std::mutex> lock(plannerMutex());
  static const bool threads_ok = fftw_init_threads() != 0;
  // Threads for the plan, fixed now: the same plan (hence the same arithmetic) is used whatever the
  // thread count at execution time. FFTW_ESTIMATE: planning does not time (or touch) the arrays, so
  // the plan is reproducible. Not FFTW_UNALIGNED, which rules out FFTW's SIMD codelets (4 FFTs of
  // 108^3, 2 threads: 36 ms unaligned, 31 ms with SIMD; 1 thread 69 and 47 ms): the plan is made
  // on fftw_malloc'd arrays and applies, through the new-array interface, to any arrays with the
  // same fftw_alignment_of (FFTW manual, "New-array Execute Functions"), which every malloc'd
  // device_vector of the CPU build has (16-byte aligned); execute() checks it.
  if (threads_ok) fftw_plan_with_nthreads(omp_get_max_threads());
  const std::size_t nreal = std::size_t(nx) * ny * nz;
  const std::size_t ncplx = std::size_t(nx) * ny * (nz / 2 + 1);
  double* r = fftw_alloc_real(nreal);
  fftw_complex* c = fftw_alloc_complex(ncplx);
  const unsigned flags = FFTW_ESTIMATE;
  m_impl->r2c = fftw_plan_dft_r2c_3d(nx, ny, nz, r, c, flags);
  m_impl->c2r = fftw_plan_dft_c2r_3d(nx, ny, nz, c, r, flags);
  m_impl->alignment = fftw_alignment_of(r);  // fftw_malloc aligns r and c alike
  fftw_free(r);
  fftw_free(c);
  if (!m_impl->r2c || !m_impl->c2r)
    throw std::runtime_error("Fft3d: FFTW could not create a plan.");
}

Fft3d::~Fft3d() {
  std::lock_guard<std::mutex> lock(plannerMutex());
  if (m_impl->r2c) fftw_destroy_plan(m_impl->r2c);
  if (m_impl->c2r) fftw_destroy_plan(m_impl->c2r);
}

void Fft3d::forward(const double* in, double* out) {
  // out-of-place r2c preserves its input (FFTW manual, "Planner Flags")
  m_impl->checkAlignment(in, out);
  fftw_execute_dft_r2c(m_impl->r2c, const_cast<double*>(in), reinterpret_cast<fftw_complex*>(out));
}

void Fft3d::backward(double* in, double* out) {
  m_impl->checkAlignment(in, out);
  fftw_execute_dft_c2r(m_impl->c2r, reinterpret_cast<fftw_complex*>(in), out);
}

std::size_t Fft3d::realSize() const { return std::size_t(m_impl->nx) * m_impl->ny * m_impl->nz; }
std::size_t Fft3d::complexSize() const {
  return std::size_t(m_impl->nx) * m_impl->ny * (m_impl->nz / 2 + 1);
}
const char* Fft3d::backendName() { return "FFTW3 (OpenMP threads)"; }

}  // namespace granagg::md
