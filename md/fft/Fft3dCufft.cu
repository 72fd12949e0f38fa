/// \file Fft3dCufft.cu
/// Fft3d on cuFFT (CUDA build only; md/CMakeLists.txt). Double precision D2Z / Z2D plans on the
/// default stream, the one Thrust's algorithms use, so no extra synchronisation is needed.
#include <cufft.h>

#include <sstream>
#include <stdexcept>

#include "md/fft/Fft3d.h"

namespace granagg::md {

namespace {
void check(cufftResult r, const char* what) {
  if (r != CUFFT_SUCCESS) {
    std::ostringstream msg;
    msg << "Fft3d (cuFFT): " << what << " failed with cufftResult " << static_cast<int>(r) << ".";
    throw std::runtime_error(msg.str());
  }
}
}  // namespace

struct Fft3d::Impl {
  int nx, ny, nz;
  cufftHandle r2c = 0;
  cufftHandle c2r = 0;
  bool have_r2c = false, have_c2r = false;
};

Fft3d::Fft3d(int nx, int ny, int nz) : m_impl(new Impl{nx, ny, nz}) {
  if (nx < 1 || ny < 1 || nz < 1) {
    std::ostringstream msg;
    msg << "Fft3d requires positive mesh sizes (got " << nx << " x " << ny << " x " << nz << ").";
    throw std::invalid_argument(msg.str());
  }
  check(cufftPlan3d(&m_impl->r2c, nx, ny, nz, CUFFT_D2Z), "cufftPlan3d(D2Z)");
  m_impl->have_r2c = true;
  check(cufftPlan3d(&m_impl->c2r, nx, ny, nz, CUFFT_Z2D), "cufftPlan3d(Z2D)");
  m_impl->have_c2r = true;
}

Fft3d::~Fft3d() {
  if (m_impl->have_r2c) cufftDestroy(m_impl->r2c);
  if (m_impl->have_c2r) cufftDestroy(m_impl->c2r);
}

void Fft3d::forward(const double* in, double* out) {
  check(cufftExecD2Z(m_impl->r2c, const_cast<cufftDoubleReal*>(in),
                     reinterpret_cast<cufftDoubleComplex*>(out)),
        "cufftExecD2Z");
}

void Fft3d::backward(double* in, double* out) {
  check(cufftExecZ2D(m_impl->c2r, reinterpret_cast<cufftDoubleComplex*>(in), out), "cufftExecZ2D");
}

std::size_t Fft3d::realSize() const { return std::size_t(m_impl->nx) * m_impl->ny * m_impl->nz; }
std::size_t Fft3d::complexSize() const {
  return std::size_t(m_impl->nx) * m_impl->ny * (m_impl->nz / 2 + 1);
}
const char* Fft3d::backendName() { return "cuFFT"; }

}  // namespace granagg::md
