// BatchOcTree::MovedCopy: the tree moved block by block with its frames' corrections (what
// `serve` publishes once a pose graph has moved its trajectory; docs/serve.md, "The pose graph").
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "dem/BatchOcTree.hpp"
#include "dem/Morton.hpp"

namespace rovermap::dem {
namespace {

using namespace morton;  // NOLINT: the key arithmetic of BatchOcTree.cpp

// A pruned leaf above this depth (a cube of more than 64³ voxels) is left out of the copy: this
// tree never prunes, and a restored one prunes free space near the sensor at most.
constexpr unsigned kShallowestExpanded = 10;

// Ascending LSD radix sort by the 48-bit code, four 12-bit digits (a comparison sort of KITTI's
// 5.5 M voxels took about a third of the move).
void SortByCode(std::vector<std::pair<std::uint64_t, float>>* v) {
  constexpr unsigned kBits = 12, kBuckets = 1U << kBits;
  std::vector<std::pair<std::uint64_t, float>> scratch(v->size());
  std::vector<std::size_t> start(kBuckets);
  for (unsigned shift = 0; shift < 48; shift += kBits) {
    std::fill(start.begin(), start.end(), 0);
    for (const auto& x : *v) ++start[(x.first >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& s : start) sum += std::exchange(s, sum);
    for (const auto& x : *v) scratch[start[(x.first >> shift) & (kBuckets - 1)]++] = x;
    v->swap(scratch);
  }
}

}  // namespace

BatchOcTree::FrameCorrection BatchOcTree::CorrectionsByFrame(
    const std::vector<std::optional<Eigen::Isometry3d>>& corrections) {
  return [&corrections](std::uint32_t frame) -> const Eigen::Isometry3d* {
    return frame < corrections.size() && corrections[frame] ? &*corrections[frame] : nullptr;
  };
}

std::unique_ptr<BatchOcTree> BatchOcTree::MovedCopy(const FrameCorrection& correction,
                                                    OcTreeMoveStats* stats) const {
  return Build(MoveVoxels(correction), stats);
}

MovedVoxels BatchOcTree::MoveVoxels(const FrameCorrection& correction) const {
  MovedVoxels out;
  out.resolution = resolution;
  out.prob_hit = getProbHit();
  out.prob_miss = getProbMiss();
  out.clamping_min = getClampingThresMin();
  out.clamping_max = getClampingThresMax();
  out.occupancy = getOccupancyThres();
  if (root == nullptr || !nodeHasChildren(root)) return out;  // empty (never a pruned root)
  OcTreeMoveStats& st = out.stats;
  std::vector<std::pair<std::uint64_t, float>>& leaves = out.leaves;
  leaves.reserve(getNumLeafNodes());
  std::vector<float>& shifts = out.shifts;
  // The block being read and its correction: a block's voxels come together (Morton order).
  std::uint64_t block = std::numeric_limits<std::uint64_t>::max();
  const Eigen::Isometry3d* T = nullptr;
  const auto centre = [this](std::uint64_t code) {
    const octomap::OcTreeKey key = FromMorton(code);
    return Eigen::Vector3d(keyToCoord(key[0]), keyToCoord(key[1]), keyToCoord(key[2]));
  };
  const auto add = [&](std::uint64_t code, float log_odds) {
    ++st.leaves_in;
    if ((code >> (3 * kBlockLevels)) != block) {
      block = code >> (3 * kBlockLevels);
      const auto tag = block_frames_.find(block);
      T = tag == block_frames_.end() ? nullptr : correction(tag->second & ~kOccupiedTag);
      if (T != nullptr) {
        // The block's centre: its first voxel's, 3.5 voxels in on each axis.
        const Eigen::Vector3d c =
            centre(block << (3 * kBlockLevels)) + Eigen::Vector3d::Constant(3.5 * resolution);
        shifts.push_back(static_cast<float>(((*T) * c - c).head<2>().norm()));
      }
    }
    if (T == nullptr) {
      leaves.emplace_back(code, log_odds);
      return;
    }
    ++st.leaves_moved;
    const Eigen::Vector3d p = (*T) * centre(code);
    octomap::OcTreeKey key;
    if (!coordToKeyChecked(p.x(), key[0]) || !coordToKeyChecked(p.y(), key[1]) ||
        !coordToKeyChecked(p.z(), key[2])) {
      ++st.dropped;
      return;
    }
    leaves.emplace_back(Morton(key), log_odds);
  };
  // Depth first, so that the codes come in ascending order.
  std::array<const octomap::OcTreeNode*, kDepth + 1> stack_node{};
  std::array<std::uint64_t, kDepth + 1> stack_code{};
  std::array<unsigned, kDepth + 1> next_child{};
  stack_node[0] = root;
  unsigned depth = 0;
  while (true) {
    const octomap::OcTreeNode* node = stack_node[depth];
    if (!nodeHasChildren(node) && next_child[depth] == 0) {
      const float value = node->getLogOdds();
      if (depth == kDepth) {
        add(stack_code[depth], value);
      } else if (depth >= kShallowestExpanded) {
        const std::uint64_t count = std::uint64_t{1} << (3 * (kDepth - depth));
        for (std::uint64_t k = 0; k < count; ++k) add(stack_code[depth] + k, value);
      } else {
        st.dropped += std::size_t{1} << (3 * (kDepth - depth));
      }
      next_child[depth] = 8;
    }
    while (next_child[depth] < 8 && !nodeChildExists(node, next_child[depth])) ++next_child[depth];
    if (next_child[depth] < 8) {
      const unsigned child = next_child[depth]++;
      stack_node[depth + 1] = getNodeChild(node, child);
      stack_code[depth + 1] = stack_code[depth] | std::uint64_t{child}
                                                      << (3 * (kDepth - 1 - depth));
      next_child[depth + 1] = 0;
      ++depth;
      continue;
    }
    if (depth == 0) break;
    --depth;
  }

  return out;
}

std::unique_ptr<BatchOcTree> BatchOcTree::Build(MovedVoxels voxels, OcTreeMoveStats* stats) {
  auto moved = std::make_unique<BatchOcTree>(voxels.resolution);
  moved->setProbHit(voxels.prob_hit);
  moved->setProbMiss(voxels.prob_miss);
  moved->setClampingThresMin(voxels.clamping_min);
  moved->setClampingThresMax(voxels.clamping_max);
  moved->setOccupancyThres(voxels.occupancy);
  OcTreeMoveStats& st = voxels.stats;
  std::vector<std::pair<std::uint64_t, float>>& leaves = voxels.leaves;
  SortByCode(&leaves);
  // Two voxels in one: the higher log-odds (occupied over free).
  std::size_t out = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (out > 0 && leaves[out - 1].first == leaves[i].first) {
      leaves[out - 1].second = std::max(leaves[out - 1].second, leaves[i].second);
    } else {
      leaves[out++] = leaves[i];
    }
  }
  leaves.resize(out);
  st.leaves_out = leaves.size();
  std::vector<float>& shifts = voxels.shifts;
  if (!shifts.empty()) {
    const auto mid = shifts.begin() + static_cast<long>(shifts.size() / 2);
    std::nth_element(shifts.begin(), mid, shifts.end());
    st.median_shift_m = *mid;
    st.max_shift_m = *std::max_element(shifts.begin(), shifts.end());
  }
  moved->SetLeaves(leaves);
  if (stats != nullptr) *stats = st;
  return moved;
}

// Apply's walk without the updates' arithmetic: each leaf is created along the path shared with
// the previous one and set, each inner node set to its children's maximum once the walk leaves it.
void BatchOcTree::SetLeaves(const std::vector<std::pair<std::uint64_t, float>>& leaves) {
  if (leaves.empty()) return;
  std::array<octomap::OcTreeNode*, kDepth + 1> path{};
  const auto close_to = [this, &path](unsigned end, unsigned depth) {
    for (unsigned d = end; d-- > depth + 1;)
      if (nodeHasChildren(path[d])) path[d]->updateOccupancyChildren();
  };
  if (root == nullptr) {
    root = new octomap::OcTreeNode();
    ++tree_size;
  }
  path[0] = root;
  std::uint64_t previous = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const std::uint64_t code = leaves[i].first;
    unsigned depth = 0;
    if (i > 0) {
      depth = CommonDepth(code, previous);
      close_to(kDepth + 1, depth);
    }
    previous = code;
    octomap::OcTreeNode* node = path[depth];
    for (; depth < kDepth; ++depth) {
      const unsigned child = ChildIndex(code, depth);
      if (!nodeChildExists(node, child)) createNodeChild(node, child);
      node = getNodeChild(node, child);
      path[depth + 1] = node;
    }
    node->setLogOdds(leaves[i].second);
  }
  close_to(kDepth + 1, 0);
  if (nodeHasChildren(root)) root->updateOccupancyChildren();
}

}  // namespace rovermap::dem
