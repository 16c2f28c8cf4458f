#pragma once
// Isolated points of a frame (stereo mismatches, off the surface along their ray;
// docs/design.md §9a), found with the frame's own k-d tree so that nothing is indexed twice.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "registration/KdTree.hpp"

namespace rovermap::mapper {

/// Which points to keep.
struct OutlierMask {
  std::vector<unsigned char> keep;   ///< one per point; 1 = keep
  std::size_t removed = 0;           ///< points flagged isolated [count]
  double angular_spacing_rad = 0.0;  ///< median nearest-neighbour distance / range, as used
};

/// Radius outlier removal with a range-adaptive radius. A frame's points are spaced about
/// range × a constant angle (the pixel pitch); that angle α is the median of (nearest-neighbour
/// distance / range) over an even sample of at most 16 384 of the points. A point is isolated when fewer than `min_neighbors`
/// other points lie within `radius_factor` · α · range of it. `tree` indexes `points`;
/// `sensor_origin` is where the ranges are measured from. radius_factor <= 0 or min_neighbors
/// <= 0 keeps everything. Never throws.
OutlierMask FindIsolatedPoints(const std::vector<Eigen::Vector3d>& points,
                               const registration::KdTree& tree,
                               const Eigen::Vector3d& sensor_origin, double radius_factor,
                               int min_neighbors);

}  // namespace rovermap::mapper
