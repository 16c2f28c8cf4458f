#include "mapper/OutlierFilter.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace rovermap::mapper {

OutlierMask FindIsolatedPoints(const std::vector<Eigen::Vector3d>& points,
                               const registration::KdTree& tree,
                               const Eigen::Vector3d& sensor_origin, double radius_factor,
                               int min_neighbors) {
  OutlierMask mask;
  const std::size_t n = points.size();
  mask.keep.assign(n, 1);
  if (!(radius_factor > 0.0) || min_neighbors <= 0 || n < 2 || tree.size() != n) return mask;

  // k = self + min_neighbors others; the buffers are small and per thread.
  constexpr int kMaxNeighbors = 16;
  const std::size_t k = static_cast<std::size_t>(std::min(min_neighbors, kMaxNeighbors)) + 1;
  std::vector<float> nearest_over_range(n), kth_over_range(n);
  const auto count = static_cast<long>(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < count; ++i) {
    std::array<std::size_t, kMaxNeighbors + 1> idx{};
    std::array<double, kMaxNeighbors + 1> d2{};
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
    const std::size_t found = tree.FindKNearest(p, k, idx.data(), d2.data());
    const double range = std::max((p - sensor_origin).norm(), 1e-9);
    // The first hit is the point itself (distance 0), unless duplicates tie with it.
    const double nearest = found > 1 ? std::sqrt(d2[1]) : INFINITY;
    const double kth = found == k ? std::sqrt(d2[k - 1]) : INFINITY;
    nearest_over_range[static_cast<std::size_t>(i)] = static_cast<float>(nearest / range);
    kth_over_range[static_cast<std::size_t>(i)] = static_cast<float>(kth / range);
  }
  std::vector<float> sorted = nearest_over_range;
  const auto mid = sorted.begin() + static_cast<long>(n / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  mask.angular_spacing_rad = *mid;
  const double limit = radius_factor * mask.angular_spacing_rad;
  if (!std::isfinite(limit) || limit <= 0.0) return mask;
  for (std::size_t i = 0; i < n; ++i) {
    if (kth_over_range[i] > limit) {
      mask.keep[i] = 0;
      ++mask.removed;
    }
  }
  return mask;
}

}  // namespace rovermap::mapper
