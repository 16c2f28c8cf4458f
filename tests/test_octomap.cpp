#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

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
