// service/Checkpoint: a snapshot plus journal restores a Mapper to the very state the
// interrupted one had (poses, DEM cells, OctoMap), a torn journal record is dropped and the
// journal goes on after the last good one, damaged or foreign checkpoints are refused, and a
// FrameResult comes back from its encoding with every field.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "config/Config.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ServeOptions.hpp"
#include "service/Checkpoint.hpp"
#include "tests/support/ScratchDir.hpp"

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

const fs::path kTinyCloud = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_cloud";  // 5 frames

mapper::PipelineOptions Defaults() {
  const config::Config c;
  return {c.mapper, c.registration, c.stereo, c.dem, c.octomap, c.terrain};
}

class CheckpointTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = rovermap::testing::ScratchDir(); }
  void TearDown() override { fs::remove_all(dir_); }

  std::unique_ptr<mapper::Mapper> NewMapper() {
    return std::make_unique<mapper::Mapper>(reader_.info(), Defaults());
  }
  io::Frame Read(std::size_t k) const { return reader_.Read(k); }

  // Every published and unpublished cell, and the OctoMap, must be the same.
  static void ExpectSameState(const mapper::Mapper& a, const mapper::Mapper& b) {
    ASSERT_EQ(a.results().size(), b.results().size());
    for (std::size_t i = 0; i < a.results().size(); ++i) {
      EXPECT_EQ(a.results()[i].step.T_world_body.matrix(),
                b.results()[i].step.T_world_body.matrix());
      EXPECT_EQ(a.results()[i].status, b.results()[i].status);
    }
    ASSERT_EQ(a.chain()->size(), b.chain()->size());
    EXPECT_EQ(a.chain()->path_length_m(), b.chain()->path_length_m());
    const dem::ElevationMap& ma = a.elevation_map();
    const dem::ElevationMap& mb = b.elevation_map();
    EXPECT_EQ(ma.CellCount(), mb.CellCount());
    EXPECT_EQ(ma.PublishedCellCount(), mb.PublishedCellCount());
    std::size_t compared = 0;
    ma.ForEachCell([&](dem::CellIndex cell, const dem::CellValue& v) {
      const auto w = mb.Cell(cell);
      ASSERT_TRUE(w.has_value());
      EXPECT_EQ(v.elevation_m, w->elevation_m);
      EXPECT_EQ(v.variance_m2, w->variance_m2);
      EXPECT_EQ(v.count, w->count);
      ++compared;
    });
    EXPECT_GT(compared, 1000u);
    std::ostringstream ta, tb;
    a.octomap().tree()->writeBinaryConst(ta);
    b.octomap().tree()->writeBinaryConst(tb);
    EXPECT_EQ(ta.str(), tb.str());
  }

  fs::path dir_;
  io::SequenceReader reader_{kTinyCloud};
};

TEST_F(CheckpointTest, SnapshotPlusJournalRestoresTheStateAndGoesOnIdentically) {
  auto straight = NewMapper();
  for (std::size_t k = 0; k < 5; ++k) straight->ProcessFrame(Read(k));

  // Frames 0-1 in the snapshot, 2-3 journalled only; then "killed".
  {
    auto first = NewMapper();
    mapper::Checkpoint cp(dir_ / "cp", "config A");
    mapper::DaemonState state;
    for (std::size_t k = 0; k < 4; ++k) {
      const mapper::FrameResult r = first->ProcessFrame(Read(k));
      state.next_index = k + 1;
      cp.Append(&r, state);
      if (k == 1) cp.Save(*first, state);
    }
    EXPECT_EQ(cp.journal_records(), 2u);
  }
  auto resumed = NewMapper();
  mapper::Checkpoint cp(dir_ / "cp", "config A");
  ASSERT_TRUE(cp.Exists());
  std::size_t frames_read = 0;
  const mapper::DaemonState state = cp.Restore(resumed.get(), [&](std::size_t k) {
    ++frames_read;
    return Read(k);
  });
  EXPECT_EQ(state.next_index, 4u);
  EXPECT_EQ(cp.reapplied(), 2u);
  EXPECT_EQ(frames_read, 3u);  // the reference (frame 1) and the two journalled frames
  resumed->ProcessFrame(Read(4));
  ExpectSameState(*straight, *resumed);
}

// With registration on voxels (mapper.registration_cell_px), the restored reference is the
// frame prepared as it was when it became the reference: its voxels and its spacing as D.
TEST_F(CheckpointTest, AStereoReferenceOfVoxelsIsRestoredAsItWas) {
  const io::SequenceReader stereo(fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_stereo");
  mapper::PipelineOptions options = Defaults();
  options.mapper.registration_cell_px = 4.0;
  options.octomap.enabled = false;
  auto fresh = [&] { return std::make_unique<mapper::Mapper>(stereo.info(), options); };
  auto straight = fresh();
  for (std::size_t k = 0; k < 3; ++k) straight->ProcessFrame(stereo.Read(k));
  {
    auto first = fresh();
    mapper::Checkpoint cp(dir_ / "cp", "config V");
    mapper::DaemonState state;
    for (std::size_t k = 0; k < 2; ++k) {
      const mapper::FrameResult r = first->ProcessFrame(stereo.Read(k));
      state.next_index = k + 1;
      cp.Append(&r, state);
    }
    cp.Save(*first, state);
  }
  auto resumed = fresh();
  mapper::Checkpoint cp(dir_ / "cp", "config V");
  cp.Restore(resumed.get(), [&](std::size_t k) { return stereo.Read(k); });
  resumed->ProcessFrame(stereo.Read(2));
  ASSERT_EQ(resumed->results().size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(resumed->results()[k].step.T_world_body.matrix(),
              straight->results()[k].step.T_world_body.matrix())
        << "frame " << k;
  }
  EXPECT_EQ(resumed->results()[2].iterations, straight->results()[2].iterations);
}

TEST_F(CheckpointTest, TornLastRecordIsDroppedAndTheJournalGoesOn) {
  {
    auto m = NewMapper();
    mapper::Checkpoint cp(dir_ / "cp", "config A");
    mapper::DaemonState state;
    for (std::size_t k = 0; k < 2; ++k) {
      const mapper::FrameResult r = m->ProcessFrame(Read(k));
      state.next_index = k + 1;
      cp.Append(&r, state);
    }
  }
  // A kill in the middle of the third record: its header and half its payload.
  const fs::path journal = dir_ / "cp" / "journal.bin";
  const std::uintmax_t good = fs::file_size(journal);
  {
    std::ofstream out(journal, std::ios::binary | std::ios::app);
    const std::string torn = "\x52\x4d\x4a\x31\x00\x10\x00\x00\x12\x34\x56\x78partial";
    out << torn;
  }
  auto m = NewMapper();
  mapper::Checkpoint cp(dir_ / "cp", "config A");
  const mapper::DaemonState state = cp.Restore(m.get(), [&](std::size_t k) { return Read(k); });
  EXPECT_EQ(state.next_index, 2u);
  EXPECT_EQ(m->results().size(), 2u);
  EXPECT_EQ(fs::file_size(journal), good);  // the torn tail is cut
  const mapper::FrameResult r = m->ProcessFrame(Read(2));
  cp.Append(&r, {3, {}, {}});
  auto again = NewMapper();
  mapper::Checkpoint reread(dir_ / "cp", "config A");
  EXPECT_EQ(reread.Restore(again.get(), [&](std::size_t k) { return Read(k); }).next_index, 3u);
  EXPECT_EQ(again->results().size(), 3u);
}

TEST_F(CheckpointTest, AnotherConfigurationOrADamagedSnapshotIsRefused) {
  {
    auto m = NewMapper();
    mapper::Checkpoint cp(dir_ / "cp", "config A");
    mapper::DaemonState state;
    const mapper::FrameResult r = m->ProcessFrame(Read(0));
    state.next_index = 1;
    cp.Append(&r, state);
    cp.Save(*m, state);
    cp.Append(&r, state);
  }
  {
    auto m = NewMapper();
    mapper::Checkpoint cp(dir_ / "cp", "config B");
    EXPECT_THROW(cp.Restore(m.get(), [&](std::size_t k) { return Read(k); }),
                 mapper::CheckpointError);
  }
  // One flipped byte in the snapshot.
  const fs::path snapshot = dir_ / "cp" / "state.bin";
  std::fstream f(snapshot, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(fs::file_size(snapshot) / 2));
  f.put('\x5a');
  f.close();
  auto m = NewMapper();
  mapper::Checkpoint cp(dir_ / "cp", "config A");
  try {
    cp.Restore(m.get(), [&](std::size_t k) { return Read(k); });
    FAIL() << "a damaged snapshot was accepted";
  } catch (const mapper::CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("state.bin"), std::string::npos) << e.what();
  }
  // A snapshot of an earlier format (the frame results grew dead reckoning's bias, then the
  // information it rests on, then the chain steps their systematic cross-covariance) is named as
  // such, not as damage.
  f.open(snapshot, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(7);
  f.put('2');
  f.close();
  try {
    cp.Restore(m.get(), [&](std::size_t k) { return Read(k); });
    FAIL() << "a snapshot of format 2 was accepted";
  } catch (const mapper::CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("another rovermap version (format 2, this one reads 9)"),
              std::string::npos)
        << e.what();
  }
}

// The snapshot cadence: checkpoint_every frames at least; then it waits for its share of the
// processing time (the last snapshot took 200 ms; 10 frames of 63 ms are not enough, 64 are),
// but never past checkpoint_max_every; share 0 is exactly every checkpoint_every.
TEST(SnapshotDue, WaitsForItsShareOfTheProcessingTimeUpToTheLimit) {
  mapper::ServeOptions o;  // every 10, share 0.05, at most every 100
  EXPECT_FALSE(mapper::SnapshotDue(o, 9, 1e6, 0.0));
  EXPECT_TRUE(mapper::SnapshotDue(o, 10, 630.0, 0.0));  // the first
  EXPECT_TRUE(mapper::SnapshotDue(o, 10, 630.0, 30.0));
  EXPECT_FALSE(mapper::SnapshotDue(o, 10, 630.0, 200.0));
  EXPECT_FALSE(mapper::SnapshotDue(o, 63, 63 * 63.0, 200.0));
  EXPECT_TRUE(mapper::SnapshotDue(o, 64, 64 * 63.0, 200.0));
  EXPECT_FALSE(mapper::SnapshotDue(o, 99, 99.0, 1e6));
  EXPECT_TRUE(mapper::SnapshotDue(o, 100, 100.0, 1e6));
  o.checkpoint_share = 0.0;
  EXPECT_FALSE(mapper::SnapshotDue(o, 9, 1.0, 1e6));
  EXPECT_TRUE(mapper::SnapshotDue(o, 10, 1.0, 1e6));
}

// The publications wait for their share the same way, on their own keys (every 10, share
// 0.05, at most every 100): the last one cost 100 ms; 13 frames of 150 ms are not enough, 14 are.
TEST(PublicationDue, WaitsForItsShareOnItsOwnKeys) {
  mapper::ServeOptions o;
  o.checkpoint_share = 0.0;  // not the snapshots' keys
  EXPECT_FALSE(mapper::PublicationDue(o, 9, 1e6, 0.0));
  EXPECT_FALSE(mapper::PublicationDue(o, 13, 13 * 150.0, 100.0));
  EXPECT_TRUE(mapper::PublicationDue(o, 14, 14 * 150.0, 100.0));
  EXPECT_TRUE(mapper::PublicationDue(o, 100, 100.0, 1e6));
  o.publish_share = 0.0;
  EXPECT_TRUE(mapper::PublicationDue(o, 10, 1.0, 1e6));
}

// Every field set away from its default, so that a field the encoding leaves out (or reads
// into another) shows.
mapper::FrameResult EveryFieldSet() {
  int n = 0;
  const auto pose = [&n] {
    ++n;
    return Eigen::Isometry3d(
        Eigen::Translation3d(0.5 * n, -1.25 * n, 2.0 + n) *
        Eigen::AngleAxisd(0.1 * n, Eigen::Vector3d(1.0, 2.0, 3.0 + n).normalized()));
  };
  const auto matrix = [&n] {
    mapper::Matrix6d m;
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) m(r, c) = 0.01 * (++n) - 0.3 * r + c;
    return m;
  };
  mapper::FrameResult f;
  f.index = 41;
  f.timestamp = 1234.5625;
  f.status = mapper::FrameStatus::kPartial;
  f.fallback_reason = mapper::FallbackReason::kHighRms;
  f.detail = "rms 0.4 m > 0.2 m";
  f.step.index = 41;
  f.step.T_world_body = pose();
  f.step.T_world_body_odom = pose();
  f.step.odom_increment = pose();
  f.step.used_increment = pose();
  f.step.increment_correction = pose();
  f.step.cumulative_correction = pose();
  f.step.fallback = true;
  f.step.covariance = matrix();
  f.step.systematic_cross = matrix();
  f.T_world_body_truth = pose();
  f.odometry_directions = 0b101101;
  f.matcher_status = "converged";
  f.iterations = 17;
  f.inliers = 9001;
  f.inlier_ratio = 0.875;
  f.rms_m = 0.0321;
  f.conditioning = 42.5;
  f.points = 12345;
  f.outliers_removed = 67;
  f.dropped_nonfinite = 8;
  f.dem = {101, 102, 103, 104, 105, 106, 107, 108, 109};
  f.time = {1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5};
  f.T_world_body_registered = pose();
  f.increment_covariance = matrix();
  f.reference_distance_m = 3.75;
  f.odometry_bias.bias << 0.001, -0.002, 0.003, -0.04, 0.05, -0.06;
  f.odometry_bias.information = matrix();
  return f;
}

TEST(FrameResultEncoding, RoundTripGivesBackEveryField) {
  const mapper::FrameResult a = EveryFieldSet();
  const std::string bytes = mapper::EncodeFrameResult(a);
  const mapper::FrameResult b = mapper::DecodeFrameResult(bytes);
  const auto same_pose = [](const Eigen::Isometry3d& x, const Eigen::Isometry3d& y) {
    return x.matrix() == y.matrix();
  };
  EXPECT_EQ(a.index, b.index);
  EXPECT_EQ(a.timestamp, b.timestamp);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.fallback_reason, b.fallback_reason);
  EXPECT_EQ(a.detail, b.detail);
  EXPECT_EQ(a.step.index, b.step.index);
  EXPECT_TRUE(same_pose(a.step.T_world_body, b.step.T_world_body));
  EXPECT_TRUE(same_pose(a.step.T_world_body_odom, b.step.T_world_body_odom));
  EXPECT_TRUE(same_pose(a.step.odom_increment, b.step.odom_increment));
  EXPECT_TRUE(same_pose(a.step.used_increment, b.step.used_increment));
  EXPECT_TRUE(same_pose(a.step.increment_correction, b.step.increment_correction));
  EXPECT_TRUE(same_pose(a.step.cumulative_correction, b.step.cumulative_correction));
  EXPECT_EQ(a.step.fallback, b.step.fallback);
  EXPECT_EQ(a.step.covariance, b.step.covariance);
  EXPECT_EQ(a.step.systematic_cross, b.step.systematic_cross);
  ASSERT_TRUE(b.T_world_body_truth.has_value());
  EXPECT_TRUE(same_pose(*a.T_world_body_truth, *b.T_world_body_truth));
  EXPECT_EQ(a.odometry_directions, b.odometry_directions);
  EXPECT_EQ(a.matcher_status, b.matcher_status);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.inlier_ratio, b.inlier_ratio);
  EXPECT_EQ(a.rms_m, b.rms_m);
  EXPECT_EQ(a.conditioning, b.conditioning);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.outliers_removed, b.outliers_removed);
  EXPECT_EQ(a.dropped_nonfinite, b.dropped_nonfinite);
  EXPECT_EQ(a.dem.points, b.dem.points);
  EXPECT_EQ(a.dem.fused, b.dem.fused);
  EXPECT_EQ(a.dem.candidate, b.dem.candidate);
  EXPECT_EQ(a.dem.swapped, b.dem.swapped);
  EXPECT_EQ(a.dem.rejected_outliers, b.dem.rejected_outliers);
  EXPECT_EQ(a.dem.dropped_nonfinite, b.dem.dropped_nonfinite);
  EXPECT_EQ(a.dem.dropped_out_of_grid, b.dem.dropped_out_of_grid);
  EXPECT_EQ(a.dem.dropped_imprecise, b.dem.dropped_imprecise);
  EXPECT_EQ(a.dem.new_tiles, b.dem.new_tiles);
  EXPECT_EQ(a.time.load_ms, b.time.load_ms);
  EXPECT_EQ(a.time.stereo_ms, b.time.stereo_ms);
  EXPECT_EQ(a.time.prepare_ms, b.time.prepare_ms);
  EXPECT_EQ(a.time.register_ms, b.time.register_ms);
  EXPECT_EQ(a.time.fuse_dem_ms, b.time.fuse_dem_ms);
  EXPECT_EQ(a.time.fuse_octomap_ms, b.time.fuse_octomap_ms);
  EXPECT_EQ(a.time.total_ms, b.time.total_ms);
  ASSERT_TRUE(b.T_world_body_registered.has_value());
  EXPECT_TRUE(same_pose(*a.T_world_body_registered, *b.T_world_body_registered));
  EXPECT_EQ(a.increment_covariance, b.increment_covariance);
  EXPECT_EQ(a.reference_distance_m, b.reference_distance_m);
  EXPECT_EQ(a.odometry_bias.bias, b.odometry_bias.bias);
  EXPECT_EQ(a.odometry_bias.information, b.odometry_bias.information);
  // The bytes a second encoding gives are the first's (nothing read into the wrong field).
  EXPECT_EQ(mapper::EncodeFrameResult(b), bytes);
  // A status or reason beyond its enumeration, and a cut encoding, are a damaged checkpoint.
  std::string bad = bytes;
  const std::int32_t beyond = 99;
  std::memcpy(bad.data() + 16, &beyond, sizeof(beyond));  // after index and timestamp
  EXPECT_THROW(mapper::DecodeFrameResult(bad), mapper::CheckpointError);
  EXPECT_THROW(mapper::DecodeFrameResult(bytes.substr(0, bytes.size() - 1)),
               mapper::CheckpointError);
  EXPECT_THROW(mapper::DecodeFrameResult(bytes + "x"), mapper::CheckpointError);
}

TEST(Crc32, KnownValues) {
  EXPECT_EQ(mapper::Crc32(""), 0x00000000u);
  EXPECT_EQ(mapper::Crc32("123456789"), 0xCBF43926u);  // the standard check value
  EXPECT_EQ(mapper::Crc32("The quick brown fox jumps over the lazy dog"), 0x414FA339u);
}

}  // namespace
