// What the matcher registers on stereo frames (MapperOptions::registration_cell_px): range-aware
// voxels of the frame's points, with the frame's own spacing as Zhang's D, while the DEM and the
// OctoMap still take every point; and the stereo's pixel spacing against a k-d tree's.
#include <gtest/gtest.h>

#include <filesystem>

#include "io/Sequence.hpp"
#include "mapper/FrameLoader.hpp"
#include "mapper/Mapper.hpp"
#include "registration/CloudGeometry.hpp"
#include "registration/KdTree.hpp"
#include "tests/support/PipelineDefaults.hpp"

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

const fs::path kData = ROVERMAP_DATASETS_DIR;

mapper::PipelineOptions WithCells(double cell_px) {
  mapper::PipelineOptions o = rovermap::testing::PipelineDefaultsWithoutOctoMap();
  o.mapper.registration_cell_px = cell_px;
  return o;
}

io::Frame FirstFrame(io::SequenceReader* reader) {
  io::Frame frame;
  EXPECT_TRUE(reader->Next(&frame));
  return frame;
}

}  // namespace

TEST(RegistrationCloud, StereoFramesRegisterVoxelsAndFuseEveryPoint) {
  io::SequenceReader reader(kData / "kitti_stereo51");
  const io::Frame frame = FirstFrame(&reader);
  const mapper::Mapper merged(reader.info(), WithCells(4.0));
  const mapper::Mapper every(reader.info(), WithCells(0.0));
  const mapper::PreparedFrame a = merged.Prepare(frame);
  const mapper::PreparedFrame b = every.Prepare(frame);
  ASSERT_TRUE(a.loaded.ok);
  ASSERT_TRUE(b.loaded.ok);
  // The DEM gets the same points and the same outlier mask either way.
  ASSERT_EQ(a.Fused().size(), b.Fused().size());
  EXPECT_EQ(a.Fused().points, b.Fused().points);
  EXPECT_EQ(a.isolated.keep, b.isolated.keep);
  EXPECT_GT(a.isolated.removed, 0u);
  // The matcher gets a fraction of them (a KITTI frame: 260 000 points), without the isolated.
  EXPECT_EQ(b.source->cloud().size(), b.Fused().size());
  EXPECT_LT(a.source->cloud().size(), a.Fused().size() / 2);
  EXPECT_GT(a.source->cloud().size(), a.Fused().size() / 20);
  EXPECT_TRUE(a.source->cloud().HasNormals());
  EXPECT_TRUE(a.source->cloud().HasCovariances());
  // Zhang's D: the frame's spacing, not the voxels'.
  EXPECT_GT(a.loaded.spacing_m, 0.0);
  EXPECT_EQ(a.source->spacing(), a.loaded.spacing_m);
  EXPECT_NEAR(a.source->spacing(), b.source->spacing(), 0.15 * b.source->spacing());
}

TEST(RegistrationCloud, CloudFramesRegisterEveryPoint) {
  io::SequenceReader reader(kData / "sim_tiny_cloud");
  const io::Frame frame = FirstFrame(&reader);
  const mapper::Mapper m(reader.info(), WithCells(4.0));
  const mapper::PreparedFrame p = m.Prepare(frame);
  ASSERT_TRUE(p.loaded.ok);
  EXPECT_EQ(p.source->cloud().size(), p.Fused().size());
  EXPECT_EQ(&p.source->cloud(), &p.Fused());
}

TEST(RegistrationCloud, PixelSpacingIsTheTreesSpacing) {
  for (const char* name : {"kitti_stereo51", "sim_tiny_stereo", "rover_devon_island"}) {
    SCOPED_TRACE(name);
    io::SequenceReader reader(kData / name);
    const io::Frame frame = FirstFrame(&reader);
    const mapper::SensorSetup setup = mapper::ResolveSensor(reader.info(), stereo::StereoOptions{},
                                                            dem::ElevationMapOptions{}, false);
    const mapper::LoadedFrame loaded = mapper::LoadFrame(frame, setup, 100);
    ASSERT_TRUE(loaded.ok) << loaded.reason;
    const registration::KdTree tree(loaded.cloud.points);
    const double spacing = registration::MedianNeighborSpacing(loaded.cloud.points, tree);
    EXPECT_NEAR(loaded.spacing_m, spacing, 0.15 * spacing);
  }
}

TEST(RegistrationCloud, MergedVoxelsRegisterAsWellAsEveryPoint) {
  // The bundled simulated stereo against its ground truth: the same statuses and points fused,
  // and no larger error, from the first pose, than registering every point (measured: 1.5 mm
  // against 3.8 mm at the last frame).
  struct Errors {
    std::vector<mapper::FrameStatus> status;
    std::vector<std::size_t> points;
    double position_m = 0.0, heading_deg = 0.0;  // largest over the frames
  };
  auto run = [](double cell_px) {
    io::SequenceReader reader(kData / "sim_tiny_stereo");
    mapper::Mapper m(reader.info(), WithCells(cell_px));
    io::Frame frame;
    while (reader.Next(&frame)) m.ProcessFrame(frame);
    Errors e;
    const auto& r = m.results();
    for (const mapper::FrameResult& f : r) {
      e.status.push_back(f.status);
      e.points.push_back(f.points);
      const Eigen::Isometry3d truth = r.front().step.T_world_body *
                                      r.front().T_world_body_truth->inverse() *
                                      *f.T_world_body_truth;
      const Eigen::Isometry3d d = f.step.T_world_body.inverse() * truth;
      e.position_m = std::max(e.position_m, d.translation().norm());
      e.heading_deg =
          std::max(e.heading_deg, std::abs(Eigen::AngleAxisd(d.linear()).angle()) * 180.0 / M_PI);
    }
    return e;
  };
  const Errors merged = run(4.0), every = run(0.0);
  EXPECT_EQ(merged.status, every.status);
  EXPECT_EQ(merged.points, every.points);
  EXPECT_LE(merged.position_m, every.position_m + 1e-4);
  EXPECT_LE(merged.heading_deg, every.heading_deg + 0.01);
  EXPECT_LT(merged.position_m, 0.005);
}
