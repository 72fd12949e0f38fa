#pragma once
// Writers of small trajectories for the analysis tests: a minimal H5MD 1.1 file (HDF5 C API,
// independent of md/'s writer, so that the reader is tested against the standard's layout) and
// a LAMMPS `dump custom` text file holding the same frames.
#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "analysis/io/Frame.h"
#include "common/Hdf5.h"

namespace testtraj {

using granagg::analysis::Frame;
namespace h5 = granagg::common::h5;

struct H5mdLayout {
  bool box = true;  // write /particles/all/box
  bool images = true;
  bool velocities = true;
  bool charges = true;
  std::size_t velocity_rows =
      static_cast<std::size_t>(-1);  // fewer rows than frames: a truncated element
  bool fixed_step_time = false;      // H5MD fixed-increment step/time (scalars)
  std::vector<std::pair<std::string, std::string>> parameters;  // string attributes of /parameters
};

inline void writeSeries(hid_t part, const std::string& name, hid_t ftype, hid_t mtype,
                        std::size_t rows, std::vector<hsize_t> inner, const void* data,
                        hid_t step_src_group) {
  h5::Handle g = h5::createGroup(part, name, "test");
  std::vector<hsize_t> shape{rows};
  shape.insert(shape.end(), inner.begin(), inner.end());
  h5::writeDataset(g.get(), "value", ftype, mtype, shape, data, "test");
  if (step_src_group >= 0) {
    H5Lcreate_hard(step_src_group, "step", g.get(), "step", H5P_DEFAULT, H5P_DEFAULT);
    H5Lcreate_hard(step_src_group, "time", g.get(), "time", H5P_DEFAULT, H5P_DEFAULT);
  }
}

/// Writes frames (positions wrapped in [0, L), images, velocities, charges) as H5MD.
inline void writeH5md(const std::string& path, const std::vector<Frame>& frames,
                      const H5mdLayout& lay = {}) {
  h5::silenceErrors();
  h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  const std::size_t F = frames.size(), N = frames.front().size();
  {
    h5::Handle g = h5::createGroup(file.get(), "h5md", "test");
    const int version[2] = {1, 1};
    const hsize_t two = 2;
    h5::Handle space(H5Screate_simple(1, &two, nullptr));
    h5::Handle a(
        H5Acreate2(g.get(), "version", H5T_STD_I32LE, space.get(), H5P_DEFAULT, H5P_DEFAULT));
    H5Awrite(a.get(), H5T_NATIVE_INT, version);
  }
  h5::Handle part = h5::createGroup(file.get(), "particles/all", "test");
  std::vector<double> pos, vel, q, edges, time;
  std::vector<int> img;
  std::vector<long long> step;
  for (const auto& f : frames) {
    pos.insert(pos.end(), f.position.begin(), f.position.end());
    vel.insert(vel.end(), f.velocity.begin(), f.velocity.end());
    q.insert(q.end(), f.charge.begin(), f.charge.end());
    img.insert(img.end(), f.image.begin(), f.image.end());
    for (int d = 0; d < 9; ++d) edges.push_back(d % 4 == 0 ? f.box : 0.0);
    time.push_back(f.time);
    step.push_back(f.step);
  }
  {
    h5::Handle g = h5::createGroup(part.get(), "position", "test");
    h5::writeDataset(g.get(), "value", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {F, N, 3}, pos.data(),
                     "test");
    if (lay.fixed_step_time) {
      const long long ds = F > 1 ? step[1] - step[0] : 1;
      const double dt = F > 1 ? time[1] - time[0] : 1.0;
      h5::writeDataset(g.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, {}, &ds, "test");
      h5::writeDataset(g.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &dt, "test");
    } else {
      h5::writeDataset(g.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, {F}, step.data(), "test");
      h5::writeDataset(g.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {F}, time.data(),
                       "test");
    }
  }
  h5::Handle posg(H5Gopen2(part.get(), "position", H5P_DEFAULT));
  if (lay.box) {
    h5::Handle box = h5::createGroup(part.get(), "box", "test");
    writeSeries(box.get(), "edges", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, F, {3, 3}, edges.data(),
                posg.get());
  }
  if (lay.images)
    writeSeries(part.get(), "image", H5T_STD_I32LE, H5T_NATIVE_INT, F, {N, 3}, img.data(),
                posg.get());
  if (lay.velocities && !vel.empty())
    writeSeries(part.get(), "velocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                std::min(F, lay.velocity_rows), {N, 3}, vel.data(), posg.get());
  if (lay.charges && !q.empty())
    writeSeries(part.get(), "charge", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, F, {N}, q.data(),
                posg.get());
  if (!lay.parameters.empty()) {
    h5::Handle g = h5::createGroup(file.get(), "parameters", "test");
    for (const auto& [k, v] : lay.parameters) h5::writeStringAttribute(g.get(), k, v, "test");
  }
}

/// Writes frames as a LAMMPS dump (`dump custom ... id x y z ix iy iz vx vy vz q`, ITEM: TIME),
/// atoms in a shuffled order (as several MPI ranks would write them), box origin `lo`.
/// `cut_last_after` >= 0 truncates the last frame after that many atom lines.
inline void writeLammps(const std::string& path, const std::vector<Frame>& frames, double lo = 0.0,
                        long cut_last_after = -1, bool unwrapped = false) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  std::mt19937_64 rng(7);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Frame& f = frames[k];
    std::fprintf(out,
                 "ITEM: TIME\n%.17g\nITEM: TIMESTEP\n%lld\nITEM: NUMBER OF ATOMS\n%zu\nITEM: BOX "
                 "BOUNDS pp pp pp\n",
                 f.time, static_cast<long long>(f.step), f.size());
    for (int d = 0; d < 3; ++d) std::fprintf(out, "%.17g %.17g\n", lo, lo + f.box);
    std::fprintf(out, unwrapped ? "ITEM: ATOMS id type xu yu zu vx vy vz q\n"
                                : "ITEM: ATOMS id type x y z ix iy iz vx vy vz q\n");
    std::vector<std::size_t> order(f.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), rng);
    long written = 0;
    for (std::size_t i : order) {
      if (k + 1 == frames.size() && cut_last_after >= 0 && written == cut_last_after) break;
      if (unwrapped) {
        std::fprintf(out, "%zu 1 %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", i + 1,
                     lo + f.unwrapped(i, 0), lo + f.unwrapped(i, 1), lo + f.unwrapped(i, 2),
                     f.velocity[3 * i], f.velocity[3 * i + 1], f.velocity[3 * i + 2], f.charge[i]);
      } else {
        std::fprintf(out, "%zu 1 %.17g %.17g %.17g %d %d %d %.17g %.17g %.17g %.17g\n", i + 1,
                     lo + f.position[3 * i], lo + f.position[3 * i + 1], lo + f.position[3 * i + 2],
                     f.image[3 * i], f.image[3 * i + 1], f.image[3 * i + 2], f.velocity[3 * i],
                     f.velocity[3 * i + 1], f.velocity[3 * i + 2], f.charge[i]);
      }
      ++written;
    }
  }
  std::fclose(out);
}

/// A random gas of N particles in a box L moving ballistically with Maxwell velocities, with
/// random charges, sampled at `times`; positions wrapped with image counts.
inline std::vector<Frame> ballisticGas(std::size_t N, double L, const std::vector<double>& times,
                                       unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, L);
  std::normal_distribution<double> G(0.0, 1.0);
  std::vector<double> x0(3 * N), v(3 * N), q(N);
  for (auto& x : x0) x = U(rng);
  for (auto& x : v) x = G(rng);
  for (auto& x : q) x = G(rng) * 0.1;
  std::vector<Frame> out;
  for (std::size_t k = 0; k < times.size(); ++k) {
    Frame f;
    f.index = k;
    f.step = static_cast<std::int64_t>(100 * k);
    f.time = times[k];
    f.box = L;
    f.position.resize(3 * N);
    f.image.resize(3 * N);
    for (std::size_t j = 0; j < 3 * N; ++j) {
      const double u = x0[j] + v[j] * times[k];
      const double n = std::floor(u / L);
      double w = u - n * L;
      int im = static_cast<int>(n);
      if (w >= L) {
        w -= L;
        ++im;
      }
      f.position[j] = w;
      f.image[j] = im;
    }
    f.velocity = v;
    for (std::size_t i = 0; i < N; ++i) q[i] *= 1.05;  // charges grow a little per frame
    f.charge = q;
    f.id.resize(N);
    for (std::size_t i = 0; i < N; ++i) f.id[i] = static_cast<std::int64_t>(i + 1);
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace testtraj
