// `rovermap replay BAG` and `rovermap import BAG` end to end: a simulated sequence recorded into
// a bag replays to the directory's trajectory, and its import to the same again; cloud bags
// replay and import; skipped images are reported; bad bags and bad `bag.` keys stop before any
// output (exit 1 or 2, the message naming the bag and the cause).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/Gnss.hpp"
#include "io/PointCloudIo.hpp"
#include "io/Sequence.hpp"
#include "io/Tum.hpp"
#include "tests/support/BagWriting.hpp"
#include "tests/support/CommandFixture.hpp"

namespace fs = std::filesystem;
using rovermap::testing::BagRecording;
using rovermap::testing::CommandResult;
using rovermap::testing::Slurp;
using rovermap::testing::WriteSequenceBag;

namespace {

const fs::path kTinyStereo = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_stereo";
const fs::path kTinyCloud = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_cloud";
// The bag's calibration, ground truth and T_body_sensor as the sequence's (the origin comes
// from the bag's NavSatFix by default).
const std::string kBagKeys =
    "--set bag.T_body_sensor_source=tf_static --set bag.groundtruth_topic=/groundtruth";

class BagReplay : public rovermap::testing::CommandFixture {
 protected:
  fs::path Bag(const std::string& name, BagRecording how = {},
               const fs::path& sequence = kTinyStereo) {
    if (how.groundtruth_topic.empty()) how.groundtruth_topic = "/groundtruth";
    return WriteSequenceBag(sequence, dir_ / name, how);
  }

  void ExpectNothingWritten(const fs::path& out, const std::string& what) {
    EXPECT_FALSE(fs::exists(out)) << what << ": " << out << " was created";
    for (const auto& entry : fs::directory_iterator(out.parent_path())) {
      EXPECT_EQ(entry.path().filename().string().find("." + out.filename().string()),
                std::string::npos)
          << what << ": left " << entry.path();
    }
  }
};

// The largest position and rotation-matrix differences between two trajectories.
std::pair<double, double> Difference(const std::vector<rovermap::io::StampedPose>& a,
                                     const std::vector<rovermap::io::StampedPose>& b) {
  EXPECT_EQ(a.size(), b.size());
  double position = 0.0;
  double rotation = 0.0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) {
    position = std::max(position,
                        (a[k].T_world_body.translation() - b[k].T_world_body.translation()).norm());
    rotation = std::max(rotation, (a[k].T_world_body.linear() - b[k].T_world_body.linear()).norm());
  }
  return {position, rotation};
}

}  // namespace

TEST_F(BagReplay, ABagOfTheSimulatedSequenceReplaysAsTheDirectoryAndImportsToTheSame) {
  const fs::path bag = Bag("tiny.bag");
  CommandResult r =
      Rovermap("replay " + kTinyStereo.string() + " --out " + (dir_ / "dir").string());
  ASSERT_EQ(r.status, 0) << r.err;
  r = Rovermap("replay " + bag.string() + " --out " + (dir_ / "bag").string() + " " + kBagKeys);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_TRUE(summary.contains("metrics"));  // the bag's ground truth went through

  const auto from_dir = rovermap::io::ReadTum(dir_ / "dir" / "trajectory.tum");
  const auto from_bag = rovermap::io::ReadTum(dir_ / "bag" / "trajectory.tum");
  ASSERT_EQ(from_bag.size(), from_dir.size());
  for (std::size_t k = 0; k < from_dir.size(); ++k) {
    EXPECT_NEAR(from_bag[k].timestamp, from_dir[k].timestamp + rovermap::testing::kBagTimeOffset,
                1e-6);
  }
  const auto [position, rotation] = Difference(from_bag, from_dir);
  // Measured: 0 m and 0 (the poses and images go through the bag unchanged).
  EXPECT_LE(position, 1e-9);
  EXPECT_LE(rotation, 1e-9);
  // The same map from the same points, origin (NavSatFix) and T_body_sensor (/tf_static).
  EXPECT_EQ(Slurp(dir_ / "bag" / "dem.tif"), Slurp(dir_ / "dir" / "dem.tif"));

  // Dead reckoning from /tf (odom -> base_link) instead of /odom: the same trajectory.
  BagRecording on_tf;
  on_tf.odometry_on_tf = true;
  r = Rovermap("replay " + Bag("tf.bag", on_tf).string() + " --out " + (dir_ / "tf").string() +
               " " + kBagKeys + " --set bag.odometry_source=tf");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Slurp(dir_ / "tf" / "trajectory.tum"), Slurp(dir_ / "bag" / "trajectory.tum"));

  // import, then replay the imported sequence: the bag's replay again.
  const fs::path seq = dir_ / "imported";
  r = Rovermap("import " + bag.string() + " --out " + seq.string() + " " + kBagKeys);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json imported = nlohmann::json::parse(r.out);
  EXPECT_EQ(imported["frames"], 3);
  EXPECT_EQ(imported["groundtruth"], true);
  for (const char* file : {"sequence.yaml", "odometry.tum", "groundtruth.tum",
                           "frames/000000.left.png", "frames/000002.right.png"}) {
    EXPECT_TRUE(fs::exists(seq / file)) << file;
  }
  // The imported sequence holds what the bag's replay used: the same images, poses and
  // calibration, and T_body_sensor to the bit.
  const rovermap::io::SequenceReader reader(seq);
  const rovermap::io::SequenceReader original(kTinyStereo);
  EXPECT_EQ(reader.info().camera->fx, original.info().camera->fx);
  EXPECT_NEAR(reader.info().camera->baseline_m, original.info().camera->baseline_m, 1e-12);
  EXPECT_EQ(reader.info().origin.latitude_deg, original.info().origin.latitude_deg);
  EXPECT_NEAR(reader.info().frame_rate_hz, original.info().frame_rate_hz, 1e-6);
  EXPECT_TRUE(reader.info().T_body_sensor.linear() == original.info().T_body_sensor.linear());
  EXPECT_TRUE(reader.info().T_body_sensor.translation().isApprox(
      original.info().T_body_sensor.translation(), 1e-15));
  for (const char* frame : {"000000.left.png", "000001.right.png", "000002.left.png"}) {
    EXPECT_EQ(Slurp(seq / "frames" / frame), Slurp(kTinyStereo / "frames" / frame)) << frame;
  }
  const auto truth = rovermap::io::ReadTum(seq / "groundtruth.tum");
  const auto [truth_position, truth_rotation] =
      Difference(truth, rovermap::io::ReadTum(kTinyStereo / "groundtruth.tum"));
  EXPECT_LE(truth_position, 1e-9);
  EXPECT_LE(truth_rotation, 1e-9);
  r = Rovermap("replay " + seq.string() + " --out " + (dir_ / "seq").string());
  ASSERT_EQ(r.status, 0) << r.err;
  // The same replay to the byte. The imported TUM files hold each pose's quaternion as the bag
  // does and its stamp as sec.nanosec, so they read back to the very doubles the bag's replay
  // used (a quaternion recomputed from the rotation matrix differed in its last bit, and the
  // trajectory by 1e-16). T_body_sensor goes through sequence.yaml as the quaternion the bag's
  // static transforms chained to, likewise (recomputed from the matrix it differed by 1e-16,
  // enough to move the matcher's stopping point by 0.5 mm).
  for (const char* file : {"trajectory.tum", "odometry.tum", "dem.tif"}) {
    EXPECT_EQ(Slurp(dir_ / "seq" / file), Slurp(dir_ / "bag" / file)) << file;
  }
  EXPECT_EQ(reader.info().body_sensor_quaternion->coeffs(),
            original.info().body_sensor_quaternion->coeffs());

  // A second import needs --force, and then replaces the sequence whole.
  r = Rovermap("import " + bag.string() + " --out " + seq.string() + " " + kBagKeys);
  EXPECT_EQ(r.status, 2) << r.err;
  std::ofstream(seq / "stale.txt") << "x";
  r = Rovermap("import " + bag.string() + " --out " + seq.string() + " --force " + kBagKeys);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(seq / "stale.txt"));
  EXPECT_TRUE(fs::exists(seq / "frames/000002.left.png"));
}

TEST_F(BagReplay, CloudBagsReplayAndImport) {
  BagRecording how;
  how.cloud_float64 = true;
  const fs::path bag = Bag("cloud.bag", how, kTinyCloud);
  const std::string keys = kBagKeys + " --set bag.sensor=cloud";
  CommandResult r =
      Rovermap("replay " + bag.string() + " --out " + (dir_ / "out").string() + " " + keys);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["frames"], 5);
  EXPECT_EQ(summary["bad_frames"], 0);
  EXPECT_GE(summary["registered"].get<int>(), 3);
  EXPECT_GT(summary["dropped_nonfinite"].get<int>(), 0);  // the bag's NaN points, counted

  const fs::path seq = dir_ / "seq";
  r = Rovermap("import " + bag.string() + " --out " + seq.string() + " " + keys);
  ASSERT_EQ(r.status, 0) << r.err;
  // The bag's NaN points (one after every 10th) stay out of the PLYs, counted.
  std::size_t nan = 0;
  for (std::size_t k = 0; k < 5; ++k)
    nan += rovermap::io::ReadPly(kTinyCloud / "frames" / (rovermap::io::FrameStem(k) + ".ply"))
               .size() /
           10;
  EXPECT_EQ(nlohmann::json::parse(r.out)["dropped_nonfinite"], nan);
  const rovermap::io::SequenceReader reader(seq);
  EXPECT_EQ(reader.info().sensor_type, rovermap::io::SensorType::kCloud);
  ASSERT_EQ(reader.frame_count(), 5u);
  const auto points = rovermap::io::ReadPly(seq / "frames/000003.ply");
  const auto want = rovermap::io::ReadPly(kTinyCloud / "frames/000003.ply");
  ASSERT_EQ(points.size(), want.size());
  EXPECT_EQ(points.points.back(), want.points.back());
}

TEST_F(BagReplay, SkippedFramesAreReportedOnStderr) {
  BagRecording how;
  how.right_delay_s = 0.004;  // within the default 5 ms
  how.truth_frames = 2;       // the ground truth ends at frame 1
  const fs::path bag = Bag("late.bag", how);
  const fs::path out = dir_ / "out";
  CommandResult r = Rovermap("replay " + bag.string() + " --out " + out.string() + " " + kBagKeys);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["frames"], 2);
  EXPECT_NE(r.err.find("replay: " + bag.string() +
                       ": 2 frames; skipped 0 images without a partner within "
                       "bag.pair_tolerance_s and 1 frames outside the time span of the odometry "
                       "(or ground truth)"),
            std::string::npos)
      << r.err;
  // Within 3 ms no image has a partner: no frame at all, and no output.
  const fs::path none = dir_ / "none";
  r = Rovermap("replay " + bag.string() + " --out " + none.string() +
               " --set bag.pair_tolerance_s=0.003");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("late.bag: no left/right image pair within 0.003"), std::string::npos)
      << r.err;
  ExpectNothingWritten(none, "no pair");
}

TEST_F(BagReplay, BadBagsStopBeforeAnyOutput) {
  const fs::path good = Bag("good.bag");
  const std::string good_bytes = Slurp(good);
  auto write = [&](const std::string& name, const std::string& bytes) {
    const fs::path file = dir_ / name;
    std::ofstream(file, std::ios::binary) << bytes;
    return file;
  };
  // An unindexed bag: what a recorder leaves when it dies before closing the bag, the header's
  // index position still 0.
  std::string unindexed = good_bytes;
  const std::size_t index_pos = unindexed.find("index_pos=");
  ASSERT_NE(index_pos, std::string::npos);
  unindexed.replace(index_pos + 10, 8, std::string(8, '\0'));

  BagRecording bayer;
  bayer.encodings = {"mono8", "bayer_rggb8"};
  BagRecording skew;
  skew.edit_info = [](auto* left, auto*) { left->P[1] = 0.5; };
  BagRecording zero_baseline;
  zero_baseline.edit_info = [](auto*, auto* right) { right->P[3] = 0.0; };
  BagRecording sizes;
  sizes.edit_info = [](auto*, auto* right) { right->height = 100; };

  struct Case {
    std::string name;
    fs::path bag;
    std::string keys;
    int status;
    std::vector<std::string> messages;  // each must appear in stderr
  };
  const std::vector<Case> cases = {
      {"missing_topic",
       good,
       "--set bag.odometry_topic=/wheel_odom",
       1,
       {"good.bag: no topic /wheel_odom (the bag has: ", "/odom (nav_msgs/Odometry)",
        "/stereo/left/image_rect (sensor_msgs/Image)", "/tf_static (tf2_msgs/TFMessage)"}},
      {"encoding",
       Bag("bayer.bag", bayer),
       "",
       1,
       {"bayer.bag: /stereo/right/image_rect at 1000.001000000: unsupported image encoding "
        "'bayer_rggb8'"}},
      {"truncated",
       write("cut.bag", good_bytes.substr(0, good_bytes.size() / 2)),
       "",
       1,
       {"cut.bag: cannot read the bag"}},
      {"unindexed",
       write("unindexed.bag", unindexed),
       "",
       1,
       {"unindexed.bag: the bag is not indexed", "rosbag reindex"}},
      {"not_a_bag", write("text.bag", "hello\n"), "", 1, {"text.bag: cannot read the bag"}},
      {"skew",
       Bag("skew.bag", skew),
       "",
       1,
       {"skew.bag: /stereo/left/camera_info: projection P is not that of a rectified camera"}},
      {"zero_baseline",
       Bag("zero.bag", zero_baseline),
       "",
       1,
       {"zero.bag: /stereo/right/camera_info: projection P gives no positive baseline"}},
      {"sizes",
       Bag("sizes.bag", sizes),
       "",
       1,
       {"sizes.bag: left and right camera info differ in image size (160x120 and 160x100)"}},
      {"bad_key",
       good,
       "--set bag.pair_tolerance_s=-1",
       2,
       {"bag.pair_tolerance_s: must be >= 0 (got -1)"}},
      {"bad_name",
       good,
       "--set \"bag.odometry_topic=odom topic\"",
       2,
       {"bag.odometry_topic: not a topic or frame name"}},
      {"bad_rpy",
       good,
       "--set bag.T_body_sensor_rpy_deg=[0,0]",
       2,
       {"bag.T_body_sensor_rpy_deg: expected a list of 3 numbers (got 2)"}},
  };
  for (const Case& c : cases) {
    for (const char* command : {"replay", "import"}) {
      const fs::path out = dir_ / (std::string(command) + "_" + c.name);
      const CommandResult r = Rovermap(std::string(command) + " " + c.bag.string() + " --out " +
                                       out.string() + " " + c.keys);
      EXPECT_EQ(r.status, c.status) << command << " " << c.name << ": " << r.err;
      for (const std::string& message : c.messages) {
        EXPECT_NE(r.err.find(message), std::string::npos)
            << command << " " << c.name << ": " << r.err;
      }
      EXPECT_TRUE(r.out.empty()) << command << " " << c.name;
      ExpectNothingWritten(out, std::string(command) + " " + c.name);
    }
  }
}

TEST_F(BagReplay, AFrameThatCannotBeDecodedIsLeftOutOfAnImport) {
  // Truncated PNGs are found only when decoded: replay keeps going (a bad frame), import leaves
  // the frame out and renumbers the rest.
  BagRecording how;
  how.encodings = {"png"};
  how.edit_compressed = [](std::size_t k, bool left, sensor_msgs::CompressedImage* image) {
    if (k == 1 && !left) image->data.resize(image->data.size() / 3);
  };
  const fs::path bag = Bag("cut.bag", how);
  CommandResult r = Rovermap("replay " + bag.string() + " --out " + (dir_ / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["bad_frames"], 1);
  const fs::path seq = dir_ / "seq";
  r = Rovermap("import " + bag.string() + " --out " + seq.string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("import: frame left out: " + bag.string() +
                       ": /stereo/right/image_rect at 1000.501000000"),
            std::string::npos)
      << r.err;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["frames"], 2);
  EXPECT_EQ(summary["skipped"]["unreadable"], 1);
  // Every frame cut: the import fails after it started writing, and leaves nothing behind.
  how.edit_compressed = [](std::size_t, bool, sensor_msgs::CompressedImage* image) {
    image->data.resize(image->data.size() / 3);
  };
  const fs::path none = dir_ / "none";
  r = Rovermap("import " + Bag("all_cut.bag", how).string() + " --out " + none.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("all_cut.bag: no frame could be read"), std::string::npos) << r.err;
  ExpectNothingWritten(none, "all frames cut");

  const rovermap::io::SequenceReader imported(seq);
  ASSERT_EQ(imported.frame_count(), 2u);
  EXPECT_NEAR(imported.odometry()[1].timestamp, rovermap::testing::kBagTimeOffset + 1.0, 1e-9);
}

// ROS 1 as ROS 2 (Ros2BagReplay.NavSatFixesHoldTheGraphAndImportWritesThem): a NavSatFix with
// every frame, its covariance given, is a fix of the pose graph with that σ; the origin's fix
// without a covariance (a tenth of a second before the first frame) gets bag.navsat_sigma_m and
// no frame (`gnss_unmatched`). import writes them to gnss.csv.
TEST_F(BagReplay, NavSatFixesHoldTheGraphAndImportWritesThem) {
  BagRecording how;
  how.navsat_track_sigma_m = 0.02;
  const fs::path bag = Bag("fixes.bag", how, kTinyCloud);
  const std::string keys = kBagKeys + " --set bag.sensor=cloud";
  CommandResult r =
      Rovermap("replay " + bag.string() + " --out " + (dir_ / "out").string() + " " + keys);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json graph = nlohmann::json::parse(r.out)["graph"];
  EXPECT_EQ(graph["gnss_fixes"], 6) << graph.dump();
  EXPECT_EQ(graph["gnss_unmatched"], 1);
  EXPECT_EQ(graph["gnss_used"], 5);
  EXPECT_TRUE(graph["solved"].get<bool>());
  const fs::path seq = dir_ / "seq";
  r = Rovermap("import " + bag.string() + " --out " + seq.string() + " " + keys);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<rovermap::io::GnssFix> fixes = rovermap::io::ReadGnssCsv(seq / "gnss.csv");
  ASSERT_EQ(fixes.size(), 6u);
  EXPECT_EQ(fixes[0].sigma_enu_m, Eigen::Vector3d::Constant(5.0));
  EXPECT_NEAR(fixes[3].sigma_enu_m.y(), 0.02, 1e-12);
}
