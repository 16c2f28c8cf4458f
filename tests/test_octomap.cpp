#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "dem/BatchOcTree.hpp"
#include "dem/OcTreeBytes.hpp"
#include "dem/OctoMapFusion.hpp"
#include "dem/QuietStderr.hpp"
#include "io/IoError.hpp"
#include "io/OctoMapIo.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap {
namespace {

namespace fs = std::filesystem;

// A flat ground z = 0 over [0, 4] × [-2, 2], sampled every 2 cm.
std::vector<Eigen::Vector3d> Ground() {
  std::vector<Eigen::Vector3d> points;
  for (double x = 0.0; x <= 4.0; x += 0.02)
    for (double y = -2.0; y <= 2.0; y += 0.02) points.emplace_back(x, y, 0.0);
  return points;
}

bool Occupied(const octomap::OcTree& tree, double x, double y, double z) {
  const octomap::OcTreeNode* node = tree.search(x, y, z);
  return node != nullptr && tree.isNodeOccupied(node);
}

bool Free(const octomap::OcTree& tree, double x, double y, double z) {
  const octomap::OcTreeNode* node = tree.search(x, y, z);
  return node != nullptr && !tree.isNodeOccupied(node);
}

fs::path TempDir() {
  const fs::path dir = rovermap::testing::ScratchDir();
  fs::create_directories(dir);
  return dir;
}

TEST(OctoMapFusion, GroundOccupiedRaysFree) {
  dem::OctoMapFusion fusion;
  ASSERT_TRUE(fusion.enabled());
  auto points = Ground();
  points.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  const auto stats = fusion.InsertFrame(points, {0.0, 0.0, 1.5});
  EXPECT_EQ(stats.dropped_nonfinite, 1u);
  EXPECT_EQ(stats.inserted, points.size() - 1);
  const octomap::OcTree& tree = *fusion.tree();
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.1);
  EXPECT_TRUE(Occupied(tree, 2.0, 0.5, 0.01));
  EXPECT_TRUE(Occupied(tree, 3.5, -1.5, 0.01));
  // On the ray from the sensor to (2, 0, 0): (1, 0, 0.75), and above the sensor's path.
  EXPECT_TRUE(Free(tree, 1.0, 0.0, 0.8));
  EXPECT_TRUE(Free(tree, 2.0, 0.0, 0.7));
  // Never observed: below the ground, and beyond it.
  EXPECT_EQ(tree.search(2.0, 0.0, -0.5), nullptr);
  EXPECT_EQ(tree.search(8.0, 0.0, 0.05), nullptr);
}

// Ground with a few boulders over [0, 6] × [-3, 3], some points 30–40 m out (beyond the 20 m
// range: only their rays' free part counts), shifted by `frame` so that frames overlap in part.
std::vector<Eigen::Vector3d> RoughFrame(int frame) {
  std::vector<Eigen::Vector3d> points;
  const double dx = 0.37 * frame;
  for (double x = 0.0; x <= 6.0; x += 0.03)
    for (double y = -3.0; y <= 3.0; y += 0.03) {
      const double bump = std::max(0.0, 0.4 - std::hypot(x - 3.0, y - 1.0 + 0.1 * frame));
      points.emplace_back(x + dx, y, 0.2 * std::sin(1.3 * x + frame) + bump);
    }
  for (int k = 0; k < 200; ++k)
    points.emplace_back(dx + 30.0 + 0.05 * k, -5.0 + 0.05 * k, 0.5 + 0.01 * (k % 7));
  return points;
}

// octomap's own insertion as the fusion used it before: insertPointCloud (lazy, discretized),
// then the inner nodes brought up to date.
void InsertLikeOctoMap(octomap::OcTree* tree, const std::vector<Eigen::Vector3d>& points,
                       const Eigen::Vector3d& origin, double max_range) {
  octomap::Pointcloud cloud;
  for (const Eigen::Vector3d& p : points)
    cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                    static_cast<float>(p.z()));
  const octomap::point3d o(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                           static_cast<float>(origin.z()));
  tree->insertPointCloud(cloud, o, max_range, /*lazy_eval=*/true, /*discretize=*/true);
  tree->updateInnerOccupancy();
}

// Node for node (structure, keys, log-odds of leaves and inner nodes), and the bytes of both
// file formats.
void ExpectSameTree(const octomap::OcTree& ours, const octomap::OcTree& theirs, int frame) {
  EXPECT_EQ(ours.size(), theirs.size()) << "after frame " << frame;
  EXPECT_EQ(ours.getNumLeafNodes(), theirs.getNumLeafNodes()) << "after frame " << frame;
  EXPECT_TRUE(ours == theirs) << "after frame " << frame;
  EXPECT_EQ(dem::BinaryOcTreeBytes(ours), dem::BinaryOcTreeBytes(theirs)) << frame;
  EXPECT_EQ(dem::FullOcTreeBytes(ours), dem::FullOcTreeBytes(theirs)) << frame;
}

// The batch insertion gives OctoMap's insertPointCloud's tree, to the node and the byte: over
// 24 frames from moving origins (free space carved again and again until it clamps, endpoints
// re-observed until they clamp, an occupied voxel later seen through), with the 20 m range, with
// none, and with a short one.
TEST(BatchOcTree, SameTreeAsOctoMapsInsertion) {
  for (const double max_range_m : {20.0, 0.0, 3.0}) {
    dem::OctoMapOptions options;
    options.max_range_m = max_range_m;
    dem::OctoMapFusion fusion(options);
    octomap::OcTree reference(options.resolution_m);
    reference.setProbHit(options.prob_hit);
    reference.setProbMiss(options.prob_miss);
    std::size_t free_voxels = 0;
    for (int frame = 0; frame < 24; ++frame) {
      const auto points = RoughFrame(frame % 6);
      const Eigen::Vector3d origin(0.37 * (frame % 6) - 0.5, 0.1 * (frame % 4), 1.4);
      const auto stats = fusion.InsertFrame(points, origin);
      free_voxels += stats.free_voxels;
      EXPECT_GT(stats.occupied_voxels, 800u);  // 896 or more with the 3 m range
      InsertLikeOctoMap(&reference, points, origin, max_range_m > 0.0 ? max_range_m : -1.0);
      if (frame % 6 == 0 || frame == 23) ExpectSameTree(*fusion.tree(), reference, frame);
    }
    EXPECT_GT(free_voxels, 100000u) << max_range_m;
    // Clamped at both ends, so the early abort was exercised.
    std::size_t clamped_free = 0, clamped_occupied = 0;
    for (auto it = reference.begin_leafs(); it != reference.end_leafs(); ++it) {
      clamped_free += it->getLogOdds() <= reference.getClampingThresMinLog();
      clamped_occupied += it->getLogOdds() >= reference.getClampingThresMaxLog();
    }
    EXPECT_GT(clamped_free, 1000u) << max_range_m;
    EXPECT_GT(clamped_occupied, 100u) << max_range_m;
  }
}

// Pruned nodes (OctoMap's own trees have them after prune() or a non-lazy insertion; a state
// restored from such a file would): a clamped one is left alone by an update that cannot change
// it, and expanded by one that can, as updateNode does.
TEST(BatchOcTree, PrunedNodesAsOctoMapTreatsThem) {
  octomap::OcTree reference(0.1);
  for (int frame = 0; frame < 12; ++frame)
    InsertLikeOctoMap(&reference, RoughFrame(0), {-0.5, 0.0, 1.4}, 20.0);
  reference.prune();
  std::stringstream bytes;
  ASSERT_TRUE(reference.write(bytes));
  const std::size_t pruned_size = reference.size();
  dem::BatchOcTree ours(0.1);
  {
    std::unique_ptr<octomap::AbstractOcTree> read;
    {
      const dem::QuietStderr quiet;
      read.reset(octomap::AbstractOcTree::read(bytes));
    }
    ours.swapContent(*dynamic_cast<octomap::OcTree*>(read.get()));
  }
  ASSERT_TRUE(ours == reference);
  for (int frame = 1; frame < 6; ++frame) {
    const auto points = RoughFrame(frame);
    const Eigen::Vector3d origin(0.37 * frame, 0.0, 1.4);
    std::vector<octomap::point3d> cloud;
    for (const Eigen::Vector3d& p : points)
      cloud.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                         static_cast<float>(p.z()));
    ours.InsertDiscretized(cloud, octomap::point3d(origin.x(), origin.y(), origin.z()), 20.0);
    InsertLikeOctoMap(&reference, points, origin, 20.0);
    ExpectSameTree(ours, reference, frame);
  }
  EXPECT_GT(reference.size(), pruned_size);  // some pruned nodes were expanded
}

// Points outside the tree's key range are dropped (octomap's coordToKey would overflow), the
// rest inserted as usual.
TEST(BatchOcTree, PointsBeyondTheKeysDropped) {
  dem::OctoMapFusion fusion;
  auto points = Ground();
  points.emplace_back(1e7, 0.0, 0.0);
  points.emplace_back(0.0, -4000.0, 0.0);
  const auto stats = fusion.InsertFrame(points, {0.0, 0.0, 1.5});
  EXPECT_EQ(stats.dropped_out_of_bounds, 2u);
  EXPECT_EQ(stats.inserted, points.size() - 2);
  EXPECT_TRUE(Occupied(*fusion.tree(), 2.0, 0.5, 0.01));
}

// Save and Restore: the restored fusion goes on as the saved one; a state from an earlier
// version (inner nodes stale, flagged in the second word) gets its inner nodes brought up to
// date, which the batch walk relies on.
TEST(OctoMapFusion, RestoreGoesOnIdenticallyAndMendsStaleInnerNodes) {
  dem::OctoMapFusion saved;
  saved.InsertFrame(RoughFrame(0), {-0.5, 0.0, 1.4});
  std::stringstream state;
  ASSERT_TRUE(saved.Save(state));
  dem::OctoMapFusion restored;
  restored.Restore(state);
  saved.InsertFrame(RoughFrame(1), {0.0, 0.0, 1.4});
  restored.InsertFrame(RoughFrame(1), {0.0, 0.0, 1.4});
  EXPECT_TRUE(*restored.tree() == *saved.tree());

  // An earlier version's state: insertPointCloud without the inner update, schedule {7, stale}.
  octomap::OcTree stale(0.1);
  {
    octomap::Pointcloud cloud;
    for (const Eigen::Vector3d& p : RoughFrame(0))
      cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                      static_cast<float>(p.z()));
    stale.insertPointCloud(cloud, octomap::point3d(-0.5f, 0.0f, 1.4f), 20.0, true, true);
  }
  std::stringstream old_state;
  const std::int32_t schedule[2] = {7, 1};
  old_state.write(reinterpret_cast<const char*>(schedule), sizeof(schedule));
  old_state << dem::FullOcTreeBytes(stale);
  dem::OctoMapFusion from_old;
  from_old.Restore(old_state);
  stale.updateInnerOccupancy();
  EXPECT_TRUE(*from_old.tree() == stale);
  from_old.InsertFrame(RoughFrame(1), {0.0, 0.0, 1.4});
  EXPECT_TRUE(*from_old.tree() == *saved.tree());
}

TEST(OctoMapFusion, MaxRangeTruncatesRays) {
  dem::OctoMapOptions options;
  options.max_range_m = 2.0;
  dem::OctoMapFusion fusion(options);
  fusion.InsertFrame(Ground(), {0.0, 0.0, 1.0});
  const octomap::OcTree& tree = *fusion.tree();
  EXPECT_TRUE(Occupied(tree, 1.0, 0.0, 0.01));   // 1.4 m away
  EXPECT_FALSE(Occupied(tree, 3.5, 0.0, 0.01));  // 3.6 m away: only free space to 2 m
}

TEST(OctoMapFusion, DisabledDoesNothing) {
  dem::OctoMapOptions options;
  options.enabled = false;
  dem::OctoMapFusion fusion(options);
  EXPECT_FALSE(fusion.enabled());
  EXPECT_EQ(fusion.tree(), nullptr);
  EXPECT_TRUE(fusion.InsertFrame(Ground(), {0, 0, 1}).skipped);
}

TEST(OctoMapFusion, RejectsBadOptions) {
  dem::OctoMapOptions options;
  options.resolution_m = 0.0;
  EXPECT_THROW(dem::OctoMapFusion{options}, std::invalid_argument);
  options = {};
  options.prob_hit = 0.4;
  EXPECT_THROW(dem::OctoMapFusion{options}, std::invalid_argument);
}

TEST(OctoMapIo, BinaryAndFullTreesReadBack) {
  dem::OctoMapFusion fusion;
  fusion.InsertFrame(Ground(), {0.0, 0.0, 1.5});
  const octomap::OcTree& tree = *fusion.tree();
  for (const char* name : {"map.bt", "map.ot"}) {
    const fs::path path = TempDir() / name;
    fs::remove(path);
    io::WriteOctoMap(path, tree);
    ASSERT_TRUE(fs::exists(path));
    const auto back = io::ReadOctoMap(path);
    ASSERT_NE(back, nullptr);
    EXPECT_DOUBLE_EQ(back->getResolution(), 0.1);
    EXPECT_EQ(back->getNumLeafNodes(), tree.getNumLeafNodes()) << name;
    EXPECT_TRUE(Occupied(*back, 2.0, 0.5, 0.01)) << name;
    EXPECT_TRUE(Free(*back, 1.0, 0.0, 0.8)) << name;
  }
  // The .bt is octomap's own format: octomap reads the file by name too.
  octomap::OcTree direct(0.1);
  EXPECT_TRUE(direct.readBinary((TempDir() / "map.bt").string()));
  EXPECT_TRUE(Occupied(direct, 2.0, 0.5, 0.01));
  // No temporaries left.
  for (const auto& entry : fs::directory_iterator(TempDir())) {
    EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << entry.path();
  }
}

// Our writers give OctoMap's own bytes, for both formats, on trees of several shapes (with
// inner nodes stale and up to date, occupied and free leaves, pruned parts) and an empty one.
TEST(OcTreeBytes, SameBytesAsOctoMapsWriters) {
  dem::OctoMapFusion fusion;
  for (int frame = 0; frame <= 3; ++frame) {
    if (frame > 0) fusion.InsertFrame(Ground(), {0.5 * frame, 0.2 * frame, 1.0 + 0.3 * frame});
    const octomap::OcTree& tree = *fusion.tree();
    std::ostringstream full, binary;
    ASSERT_TRUE(tree.write(full));
    {
      const dem::QuietStderr quiet;
      ASSERT_TRUE(tree.writeBinaryConst(binary));
    }
    EXPECT_EQ(dem::FullOcTreeBytes(tree), full.str()) << frame << " frames";
    EXPECT_EQ(dem::BinaryOcTreeBytes(tree), binary.str()) << frame << " frames";
  }
  // Stale inner nodes (the fusion updates them only when read): the .ot keeps them as they are.
  octomap::OcTree raw(0.05);
  for (int i = 0; i < 200; ++i) raw.updateNode(0.01 * i, 0.02 * (i % 17), 0.3, i % 3 != 0, true);
  std::ostringstream full;
  ASSERT_TRUE(raw.write(full));
  EXPECT_EQ(dem::FullOcTreeBytes(raw), full.str());
}

// The leaf count read from the written bytes is the tree's own, for both formats: after one
// frame, after several from other origins (deeper, partly pruned trees), and for an empty tree.
TEST(OctoMapIo, LeavesCountedInTheWrittenBytes) {
  dem::OctoMapFusion fusion;
  for (int frame = 0; frame <= 3; ++frame) {
    if (frame > 0) fusion.InsertFrame(Ground(), {0.4 * frame, -0.3 * frame, 1.5});
    const octomap::OcTree& tree = *fusion.tree();
    for (const char* name : {"map.bt", "map.ot"}) {
      const io::OctoMapFileInfo info = io::WriteOctoMap(TempDir() / name, tree);
      EXPECT_EQ(info.leaves, tree.getNumLeafNodes()) << name << " after " << frame << " frames";
      EXPECT_EQ(info.bytes, fs::file_size(TempDir() / name)) << name;
    }
    if (frame > 0) {
      EXPECT_GT(tree.getNumLeafNodes(), 100u);
    }
  }
  EXPECT_THROW(io::CountSerialisedLeaves("no data line", true), io::IoError);
}

TEST(OctoMapIo, Errors) {
  dem::OctoMapFusion fusion;
  EXPECT_THROW(io::WriteOctoMap(TempDir() / "map.txt", *fusion.tree()), io::IoError);
  EXPECT_THROW(io::WriteOctoMap(TempDir() / "missing_dir" / "map.bt", *fusion.tree()), io::IoError);
  const fs::path junk = TempDir() / "junk.bt";
  { std::ofstream(junk) << "not an octree"; }
  EXPECT_THROW(io::ReadOctoMap(junk), io::IoError);
  EXPECT_THROW(io::ReadOctoMap(TempDir() / "absent.bt"), io::IoError);
}

}  // namespace
}  // namespace rovermap
