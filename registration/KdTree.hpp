#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <vector>

namespace rovermap::registration {

/// Result of a bounded closest-point query.
struct Neighbor {
  bool found = false;             ///< false: no point strictly within the bound ("no match")
  std::size_t index = 0;          ///< index into the indexed points
  double squared_distance = 0.0;  ///< [m^2]
};

/// 3-D k-d tree over a point set, written for the matcher (bench/bench_kdtree compares it
/// with nanoflann): balanced median splits on the widest extent, an implicit node layout,
/// leaves stored contiguously, built in parallel, searched nearest-first with the
/// incremental cell distance.
///
/// The points are copied into leaf order; the caller's vector must still outlive the tree
/// (hints are read from it) and stay unchanged.
class KdTree {
 public:
  /// Builds the tree (O(n log n)). An empty set gives a tree that never matches.
  explicit KdTree(const std::vector<Eigen::Vector3d>& points, int leaf_size = 10);
  ~KdTree();
  KdTree(const KdTree&) = delete;
  KdTree& operator=(const KdTree&) = delete;

  /// Closest point strictly within `max_distance` [m] of `query` (Zhang 1994, §4.1:
  /// the search starts with radius Dmax so whole branches are pruned).
  /// @return found == false if no point lies within the bound.
  Neighbor FindClosest(const Eigen::Vector3d& query, double max_distance) const;

  /// The same result, warm-started from `hint` (an index into the points, e.g. last
  /// iteration's match): if the hint lies within the bound, its distance becomes the initial
  /// bound, which prunes far more of the tree. The result is still the closest point (among
  /// equidistant points the hint may be returned). An out-of-range hint is ignored.
  Neighbor FindClosest(const Eigen::Vector3d& query, double max_distance, std::size_t hint) const;

  /// The same closest point, and a lower bound on the distance of every other point
  /// (`*others_squared_distance` [m²]): the second closest's squared distance, or
  /// max_distance² when no other point lies within the bound. A query point that then moves
  /// by δ keeps the same closest point while its distance to it stays below √others − δ
  /// (triangle inequality), so the caller may skip the next search (QueryMemo in Icp.cpp).
  Neighbor FindClosest(const Eigen::Vector3d& query, double max_distance, std::size_t hint,
                       double* others_squared_distance) const;

  /// The k nearest points (fewer if the set is smaller), closest first.
  std::vector<Neighbor> FindKNearest(const Eigen::Vector3d& query, std::size_t k) const;

  /// The same into caller buffers of at least k entries (no allocation: hot loops).
  /// @return the number found (min(k, size())).
  std::size_t FindKNearest(const Eigen::Vector3d& query, std::size_t k, std::size_t* indices,
                           double* squared_distances) const;

  /// How many points lie within `radius` [m] of `query` (squared distance <= radius²),
  /// counting no further than `at_most`: the search stops once that many are found, so a
  /// dense neighbourhood costs a leaf or two.
  std::size_t CountWithin(const Eigen::Vector3d& query, double radius, std::size_t at_most) const;

  std::size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rovermap::registration
