#include "dem/BatchOcTree.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "dem/Morton.hpp"

namespace rovermap::dem {
namespace {

using morton::ChildIndex;
using morton::CommonDepth;
using morton::FromMorton;
using morton::kDepth;
using morton::Morton;

// Ascending LSD radix sort of 48-bit codes, four 12-bit digits.
void RadixSort48(std::vector<std::uint64_t>* v, std::vector<std::uint64_t>* scratch) {
  constexpr unsigned kBits = 12, kBuckets = 1U << kBits;
  scratch->resize(v->size());
  std::array<std::size_t, kBuckets> start{};
  for (unsigned shift = 0; shift < 48; shift += kBits) {
    start.fill(0);
    for (const std::uint64_t x : *v) ++start[(x >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& s : start) sum += std::exchange(s, sum);
    for (const std::uint64_t x : *v) (*scratch)[start[(x >> shift) & (kBuckets - 1)]++] = x;
    v->swap(*scratch);
  }
}

void SortUnique(std::vector<std::uint64_t>* v, std::vector<std::uint64_t>* scratch) {
  RadixSort48(v, scratch);
  v->erase(std::unique(v->begin(), v->end()), v->end());
}

constexpr unsigned kRecentBits = 16;  // 64k entries, 512 kB: rays from one origin overlap

}  // namespace

BatchOcTree::BatchOcTree(double resolution) : octomap::OcTree(resolution) {}

// OcTreeBaseImpl::computeRayKeys (Amanatides & Woo's 3-D DDA), expression for expression so that
// the same floats pick the same voxels, with each key's Morton code stepped along with it and
// handed to the free set at once: no key ray stored and read back, no code spread from a key
// per voxel (the two were a visible share of a KITTI replay's CPU time; docs/benchmarks.md,
// "Figures behind the frame pipeline's code"). The tests compare the tree with OctoMap's
// insertPointCloud byte for byte.
void BatchOcTree::CastRay(const octomap::point3d& origin, const octomap::point3d& end) {
  octomap::OcTreeKey key_origin, key_end;
  // computeRayKeys would print and fail on either.
  if (!coordToKeyChecked(origin, key_origin) || !coordToKeyChecked(end, key_end)) return;
  if (key_origin == key_end) return;  // the same voxel: no free space

  const auto add = [this](std::uint64_t code) {
    // Most of a ray's voxels near the origin were just added by its neighbours: a lossy
    // filter drops those repeats before the sort, which removes the rest.
    const std::size_t slot = (code * 0x9E3779B97F4A7C15ULL) >> (64 - kRecentBits);
    if (recent_[slot] == code + 1) return;
    recent_[slot] = code + 1;
    free_.push_back(code);
  };
  std::uint64_t code = Morton(key_origin);
  const std::uint64_t code_end = Morton(key_end);
  add(code);

  octomap::point3d direction = (end - origin);
  const float length = static_cast<float>(direction.norm());
  direction /= length;
  int step[3];
  double t_max[3];
  double t_delta[3];
  for (unsigned i = 0; i < 3; ++i) {
    if (direction(i) > 0.0)
      step[i] = 1;
    else if (direction(i) < 0.0)
      step[i] = -1;
    else
      step[i] = 0;
    if (step[i] != 0) {
      double voxel_border = this->keyToCoord(key_origin[i]);
      voxel_border += static_cast<float>(step[i] * this->resolution * 0.5);
      t_max[i] = (voxel_border - origin(i)) / direction(i);
      t_delta[i] = this->resolution / std::fabs(direction(i));
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  // One key coordinate's bits in the code (every third bit from bit `dim`): adding or
  // subtracting its unit there carries through that coordinate's bits alone. The walk's state
  // lives in scalars, not in arrays indexed by the axis, whose store and reload per voxel chained
  // each step to the last (docs/benchmarks.md, "Figures behind the frame pipeline's code").
  constexpr std::uint64_t kMask = 0x249249249249ULL;
  double t0 = t_max[0], t1 = t_max[1], t2 = t_max[2];
  const auto advance = [&code](std::uint64_t mask, std::uint64_t unit, bool up) {
    const std::uint64_t coordinate = code & mask;
    const std::uint64_t stepped =
        up ? ((coordinate | ~mask) + unit) & mask : (coordinate - unit) & mask;
    code = (code & ~mask) | stepped;
  };
  while (true) {
    if (t0 < t1 && t0 < t2) {
      t0 += t_delta[0];
      advance(kMask, 1, step[0] > 0);
    } else if (!(t0 < t1) && t1 < t2) {
      t1 += t_delta[1];
      advance(kMask << 1, 2, step[1] > 0);
    } else {
      t2 += t_delta[2];
      advance(kMask << 2, 4, step[2] > 0);
    }
    if (code == code_end) return;
    // Past the ray's length without meeting the end voxel (rounding): stop, as OctoMap does.
    if (std::min(std::min(t0, t1), t2) > length) return;
    add(code);
  }
}

BatchCounts BatchOcTree::InsertDiscretized(const std::vector<octomap::point3d>& points,
                                           const octomap::point3d& origin, double max_range,
                                           std::uint32_t frame) {
  BatchCounts counts;
  endpoints_.clear();
  free_.clear();
  updates_.clear();
  recent_.assign(std::size_t{1} << kRecentBits, 0);
  for (const octomap::point3d& p : points) {
    octomap::OcTreeKey key;
    if (coordToKeyChecked(p, key))
      endpoints_.push_back(Morton(key));
    else
      ++counts.dropped_out_of_bounds;
  }
  SortUnique(&endpoints_, &scratch_);
  counts.endpoints = endpoints_.size();
  octomap::OcTreeKey origin_key;
  const bool origin_in_bounds = coordToKeyChecked(origin, origin_key);
  // OccupancyOcTreeBase::computeDiscreteUpdate and computeUpdate, expression for expression
  // (the same floats decide the range test and the truncated end).
  std::vector<std::uint64_t>& occupied = scratch_;  // endpoints_ stays sorted: reuse its order
  occupied.clear();
  for (const std::uint64_t code : endpoints_) {
    const octomap::point3d p = keyToCoord(FromMorton(code));
    if (max_range < 0.0 || (p - origin).norm() <= max_range) {
      if (origin_in_bounds) CastRay(origin, p);
      octomap::OcTreeKey key;
      if (coordToKeyChecked(p, key)) occupied.push_back(Morton(key));
    } else if (origin_in_bounds) {
      const octomap::point3d direction = (p - origin).normalized();
      CastRay(origin, origin + direction * static_cast<float>(max_range));
    }
  }
  endpoints_.swap(occupied);  // endpoints_ now holds the occupied voxels
  const auto not_ascending = [](std::uint64_t a, std::uint64_t b) { return a >= b; };
  if (std::adjacent_find(endpoints_.begin(), endpoints_.end(), not_ascending) != endpoints_.end())
    SortUnique(&endpoints_, &scratch_);  // a centre keyed to another voxel (huge coordinates)
  SortUnique(&free_, &scratch_);
  // Merge: an endpoint wins over free space in the same frame.
  updates_.reserve(free_.size() + endpoints_.size());
  auto f = free_.begin();
  for (const std::uint64_t code : endpoints_) {
    for (; f != free_.end() && *f < code; ++f) updates_.push_back(*f << 1);
    if (f != free_.end() && *f == code) ++f;
    updates_.push_back(code << 1 | 1U);
  }
  for (; f != free_.end(); ++f) updates_.push_back(*f << 1);
  counts.occupied_voxels = endpoints_.size();
  counts.free_voxels = updates_.size() - endpoints_.size();
  TagBlocks(frame);
  Apply();
  return counts;
}

// The updates are in ascending order, so a block's come together: one look-up per block.
void BatchOcTree::TagBlocks(std::uint32_t frame) {
  frame &= ~kOccupiedTag;
  std::size_t i = 0;
  while (i < updates_.size()) {
    const std::uint64_t block = (updates_[i] >> 1) >> (3 * kBlockLevels);
    bool occupied = false;
    for (; i < updates_.size() && ((updates_[i] >> 1) >> (3 * kBlockLevels)) == block; ++i)
      occupied = occupied || (updates_[i] & 1U) != 0;
    const auto [tag, added] =
        block_frames_.try_emplace(block, occupied ? frame | kOccupiedTag : frame);
    if (!added && occupied) tag->second = frame | kOccupiedTag;
  }
}

// updateNode(key, occupied, lazy_eval = true) for every update in depth-first order, each
// descent starting from the deepest node shared with the previous key's path; an inner node is
// set to its children's maximum (updateInnerOccupancy) once the walk leaves it.
void BatchOcTree::Apply() {
  if (updates_.empty()) return;
  std::array<octomap::OcTreeNode*, kDepth + 1> path{};
  const auto close_to = [this, &path](unsigned end, unsigned depth) {
    for (unsigned d = end; d-- > depth + 1;)
      if (nodeHasChildren(path[d])) path[d]->updateOccupancyChildren();
  };
  bool root_created = false;
  if (root == nullptr) {
    root = new octomap::OcTreeNode();
    ++tree_size;
    root_created = true;
  }
  path[0] = root;
  unsigned reached = 0;  // depth of the last node on the previous path
  std::uint64_t previous = 0;
  for (std::size_t i = 0; i < updates_.size(); ++i) {
    const std::uint64_t code = updates_[i] >> 1;
    const float log_odds = (updates_[i] & 1U) != 0 ? prob_hit_log : prob_miss_log;
    unsigned depth = 0;
    if (i > 0) {
      depth = std::min(CommonDepth(code, previous), reached);
      close_to(reached + 1, depth);
    }
    previous = code;
    // updateNode's early abort: a leaf, or a pruned node, already clamped this way.
    const auto clamped = [&](const octomap::OcTreeNode* node) {
      return (log_odds >= 0 && node->getLogOdds() >= clamping_thres_max) ||
             (log_odds <= 0 && node->getLogOdds() <= clamping_thres_min);
    };
    octomap::OcTreeNode* node = path[depth];
    bool just_created = i == 0 && root_created;
    bool aborted = false;
    // updateNodeRecurs, iteratively.
    for (; depth < kDepth; ++depth) {
      const unsigned child = ChildIndex(code, depth);
      bool created = false;
      if (!nodeChildExists(node, child)) {
        if (!nodeHasChildren(node) && !just_created) {  // a pruned node
          if (clamped(node)) {
            aborted = true;
            break;
          }
          expandNode(node);
        } else {
          createNodeChild(node, child);
          created = true;
        }
      }
      node = getNodeChild(node, child);
      path[depth + 1] = node;
      just_created = created;
    }
    reached = depth;
    if (!aborted && (just_created || !clamped(node))) updateNodeLogOdds(node, log_odds);
  }
  close_to(reached + 1, 0);
  if (nodeHasChildren(root)) root->updateOccupancyChildren();
}

}  // namespace rovermap::dem
