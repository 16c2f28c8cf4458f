#include "registration/KdTree.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace rovermap::registration {
namespace {

// A point copied into leaf order: the leaves' points are contiguous in memory, so a leaf
// scan reads one cache-friendly run instead of chasing an index array.
struct Slot {
  double x[3];
  std::size_t index;  // into the caller's points
};

// Inner node of the implicit tree (children of node i are 2i+1 and 2i+2).
struct Node {
  double split = 0.0;
  int dim = 0;
};

// Balanced median splits: a node's point range follows from its parent's, so the whole
// shape is fixed by n and the leaf size (no child pointers, no per-leaf ranges).
std::size_t Mid(std::size_t begin, std::size_t end) { return begin + (end - begin) / 2; }

// Subtrees larger than this are built as parallel tasks; smaller ones are not worth a task.
constexpr std::size_t kParallelBuildPoints = 16384;

}  // namespace

struct KdTree::Impl {
  const std::vector<Eigen::Vector3d>& points;
  std::vector<Slot> slots;
  std::vector<Node> nodes;
  int depth = 0;  // leaves are the nodes at this depth

  Impl(const std::vector<Eigen::Vector3d>& pts, int leaf_size) : points(pts) {
    const std::size_t n = pts.size();
    slots.resize(n);
    for (std::size_t i = 0; i < n; ++i) slots[i] = Slot{{pts[i].x(), pts[i].y(), pts[i].z()}, i};
    const std::size_t leaf = static_cast<std::size_t>(std::max(leaf_size, 1));
    // Smallest depth at which every leaf holds at most `leaf` points.
    while (((n + (std::size_t{1} << depth) - 1) >> depth) > leaf) ++depth;
    nodes.resize((std::size_t{1} << depth) - 1);
    if (n <= kParallelBuildPoints) {
      Build(0, 0, 0, n);
      return;
    }
#pragma omp parallel
#pragma omp single nowait
    Build(0, 0, 0, n);
  }

  void Build(std::size_t node, int level, std::size_t begin, std::size_t end) {
    if (level == depth) return;
    // Split the widest extent at the median (robust for scans: long thin strips).
    double lo[3] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                    std::numeric_limits<double>::max()};
    double hi[3] = {-lo[0], -lo[0], -lo[0]};
    for (std::size_t i = begin; i < end; ++i)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], slots[i].x[d]);
        hi[d] = std::max(hi[d], slots[i].x[d]);
      }
    int dim = 0;
    for (int d = 1; d < 3; ++d)
      if (hi[d] - lo[d] > hi[dim] - lo[dim]) dim = d;
    const std::size_t mid = Mid(begin, end);
    if (mid < end) {
      std::nth_element(slots.begin() + static_cast<long>(begin),
                       slots.begin() + static_cast<long>(mid),
                       slots.begin() + static_cast<long>(end),
                       [dim](const Slot& a, const Slot& b) { return a.x[dim] < b.x[dim]; });
      nodes[node] = Node{slots[mid].x[dim], dim};
    } else {
      nodes[node] = Node{0.0, dim};  // empty range: both children empty
    }
    // Left holds coordinates <= split, right >= split. Parallel on large ranges only.
    if (end - begin > kParallelBuildPoints) {
#pragma omp task
      Build(2 * node + 1, level + 1, begin, mid);
      Build(2 * node + 2, level + 1, mid, end);
#pragma omp taskwait
    } else {
      Build(2 * node + 1, level + 1, begin, mid);
      Build(2 * node + 2, level + 1, mid, end);
    }
  }

  // Nearest-first descent with the incremental distance to the cell (Arya & Mount):
  // `offsets` are the per-axis distances from the query to the current cell, `cell_sq` their
  // squared sum; a subtree is entered only if its cell is closer than the current best.
  template <class Visit, class Worst>
  void Search(const double* q, std::size_t node, int level, std::size_t begin, std::size_t end,
              double cell_sq, double* offsets, Visit& visit, const Worst& worst) const {
    if (level == depth) {
      for (std::size_t i = begin; i < end; ++i) {
        const Slot& s = slots[i];
        const double dx = s.x[0] - q[0], dy = s.x[1] - q[1], dz = s.x[2] - q[2];
        visit(dx * dx + dy * dy + dz * dz, s.index);
      }
      return;
    }
    const Node& nd = nodes[node];
    const std::size_t mid = Mid(begin, end);
    const double diff = q[nd.dim] - nd.split;
    const bool left_first = diff < 0.0;
    if (left_first) {
      Search(q, 2 * node + 1, level + 1, begin, mid, cell_sq, offsets, visit, worst);
    } else {
      Search(q, 2 * node + 2, level + 1, mid, end, cell_sq, offsets, visit, worst);
    }
    const double old = offsets[nd.dim];
    const double far_sq = cell_sq - old * old + diff * diff;
    if (far_sq < worst()) {
      offsets[nd.dim] = diff;
      if (left_first) {
        Search(q, 2 * node + 2, level + 1, mid, end, far_sq, offsets, visit, worst);
      } else {
        Search(q, 2 * node + 1, level + 1, begin, mid, far_sq, offsets, visit, worst);
      }
      offsets[nd.dim] = old;
    }
  }

  template <class Visit, class Worst>
  void Search(const Eigen::Vector3d& query, Visit& visit, const Worst& worst) const {
    double offsets[3] = {0.0, 0.0, 0.0};
    Search(query.data(), 0, 0, 0, slots.size(), 0.0, offsets, visit, worst);
  }
};

KdTree::KdTree(const std::vector<Eigen::Vector3d>& points, int leaf_size)
    : impl_(std::make_unique<Impl>(points, leaf_size)) {}

KdTree::~KdTree() = default;

std::size_t KdTree::size() const { return impl_->slots.size(); }

Neighbor KdTree::FindClosest(const Eigen::Vector3d& query, double max_distance) const {
  return FindClosest(query, max_distance, std::numeric_limits<std::size_t>::max());
}

Neighbor KdTree::FindClosest(const Eigen::Vector3d& query, double max_distance,
                             std::size_t hint) const {
  Neighbor result;
  if (size() == 0 || !(max_distance > 0.0)) return result;
  // Starting at Dmax² prunes from the root (Zhang 1994, §4.1); a hint within the bound
  // tightens it further.
  double best_sq = std::isinf(max_distance) ? std::numeric_limits<double>::infinity()
                                            : max_distance * max_distance;
  auto visit = [&](double d_sq, std::size_t index) {
    if (d_sq < best_sq) {
      best_sq = d_sq;
      result.index = index;
      result.found = true;
    }
  };
  if (hint < size()) visit((impl_->points[hint] - query).squaredNorm(), hint);
  impl_->Search(query, visit, [&] { return best_sq; });
  if (result.found) result.squared_distance = best_sq;
  return result;
}

Neighbor KdTree::FindClosest(const Eigen::Vector3d& query, double max_distance, std::size_t hint,
                             double* others_squared_distance) const {
  Neighbor result;
  const double bound_sq = std::isinf(max_distance) ? std::numeric_limits<double>::infinity()
                                                   : max_distance * max_distance;
  *others_squared_distance = bound_sq;
  if (size() == 0 || !(max_distance > 0.0)) return result;
  double best_sq = bound_sq;
  double& second_sq = *others_squared_distance;
  auto visit = [&](double d_sq, std::size_t index) {
    if (result.found && index == result.index) {
      // The hint met again in its leaf: the same point, perhaps an ulp closer (as above).
      best_sq = std::min(best_sq, d_sq);
      return;
    }
    if (d_sq < best_sq) {
      if (result.found) second_sq = best_sq;
      best_sq = d_sq;
      result.index = index;
      result.found = true;
    } else if (d_sq < second_sq) {
      second_sq = d_sq;
    }
  };
  if (hint < size()) visit((impl_->points[hint] - query).squaredNorm(), hint);
  // Cells beyond the second closest cannot change either answer.
  impl_->Search(query, visit, [&] { return second_sq; });
  if (result.found) result.squared_distance = best_sq;
  return result;
}

std::size_t KdTree::FindKNearest(const Eigen::Vector3d& query, std::size_t k, std::size_t* indices,
                                 double* squared_distances) const {
  k = std::min(k, size());
  if (k == 0) return 0;
  std::size_t count = 0;
  // Insertion into a sorted run: k is small (normals use about 10).
  auto visit = [&](double d_sq, std::size_t index) {
    if (count == k && d_sq >= squared_distances[k - 1]) return;
    std::size_t j = count < k ? count++ : k - 1;
    while (j > 0 && squared_distances[j - 1] > d_sq) {
      squared_distances[j] = squared_distances[j - 1];
      indices[j] = indices[j - 1];
      --j;
    }
    squared_distances[j] = d_sq;
    indices[j] = index;
  };
  auto worst = [&] {
    return count < k ? std::numeric_limits<double>::infinity() : squared_distances[k - 1];
  };
  impl_->Search(query, visit, worst);
  return count;
}

std::size_t KdTree::CountWithin(const Eigen::Vector3d& query, double radius,
                                std::size_t at_most) const {
  if (size() == 0 || at_most == 0 || !(radius >= 0.0)) return 0;
  const double radius_sq = radius * radius;
  std::size_t count = 0;
  auto visit = [&](double d_sq, std::size_t) { count += d_sq <= radius_sq; };
  // Cells farther than the radius are skipped; once enough are found, every cell is.
  auto worst = [&] { return count >= at_most ? -1.0 : std::nextafter(radius_sq, INFINITY); };
  impl_->Search(query, visit, worst);
  return std::min(count, at_most);
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
