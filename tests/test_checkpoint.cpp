// service/Checkpoint: a snapshot plus journal restores a Mapper to the very state the
// interrupted one had (poses, DEM cells, OctoMap), a torn journal record is dropped and the
// journal goes on after the last good one, and damaged or foreign checkpoints are refused.
#include <gtest/gtest.h>
#include <unistd.h>

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
  return {c.mapper, c.registration, c.stereo, c.dem, c.octomap};
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
    EXPECT_NE(std::string(e.what()).find("another rovermap version (format 2, this one reads 4)"),
              std::string::npos)
        << e.what();
  }
}

// The snapshot cadence: checkpoint_every frames at least; then it waits for its share of the
// processing time (the last snapshot took 200 ms; 10 frames of 63 ms are not enough, 32 are),
// but never past checkpoint_max_every; share 0 is exactly every checkpoint_every.
TEST(SnapshotDue, WaitsForItsShareOfTheProcessingTimeUpToTheLimit) {
  mapper::ServeOptions o;  // every 10, share 0.1, at most every 100
  EXPECT_FALSE(mapper::SnapshotDue(o, 9, 1e6, 0.0));
  EXPECT_TRUE(mapper::SnapshotDue(o, 10, 630.0, 0.0));  // the first
  EXPECT_TRUE(mapper::SnapshotDue(o, 10, 630.0, 60.0));
  EXPECT_FALSE(mapper::SnapshotDue(o, 10, 630.0, 200.0));
  EXPECT_FALSE(mapper::SnapshotDue(o, 31, 31 * 63.0, 200.0));
  EXPECT_TRUE(mapper::SnapshotDue(o, 32, 32 * 63.0, 200.0));
  EXPECT_FALSE(mapper::SnapshotDue(o, 99, 99.0, 1e6));
  EXPECT_TRUE(mapper::SnapshotDue(o, 100, 100.0, 1e6));
  o.checkpoint_share = 0.0;
  EXPECT_FALSE(mapper::SnapshotDue(o, 9, 1.0, 1e6));
  EXPECT_TRUE(mapper::SnapshotDue(o, 10, 1.0, 1e6));
}

TEST(Crc32, KnownValues) {
  EXPECT_EQ(mapper::Crc32(""), 0x00000000u);
  EXPECT_EQ(mapper::Crc32("123456789"), 0xCBF43926u);  // the standard check value
  EXPECT_EQ(mapper::Crc32("The quick brown fox jumps over the lazy dog"), 0x414FA339u);
}

}  // namespace
