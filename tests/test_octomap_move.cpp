// dem::BatchOcTree::MovedCopy: the OctoMap moved block by block with each frame's correction
// (what `serve` publishes once a pose graph has moved its trajectory). Property checks against
// transforms that map the voxel grid onto itself exactly (whole-voxel shifts, a quarter turn
// about a voxel corner), the blocks' frame tags, and the tags across a checkpoint.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include "dem/BatchOcTree.hpp"
#include "dem/OcTreeBytes.hpp"
#include "dem/OctoMapFusion.hpp"

namespace rovermap {
namespace {

using Corrections = std::vector<std::optional<Eigen::Isometry3d>>;

// Rough ground around (x0, y0) over 4 × 4 m with a boulder, seen from 1.5 m above its west edge.
std::vector<Eigen::Vector3d> Patch(double x0, double y0, int seed) {
  std::vector<Eigen::Vector3d> points;
  for (double x = 0.0; x <= 4.0; x += 0.03)
    for (double y = -2.0; y <= 2.0; y += 0.03) {
      const double bump = std::max(0.0, 0.5 - std::hypot(x - 2.0, y - 0.3 * seed));
      points.emplace_back(x0 + x, y0 + y, 0.15 * std::sin(1.7 * x + seed) + bump);
    }
  return points;
}

dem::BatchOcTree::FrameCorrection From(const Corrections& c) {
  return dem::BatchOcTree::CorrectionsByFrame(c);
}

// Every leaf's key and log-odds.
std::map<octomap::OcTreeKey, float, bool (*)(const octomap::OcTreeKey&, const octomap::OcTreeKey&)>
Leaves(const octomap::OcTree& tree) {
  const auto less = [](const octomap::OcTreeKey& a, const octomap::OcTreeKey& b) {
    return a[0] != b[0] ? a[0] < b[0] : a[1] != b[1] ? a[1] < b[1] : a[2] < b[2];
  };
  std::map<octomap::OcTreeKey, float,
           bool (*)(const octomap::OcTreeKey&, const octomap::OcTreeKey&)>
      out(less);
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    EXPECT_EQ(it.getDepth(), tree.getTreeDepth());  // never pruned
    out[it.getKey()] = it->getLogOdds();
  }
  return out;
}

dem::OctoMapFusion ThreeFrames() {
  dem::OctoMapFusion fusion;
  fusion.InsertFrame(Patch(0.0, 0.0, 0), {0.0, 0.0, 1.5}, 0);
  fusion.InsertFrame(Patch(2.0, 0.5, 1), {2.0, 0.5, 1.5}, 1);
  fusion.InsertFrame(Patch(4.0, -0.5, 2), {4.0, -0.5, 1.5}, 2);
  return fusion;
}

// No correction, or the identity for every frame: the same tree, byte for byte.
TEST(OctoMapMove, NoCorrectionGivesTheSameTree) {
  const dem::OctoMapFusion fusion = ThreeFrames();
  const octomap::OcTree& tree = *fusion.tree();
  dem::OcTreeMoveStats stats;
  const auto none = fusion.tree()->MovedCopy(From({}), &stats);
  EXPECT_EQ(stats.leaves_moved, 0u);
  EXPECT_EQ(stats.leaves_in, tree.getNumLeafNodes());
  EXPECT_EQ(dem::FullOcTreeBytes(*none), dem::FullOcTreeBytes(tree));
  const Corrections identity(3, Eigen::Isometry3d::Identity());
  const auto same = fusion.tree()->MovedCopy(From(identity), &stats);
  EXPECT_EQ(stats.leaves_moved, stats.leaves_in);
  EXPECT_EQ(stats.leaves_out, stats.leaves_in);
  EXPECT_EQ(stats.max_shift_m, 0.0);
  EXPECT_EQ(dem::FullOcTreeBytes(*same), dem::FullOcTreeBytes(tree));
  EXPECT_EQ(dem::BinaryOcTreeBytes(*same), dem::BinaryOcTreeBytes(tree));
}

// A shift by whole voxels maps the grid onto itself: every voxel lands exactly, log-odds kept.
TEST(OctoMapMove, AWholeVoxelShiftMovesEveryVoxelExactly) {
  const dem::OctoMapFusion fusion = ThreeFrames();
  const double r = fusion.tree()->getResolution();
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = Eigen::Vector3d(7 * r, -3 * r, 2 * r);
  const Corrections c(3, shift);
  dem::OcTreeMoveStats stats;
  const auto moved = fusion.tree()->MovedCopy(From(c), &stats);
  const auto before = Leaves(*fusion.tree());
  const auto after = Leaves(*moved);
  ASSERT_EQ(after.size(), before.size());
  for (const auto& [key, value] : before) {
    const octomap::OcTreeKey to(key[0] + 7, key[1] - 3, key[2] + 2);
    const auto it = after.find(to);
    ASSERT_NE(it, after.end());
    EXPECT_EQ(it->second, value);
  }
  EXPECT_NEAR(stats.median_shift_m, std::hypot(7 * r, 3 * r), 1e-6);  // kept as floats
  // The inner nodes are their children's maximum, as the fusion keeps them.
  octomap::OcTree copy(r);
  copy.swapContent(*moved);
  const std::string bytes = dem::FullOcTreeBytes(copy);
  copy.updateInnerOccupancy();
  EXPECT_EQ(dem::FullOcTreeBytes(copy), bytes);
}

// A quarter turn about the z axis through a voxel corner (the world origin) maps voxel centres
// onto voxel centres: rotations are applied to each voxel, not only to blocks.
TEST(OctoMapMove, AQuarterTurnAboutAVoxelCornerIsAPermutation) {
  const dem::OctoMapFusion fusion = ThreeFrames();
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // exact, not through cos(π/2)
  const Corrections c(3, turn);
  const auto moved = fusion.tree()->MovedCopy(From(c));
  const auto before = Leaves(*fusion.tree());
  const auto after = Leaves(*moved);
  ASSERT_EQ(after.size(), before.size());
  constexpr int kCentre = 32768;  // key of the voxel just above the origin
  for (const auto& [key, value] : before) {
    // (x, y) -> (-y, x) on centres (k - 32768 + 0.5): key x' = 2·32768 - 1 - ky, y' = kx.
    const octomap::OcTreeKey to(static_cast<octomap::key_type>(2 * kCentre - 1 - key[1]), key[0],
                                key[2]);
    const auto it = after.find(to);
    ASSERT_NE(it, after.end());
    EXPECT_EQ(it->second, value);
  }
}

// Each block follows its own frame: the last that marked it occupied, else the first that
// carved it. Three patches 20 m apart, frame 1's alone moved by a metre: its voxels move by ten,
// the others' stay. Frame 3 sees frame 1's ground again: that ground's surface now follows frame
// 3 and stays, while the free space only frame 1 carved still moves.
TEST(OctoMapMove, EachBlockFollowsTheLastFrameThatSawItsSurface) {
  dem::OctoMapFusion fusion;
  fusion.InsertFrame(Patch(-20.0, 0.0, 0), {-20.0, 0.0, 1.5}, 0);
  fusion.InsertFrame(Patch(20.0, 0.0, 1), {20.0, 0.0, 1.5}, 1);
  fusion.InsertFrame(Patch(40.0, 0.0, 2), {40.0, 0.0, 1.5}, 2);
  Eigen::Isometry3d one_metre = Eigen::Isometry3d::Identity();
  one_metre.translation().x() = 1.0;  // ten voxels
  Corrections c(4);
  c[1] = one_metre;
  dem::OcTreeMoveStats stats;
  const auto moved = fusion.tree()->MovedCopy(From(c), &stats);
  const octomap::OcTree& tree = *fusion.tree();
  const auto before = Leaves(tree);
  const auto after = Leaves(*moved);
  ASSERT_EQ(after.size(), before.size());
  std::size_t of_frame_1 = 0;
  for (const auto& [key, value] : before) {
    const double x = tree.keyToCoord(key[0]);
    const bool frame_1 = x > 10.0 && x < 30.0;
    of_frame_1 += frame_1;
    const octomap::OcTreeKey to(static_cast<octomap::key_type>(key[0] + (frame_1 ? 10 : 0)), key[1],
                                key[2]);
    const auto it = after.find(to);
    ASSERT_NE(it, after.end()) << x;
    EXPECT_EQ(it->second, value);
  }
  EXPECT_EQ(stats.leaves_moved, of_frame_1);
  EXPECT_NEAR(stats.max_shift_m, 1.0, 1e-6);

  fusion.InsertFrame(Patch(20.0, 0.0, 1), {20.0, 0.0, 1.5}, 3);
  const auto again = fusion.tree()->MovedCopy(From(c), &stats);
  std::size_t surface = 0, stayed = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (it.getX() < 10.0 || it.getX() > 30.0 || !tree.isNodeOccupied(*it)) continue;
    ++surface;
    const octomap::OcTreeNode* n = again->search(it.getKey());
    stayed += n != nullptr && again->isNodeOccupied(n);
  }
  ASSERT_GT(surface, 1000u);
  EXPECT_EQ(stayed, surface);
  EXPECT_GT(stats.leaves_moved, 0u);  // frame 1's free space above the ground
}

// The tags are part of the fusion's state: a restored fusion moves as the saved one; a state
// saved before the tags were kept restores with none, and nothing of it moves.
TEST(OctoMapMove, TagsAreKeptAcrossACheckpoint) {
  const dem::OctoMapFusion saved = ThreeFrames();
  std::stringstream state;
  ASSERT_TRUE(saved.Save(state));
  dem::OctoMapFusion restored;
  restored.Restore(state);
  EXPECT_EQ(restored.tree()->block_frames(), saved.tree()->block_frames());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.33, -0.21, 0.05);
  Corrections c(3);
  c[0] = T;
  c[2] = T.inverse();
  EXPECT_EQ(dem::FullOcTreeBytes(*restored.tree()->MovedCopy(From(c))),
            dem::FullOcTreeBytes(*saved.tree()->MovedCopy(From(c))));

  std::stringstream old_state;
  const std::int32_t schedule[2] = {0, 0};
  old_state.write(reinterpret_cast<const char*>(schedule), sizeof(schedule));
  old_state << dem::FullOcTreeBytes(*saved.tree());
  dem::OctoMapFusion from_old;
  from_old.Restore(old_state);
  EXPECT_TRUE(from_old.tree()->block_frames().empty());
  dem::OcTreeMoveStats stats;
  EXPECT_EQ(dem::FullOcTreeBytes(*from_old.tree()->MovedCopy(From(c), &stats)),
            dem::FullOcTreeBytes(*saved.tree()));
  EXPECT_EQ(stats.leaves_moved, 0u);

  // A state cut inside its tags is refused.
  std::stringstream full;
  ASSERT_TRUE(saved.Save(full));
  std::stringstream truncated(full.str().substr(0, full.str().size() - 6));
  dem::OctoMapFusion broken;
  EXPECT_THROW(broken.Restore(truncated), std::runtime_error);
}

// A small rotation (5°) leaves few voxels without a source (nearest-voxel forward mapping)
// and keeps every occupied voxel near where its surface went.
TEST(OctoMapMove, ASmallTurnKeepsNearlyEveryVoxel) {
  const dem::OctoMapFusion fusion = ThreeFrames();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.123, 0.456, 0.0);
  const Corrections c(3, T);
  dem::OcTreeMoveStats stats;
  const auto moved = fusion.tree()->MovedCopy(From(c), &stats);
  EXPECT_EQ(stats.dropped, 0u);
  EXPECT_GT(static_cast<double>(stats.leaves_out), 0.97 * static_cast<double>(stats.leaves_in));
  std::size_t occupied = 0, landed = 0;
  const octomap::OcTree& tree = *fusion.tree();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    ++occupied;
    const Eigen::Vector3d p = T * Eigen::Vector3d(it.getX(), it.getY(), it.getZ());
    const octomap::OcTreeNode* n = moved->search(p.x(), p.y(), p.z());
    landed += n != nullptr && moved->isNodeOccupied(n);
  }
  ASSERT_GT(occupied, 1000u);
  EXPECT_EQ(landed, occupied);
}

}  // namespace
}  // namespace rovermap
