#pragma once
// The simulator's ground truth: a heightfield with fractal relief, a regional slope, craters and
// rocks, and a procedural albedo texture fine enough for correlation stereo to match.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sim/SimOptions.hpp"

namespace rovermap::sim {

/// Deterministic hash of up to four integers into [0, 1) (counter-based noise: every sample
/// is a pure function of its indices, so results do not depend on evaluation order).
double Hash01(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d);
/// Standard normal sample from the same hash (Box-Muller).
double HashNormal(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d);

class Terrain {
 public:
  /// Builds the heightfield from `options` (seeded). Rocks keep `options.keep_out_m` away from
  /// the points of `path_xy` (the rover's wheels stay on the relief).
  Terrain(const SimOptions& options, const std::vector<Eigen::Vector2d>& path_xy);

  /// Height [m] at world (x, y), bilinear between samples; NaN outside the square.
  double Height(double x, double y) const;
  /// Upward unit normal at (x, y) from the heightfield's central differences.
  Eigen::Vector3d Normal(double x, double y) const;
  /// Albedo in [0, 1] at (x, y); texture octaves finer than `footprint_m` (a pixel's size on
  /// the ground) are left out so that distant texture does not alias.
  double Albedo(double x, double y, double footprint_m) const;
  /// First intersection of the ray origin + t·direction (direction unit), t in (0, max_t].
  /// @return false when the ray leaves the square or reaches max_t without hitting.
  bool Raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double max_t,
               double* t_hit) const;

  double half_size_m() const { return half_size_; }
  double cell_m() const { return cell_; }
  int samples() const { return n_; }
  /// Height sample (i, j) at x = −half + i·cell, y = −half + j·cell.
  double Sample(int i, int j) const { return heights_[static_cast<std::size_t>(j) * n_ + i]; }

 private:
  double FractalNoise(double x, double y, double wavelength, int octaves, double persistence,
                      std::uint64_t salt, double min_wavelength) const;

  std::uint64_t seed_;
  double half_size_;
  double cell_;
  int n_;
  std::vector<float> heights_;
  std::vector<float> rock_;  ///< per sample: 1 on a rock, 0 off (darker albedo)
};

}  // namespace rovermap::sim
