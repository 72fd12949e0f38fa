#pragma once
/// \file ParticleData.h
/// Particle state as structure-of-arrays Thrust device vectors (host memory on the OpenMP backend,
/// GPU memory on CUDA). Only device sources (neighbor/, compute/, integrate/, engine/) include it.
#include <cstdint>

#include <thrust/device_vector.h>
#include <thrust/sequence.h>

namespace granagg::md {

template <class T>
using DVec = thrust::device_vector<T>;

template <class T>
T* raw(DVec<T>& v) {
  return thrust::raw_pointer_cast(v.data());
}
template <class T>
const T* raw(const DVec<T>& v) {
  return thrust::raw_pointer_cast(v.data());
}

struct ParticleData {
  DVec<double> x, y, z;        ///< wrapped positions in [0, L)
  DVec<double> xp, yp, zp;     ///< positions one step earlier (collision = first overlapping step)
  DVec<double> vx, vy, vz;
  DVec<double> fx, fy, fz;     ///< forces of the current positions
  DVec<double> q;              ///< charges
  DVec<int> ix, iy, iz;        ///< image counts
  /// Particle id (index in the user's order) of each slot: the engine stores particles sorted by
  /// cell for memory locality and maps back to ids for output.
  DVec<int> id;
  void resize(std::size_t n) {
    for (auto* v : {&x, &y, &z, &xp, &yp, &zp, &vx, &vy, &vz, &fx, &fy, &fz, &q}) v->assign(n, 0.0);
    for (auto* v : {&ix, &iy, &iz}) v->assign(n, 0);
    id.resize(n);
    thrust::sequence(id.begin(), id.end());
  }
  std::size_t size() const { return x.size(); }
};

}  // namespace granagg::md
