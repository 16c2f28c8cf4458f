// io::FrameSource: what OpenFrameSource opens a sequence directory as yields the frames, poses
// and errors of io::SequenceReader, through the interface alone.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>

#include "io/FrameSource.hpp"
#include "io/IoError.hpp"
#include "io/Sequence.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

const fs::path kData = ROVERMAP_DATASETS_DIR;

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();  // cloud frames have no images
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

void ExpectSameFrames(const fs::path& sequence) {
  SequenceReader reader(sequence);
  const std::unique_ptr<FrameSource> source = OpenFrameSource(sequence);
  ASSERT_EQ(source->frame_count(), reader.frame_count());
  EXPECT_EQ(source->info().sensor_type, reader.info().sensor_type);
  EXPECT_EQ(source->has_groundtruth(), reader.has_groundtruth());
  EXPECT_EQ(source->groundtruth().size(), reader.groundtruth().size());
  Frame a;
  Frame b;
  std::size_t n = 0;
  while (reader.Next(&a)) {
    EXPECT_EQ(source->next_index(), n);
    ASSERT_TRUE(source->Next(&b));
    EXPECT_EQ(b.index, a.index);
    EXPECT_EQ(b.timestamp, a.timestamp);
    EXPECT_TRUE(b.T_world_body_odom.matrix() == a.T_world_body_odom.matrix());
    EXPECT_EQ(source->odometry()[n].timestamp, a.timestamp);
    EXPECT_TRUE(SameImage(b.left, a.left));
    EXPECT_TRUE(SameImage(b.right, a.right));
    EXPECT_EQ(b.cloud.size(), a.cloud.size());
    const Frame c = source->Read(n);  // random access gives the same frame
    EXPECT_EQ(c.timestamp, a.timestamp);
    EXPECT_TRUE(SameImage(c.left, a.left));
    ++n;
  }
  EXPECT_FALSE(source->Next(&b));
  EXPECT_EQ(source->next_index(), n);
  EXPECT_THROW(source->Read(n), std::out_of_range);
}

TEST(FrameSource, ASequenceDirectoryGivesTheFramesOfSequenceReaderStereo) {
  ExpectSameFrames(kData / "sim_tiny_stereo");
}

TEST(FrameSource, ASequenceDirectoryGivesTheFramesOfSequenceReaderCloud) {
  ExpectSameFrames(kData / "sim_tiny_cloud");
}

TEST(FrameSource, OpeningWhatIsNotARecordingThrowsIoError) {
  EXPECT_THROW(OpenFrameSource(kData / "no_such_sequence"), IoError);
}

TEST(FrameSource, ABagFileOpensAsABagOrSaysTheBuildHasNoBagSupport) {
  const fs::path file = rovermap::testing::ScratchDir() / "notes.bag";
  std::ofstream(file) << "not a bag\n";
  const std::string message = rovermap::testing::ErrorOf<IoError>([&] { OpenFrameSource(file); });
#ifdef ROVERMAP_WITH_ROSBAG
  EXPECT_TRUE(rovermap::testing::Contains(message, file.string() + ": cannot read the bag"));
#else
  EXPECT_TRUE(rovermap::testing::Contains(
      message, file.string() + ": this rovermap was built without ROS bag support"));
#endif
}

}  // namespace
}  // namespace rovermap::io
