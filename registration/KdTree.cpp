#include "registration/KdTree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>

namespace rovermap::registration {
namespace {

// nanoflann dataset adaptor over a std::vector<Eigen::Vector3d>.
struct PointsAdaptor {
  const std::vector<Eigen::Vector3d>& points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointsAdaptor>,
                                                 PointsAdaptor, 3, std::size_t>;

// A 1-NN result set whose initial worst distance is the bound: nanoflann prunes every
// branch farther than the best distance so far, so starting at Dmax² prunes from the root.
class BoundedNearestResultSet {
 public:
  explicit BoundedNearestResultSet(double bound_sq) : best_sq_(bound_sq) {}
  bool addPoint(double dist_sq, std::size_t index) {
    if (dist_sq < best_sq_) {
      best_sq_ = dist_sq;
      index_ = index;
      found_ = true;
    }
    return true;
  }
  double worstDist() const { return best_sq_; }
  bool full() const { return found_; }
  std::size_t size() const { return found_ ? 1 : 0; }

  bool found_ = false;
  double best_sq_;
  std::size_t index_ = 0;
};

}  // namespace

struct KdTree::Impl {
  Impl(const std::vector<Eigen::Vector3d>& points, int leaf_size)
      : adaptor{points},
        tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(static_cast<std::size_t>(leaf_size))) {
    if (!points.empty()) tree.buildIndex();
  }
  PointsAdaptor adaptor;
  Tree tree;
};

KdTree::KdTree(const std::vector<Eigen::Vector3d>& points, int leaf_size)
    : impl_(std::make_unique<Impl>(points, leaf_size)) {}

KdTree::~KdTree() = default;

std::size_t KdTree::size() const { return impl_->adaptor.points.size(); }

Neighbor KdTree::FindClosest(const Eigen::Vector3d& query, double max_distance) const {
  return FindClosest(query, max_distance, std::numeric_limits<std::size_t>::max());
}

Neighbor KdTree::FindClosest(const Eigen::Vector3d& query, double max_distance,
                             std::size_t hint) const {
  Neighbor result;
  if (size() == 0 || !(max_distance > 0.0)) return result;
  const double bound_sq = std::isinf(max_distance) ? std::numeric_limits<double>::max()
                                                   : max_distance * max_distance;
  BoundedNearestResultSet set(bound_sq);
  if (hint < size()) set.addPoint((impl_->adaptor.points[hint] - query).squaredNorm(), hint);
  impl_->tree.findNeighbors(set, query.data(), nanoflann::SearchParams());
  if (set.found_) {
    result.found = true;
    result.index = set.index_;
    result.squared_distance = set.best_sq_;
  }
  return result;
}

std::size_t KdTree::FindKNearest(const Eigen::Vector3d& query, std::size_t k,
                                 std::size_t* indices, double* squared_distances) const {
  k = std::min(k, size());
  if (k == 0) return 0;
  nanoflann::KNNResultSet<double, std::size_t, std::size_t> set(k);
  set.init(indices, squared_distances);
  impl_->tree.findNeighbors(set, query.data(), nanoflann::SearchParams());
  return set.size();
}

std::vector<Neighbor> KdTree::FindKNearest(const Eigen::Vector3d& query, std::size_t k) const {
  k = std::min(k, size());
  std::vector<std::size_t> indices(k);
  std::vector<double> dists(k);
  const std::size_t n = FindKNearest(query, k, indices.data(), dists.data());
  std::vector<Neighbor> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = Neighbor{true, indices[i], dists[i]};
  return out;
}

}  // namespace rovermap::registration
