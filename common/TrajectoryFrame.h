#pragma once
/// \file TrajectoryFrame.h
/// One frame of a trajectory file as read, whatever the file's format (H5MD, a LAMMPS dump): what
/// common::H5mdReader and analysis's readers return. The MD engine's own host state is md::Frame
/// (one array per component, forces included); md/io/InitialState converts (engineFrame).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace granagg::common {

/// Positions are wrapped into [0, L)^3 (a box with origin 0; readers shift other origins), so
/// that unwrapped = position + image * L. Optional arrays are empty when the file lacks them.
/// Reduced units (d = m = T0 = 1): lengths in d, velocities in sqrt(T0/m), charges in q_ref.
struct TrajectoryFrame {
  std::size_t index = 0;            ///< 0-based frame number in its file
  std::int64_t step = 0;            ///< integration step (H5MD step, LAMMPS TIMESTEP)
  double time = 0.0;                ///< time, in sqrt(m d^2 / T0)
  double box = 0.0;                 ///< edge L of the cubic periodic box, in d
  std::vector<double> position;     ///< 3N, x0 y0 z0 x1 ..., wrapped into [0, L)
  std::vector<std::int32_t> image;  ///< 3N image counts, or empty
  std::vector<double> velocity;     ///< 3N, or empty
  std::vector<double> charge;       ///< N, or empty
  std::vector<std::int64_t> id;     ///< N particle ids (0-based index order when the file has none)

  std::size_t size() const { return position.size() / 3; }
  bool hasImages() const { return !image.empty(); }
  bool hasVelocities() const { return !velocity.empty(); }
  bool hasCharges() const { return !charge.empty(); }
  /// Unwrapped coordinate d (0..2) of particle i: position + image * L.
  double unwrapped(std::size_t i, int d) const {
    return position[3 * i + d] +
           (image.empty() ? 0.0 : static_cast<double>(image[3 * i + d]) * box);
  }
};

/// A missing, truncated or malformed trajectory: the message names the file and the frame.
/// `frame()` is the 0-based index of the first frame that could not be read; the ones before it
/// are fine (0 for a file that cannot be opened at all).
class TrajectoryError : public std::runtime_error {
 public:
  TrajectoryError(const std::string& file, std::size_t frame, const std::string& what)
      : std::runtime_error("trajectory '" + file + "', frame " + std::to_string(frame) + ": " +
                           what),
        m_frame(frame) {}
  std::size_t frame() const { return m_frame; }

 private:
  std::size_t m_frame;
};

}  // namespace granagg::common
