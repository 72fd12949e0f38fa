#pragma once
/// \file ParticleData.h
/// Particle state as Thrust device vectors (host memory on the OpenMP backend, GPU memory on
/// CUDA). Only device sources (neighbor/, compute/, integrate/, engine/, coulomb/) include it.
///
/// Layout: what the neighbour gathers read for a partner j -- its position, and its charge for the
/// Coulomb real-space term -- is packed into one 32-byte record (Scalar4, HOOMD-blue's layout), so
/// a neighbour costs one cache line instead of four. Velocities and forces are packed per particle
/// too (Vec3): a contact reads its partner's velocity and previous force (the predicted velocity,
/// ContactForce.h), one or two cache lines instead of six, and the per-step passes stream two
/// arrays instead of six. Image counts, read by nobody else, stay structure-of-arrays.
#include <cstdint>
#include <vector>

#include <thrust/device_vector.h>
#include <thrust/sequence.h>
#include <thrust/transform.h>

#include "common/HostDevice.h"

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

/// Four doubles in one aligned record: a position and one scalar (charge or unused).
struct alignas(32) Scalar4 {
  double x, y, z, w;
};

/// A velocity or force: three doubles, packed.
struct Vec3 {
  double x, y, z;
};

struct ParticleData {
  DVec<Scalar4> pos;     ///< wrapped positions in [0, L) (x, y, z) and charge (w)
  DVec<Vec3> vel;        ///< velocities
  DVec<Vec3> force;      ///< forces of the current positions
  DVec<int> ix, iy, iz;  ///< image counts
  /// Particle id (index in the user's order) of each slot: the engine stores particles sorted by
  /// cell for memory locality and maps back to ids for output.
  DVec<int> id;
  void resize(std::size_t n) {
    pos.assign(n, Scalar4{0, 0, 0, 0});
    vel.assign(n, Vec3{0, 0, 0});
    force.assign(n, Vec3{0, 0, 0});
    for (auto* v : {&ix, &iy, &iz}) v->assign(n, 0);
    id.resize(n);
    thrust::sequence(id.begin(), id.end());
  }
  std::size_t size() const { return pos.size(); }
  /// Sets positions and charges from host arrays (slot order).
  void setPositions(const std::vector<double>& x, const std::vector<double>& y,
                    const std::vector<double>& z, const std::vector<double>& q) {
    std::vector<Scalar4> h(x.size());
    for (std::size_t i = 0; i < h.size(); ++i)
      h[i] = Scalar4{x[i], y[i], z[i], q.empty() ? 0.0 : q[i]};
    pos.assign(h.begin(), h.end());
  }
};

/// Packs host component arrays (slot order) into v.
inline void packVec3(const std::vector<double>& x, const std::vector<double>& y,
                     const std::vector<double>& z, DVec<Vec3>& v) {
  std::vector<Vec3> h(x.size());
  for (std::size_t i = 0; i < h.size(); ++i) h[i] = Vec3{x[i], y[i], z[i]};
  v.assign(h.begin(), h.end());
}

struct Vec3Component {
  int c;
  HD double operator()(const Vec3& v) const { return c == 0 ? v.x : (c == 1 ? v.y : v.z); }
};
/// The components of v as three arrays (for output and observables, which work per component).
inline void unpackVec3(const DVec<Vec3>& v, DVec<double>& x, DVec<double>& y, DVec<double>& z) {
  DVec<double>* out[3] = {&x, &y, &z};
  for (int c = 0; c < 3; ++c) {
    out[c]->resize(v.size());
    thrust::transform(v.begin(), v.end(), out[c]->begin(), Vec3Component{c});
  }
}

}  // namespace granagg::md
