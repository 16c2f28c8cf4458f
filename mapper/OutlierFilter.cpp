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

  // α, the median of nearest distance / range, from an even sample of at most kSample points:
  // a median, it needs no more (a search for every point of the frame was a visible share of a
  // KITTI replay's time, for a figure this sample gives to a fraction of a percent;
  // docs/benchmarks.md, "Figures behind the frame pipeline's code").
  constexpr std::size_t kSample = 16384;
  const std::size_t stride = std::max<std::size_t>(1, n / kSample);
  const std::size_t sampled = (n + stride - 1) / stride;
  std::vector<float> nearest_over_range(sampled);
  const auto sample_count = static_cast<long>(sampled);
#pragma omp parallel for schedule(static)
  for (long s = 0; s < sample_count; ++s) {
    std::array<std::size_t, 2> idx{};
    std::array<double, 2> d2{};
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(s) * stride];
    const std::size_t found = tree.FindKNearest(p, 2, idx.data(), d2.data());
    const double range = std::max((p - sensor_origin).norm(), 1e-9);
    // The first hit is the point itself (distance 0), unless duplicates tie with it.
    const double nearest = found > 1 ? std::sqrt(d2[1]) : INFINITY;
    nearest_over_range[static_cast<std::size_t>(s)] = static_cast<float>(nearest / range);
  }
  const auto mid = nearest_over_range.begin() + static_cast<long>(sampled / 2);
  std::nth_element(nearest_over_range.begin(), mid, nearest_over_range.end());
  mask.angular_spacing_rad = *mid;
  const double limit = radius_factor * mask.angular_spacing_rad;
  if (!std::isfinite(limit) || limit <= 0.0) return mask;

  // Isolated: fewer than min_neighbors others (plus the point itself) within limit · range.
  const std::size_t needed = static_cast<std::size_t>(min_neighbors) + 1;
  const auto count = static_cast<long>(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < count; ++i) {
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
    const double range = std::max((p - sensor_origin).norm(), 1e-9);
    if (tree.CountWithin(p, limit * range, needed) < needed)
      mask.keep[static_cast<std::size_t>(i)] = 0;
  }
  for (const unsigned char k : mask.keep) mask.removed += k == 0;
  return mask;
}

}  // namespace rovermap::mapper
