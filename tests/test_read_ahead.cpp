// mapper::ReadAhead: frames prepared one ahead on another thread give the very results of
// reading and processing them one by one, in order, with unreadable frames passed on.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ReadAhead.hpp"
#include "tests/support/PipelineDefaults.hpp"
#include "tests/support/ScratchDir.hpp"

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

const fs::path kData = ROVERMAP_DATASETS_DIR;

using rovermap::testing::PipelineDefaults;

std::vector<mapper::FrameResult> OneByOne(const fs::path& sequence) {
  io::SequenceReader reader(sequence);
  mapper::Mapper m(reader.info(), PipelineDefaults());
  io::Frame frame;
  while (reader.Next(&frame)) m.ProcessFrame(frame);
  return m.results();
}

std::vector<mapper::FrameResult> Ahead(const fs::path& sequence) {
  io::SequenceReader reader(sequence);
  mapper::Mapper m(reader.info(), PipelineDefaults());
  mapper::ReadAhead ahead(&reader, &m);
  mapper::ReadAhead::Item item;
  std::size_t expected_index = 0;
  while (ahead.Next(&item)) {
    EXPECT_EQ(item.index, expected_index++);
    if (!item.frame) {
      const io::StampedPose& odom = reader.odometry()[item.index];
      m.SkipFrame(item.index, odom.timestamp, odom.T_world_body, mapper::FallbackReason::kBadFrame,
                  item.error);
      continue;
    }
    EXPECT_EQ(item.frame->index, item.index);
    m.ProcessPrepared(*item.frame, std::move(item.prepared), item.load_ms);
  }
  EXPECT_FALSE(ahead.Next(&item));  // stays at the end
  return m.results();
}

void ExpectSameResults(const std::vector<mapper::FrameResult>& a,
                       const std::vector<mapper::FrameResult>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    EXPECT_EQ(a[k].status, b[k].status);
    EXPECT_EQ(a[k].step.T_world_body.matrix(), b[k].step.T_world_body.matrix());  // bit for bit
    EXPECT_EQ(a[k].step.covariance, b[k].step.covariance);
    EXPECT_EQ(a[k].points, b[k].points);
    EXPECT_EQ(a[k].outliers_removed, b[k].outliers_removed);
    EXPECT_EQ(a[k].iterations, b[k].iterations);
    EXPECT_EQ(a[k].dem.fused, b[k].dem.fused);
  }
}

}  // namespace

TEST(ReadAhead, StereoFramesGiveTheResultsOfOneByOne) {
  ExpectSameResults(OneByOne(kData / "sim_tiny_stereo"), Ahead(kData / "sim_tiny_stereo"));
}

TEST(ReadAhead, CloudFramesGiveTheResultsOfOneByOne) {
  ExpectSameResults(OneByOne(kData / "sim_tiny_cloud"), Ahead(kData / "sim_tiny_cloud"));
}

TEST(ReadAhead, AnUnreadableFrameIsPassedOnWithItsErrorAndTheRestFollow) {
  const fs::path seq = rovermap::testing::ScratchDir() / "seq";
  fs::copy(kData / "sim_tiny_cloud", seq, fs::copy_options::recursive);
  std::ofstream(seq / "frames/000002.ply", std::ios::binary) << "ply\nformat ascii 1.0\n";

  io::SequenceReader reader(seq);
  mapper::Mapper m(reader.info(), PipelineDefaults());
  mapper::ReadAhead ahead(&reader, &m);
  mapper::ReadAhead::Item item;
  std::vector<std::size_t> read, unreadable;
  while (ahead.Next(&item)) {
    (item.frame ? read : unreadable).push_back(item.index);
    if (!item.frame) {
      EXPECT_NE(item.error.find("000002.ply"), std::string::npos) << item.error;
    }
  }
  EXPECT_EQ(read, (std::vector<std::size_t>{0, 1, 3, 4}));
  EXPECT_EQ(unreadable, (std::vector<std::size_t>{2}));
}

TEST(ReadAhead, StopsCleanlyWithAFrameInFlight) {
  io::SequenceReader reader(kData / "sim_tiny_stereo");
  mapper::Mapper m(reader.info(), PipelineDefaults());
  {
    mapper::ReadAhead ahead(&reader, &m);
    mapper::ReadAhead::Item item;
    ASSERT_TRUE(ahead.Next(&item));  // frame 1 is now being prepared
    EXPECT_TRUE(item.frame.has_value());
    EXPECT_TRUE(item.prepared.loaded.ok);
    EXPECT_NE(item.prepared.source, nullptr);
  }  // the destructor waits for frame 1
  EXPECT_EQ(reader.next_index(), 2u);
}
