// `rovermap replay`, `import` and `campaign` on ROS 2 bags end to end: an MCAP bag of the
// simulated sequence replays to the directory's trajectory byte for byte (and its DEM), so does
// its import, a SQLite bag directory byte for byte too; KITTI's first three frames
// likewise; a campaign takes a bag as a traverse; a bad bag stops before any output.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/Gnss.hpp"
#include "io/Sequence.hpp"
#include "tests/support/CommandFixture.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/Ros2BagWriting.hpp"

namespace fs = std::filesystem;
using rovermap::testing::CommandResult;
using rovermap::testing::Contains;
using rovermap::testing::Ros2Recording;
using rovermap::testing::Slurp;
using rovermap::testing::WriteSequenceRos2Bag;

namespace {

const fs::path kData = ROVERMAP_DATASETS_DIR;
const fs::path kTinyStereo = kData / "sim_tiny_stereo";
// The bag's T_body_sensor and ground truth as the sequence's; the origin from its NavSatFix.
const std::string kBagKeys =
    "--set bag.T_body_sensor_source=tf_static --set bag.groundtruth_topic=/groundtruth";

class Ros2BagReplay : public rovermap::testing::CommandFixture {
 protected:
  // `rovermap replay IN --out dir_/OUT ARGS`, which must succeed.
  nlohmann::json Replay(const fs::path& in, const std::string& out, const std::string& args = "") {
    const CommandResult r =
        Rovermap("replay " + in.string() + " --out " + (dir_ / out).string() + " " + args);
    EXPECT_EQ(r.status, 0) << r.err;
    return r.status == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
  }

  // The first `frames` frames of a sequence directory, as a directory of their own.
  fs::path FirstFrames(const fs::path& sequence, std::size_t frames, const std::string& name) {
    const fs::path out = dir_ / name;
    fs::create_directories(out / "frames");
    // T_body_sensor as the quaternion sequence.yaml's comment gives (KITTI's is written by
    // roll, pitch and yaw), so that the bag's /tf_static carries that very rotation.
    std::ofstream yaml(out / "sequence.yaml");
    std::ifstream in(sequence / "sequence.yaml");
    for (std::string line; std::getline(in, line);) {
      const std::size_t at = line.find("rotation_rpy_deg: ");
      const std::size_t q = line.find("# quaternion ");
      if (at != std::string::npos && q != std::string::npos) {
        line = line.substr(0, at) + "quaternion: " + line.substr(q + 13);
      }
      yaml << line << "\n";
    }
    yaml.close();
    for (const char* tum : {"odometry.tum", "groundtruth.tum"}) {
      std::ofstream copy(out / tum);
      std::size_t kept = 0;
      for (const std::string& line : rovermap::testing::DataLines(sequence / tum)) {
        if (kept++ == frames) break;
        copy << line << "\n";
      }
    }
    for (std::size_t k = 0; k < frames; ++k) {
      char stem[16];
      std::snprintf(stem, sizeof(stem), "%06zu", k);
      for (const char* side : {".left.png", ".right.png"}) {
        fs::copy_file(sequence / "frames" / (stem + std::string(side)),
                      out / "frames" / (stem + std::string(side)));
      }
    }
    return out;
  }
};

TEST_F(Ros2BagReplay, AnMcapBagReplaysAsTheDirectoryByteForByteAndImportsToTheSame) {
  const fs::path bag = WriteSequenceRos2Bag(kTinyStereo, dir_ / "tiny.mcap");
  Replay(kTinyStereo, "dir");
  const nlohmann::json summary = Replay(bag, "bag", kBagKeys);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_TRUE(summary.contains("metrics"));  // the bag's ground truth went through
  for (const char* file : {"trajectory.tum", "odometry.tum", "dem.tif"}) {
    EXPECT_EQ(Slurp(dir_ / "bag" / file), Slurp(dir_ / "dir" / file)) << file;
  }

  // import, then replay the imported sequence: the same again.
  const fs::path seq = dir_ / "imported";
  const CommandResult r =
      Rovermap("import " + bag.string() + " --out " + seq.string() + " " + kBagKeys);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["frames"], 3);
  Replay(seq, "seq");
  // The imported TUM files hold each pose's quaternion as the bag does (here the sequence's own,
  // as its TUM lines give them) and its stamp as sec.nanosec: they are the sequence's files, and
  // read back to the very doubles the bag's replay used (a quaternion recomputed from the
  // rotation matrix differed in its last bit, and the trajectory by 1e-16).
  EXPECT_EQ(Slurp(seq / "odometry.tum"), Slurp(kTinyStereo / "odometry.tum"));
  EXPECT_EQ(Slurp(seq / "groundtruth.tum"), Slurp(kTinyStereo / "groundtruth.tum"));
  for (const char* file : {"trajectory.tum", "odometry.tum", "dem.tif"}) {
    EXPECT_EQ(Slurp(dir_ / "seq" / file), Slurp(dir_ / "bag" / file)) << file;
  }
  EXPECT_EQ(Slurp(seq / "frames" / "000001.right.png"),
            Slurp(kTinyStereo / "frames" / "000001.right.png"));

  // A rosbag2 directory holding a SQLite file, big-endian CDR, odometry on /tf.
  const fs::path directory = dir_ / "rosbag2";
  fs::create_directory(directory);
  Ros2Recording how;
  how.big_endian = true;
  how.odometry_on_tf = true;
  how.encodings = {"png"};
  WriteSequenceRos2Bag(kTinyStereo, directory / "rosbag2_0.db3", how);
  rovermap::testing::WriteRos2Metadata(directory, {"rosbag2_0.db3"}, "sqlite3");
  Replay(directory, "db3", kBagKeys + " --set bag.odometry_source=tf");
  EXPECT_EQ(Slurp(dir_ / "db3" / "trajectory.tum"), Slurp(dir_ / "dir" / "trajectory.tum"));
}

TEST_F(Ros2BagReplay, KittisFirstFramesFromAnLz4McapReplayAsFromTheirDirectory) {
  const fs::path seq = FirstFrames(kData / "kitti_stereo51", 3, "kitti3");
  Ros2Recording how;
  how.frames = 3;
  how.encodings = {"png"};
  how.mcap.compression = "lz4";
  const fs::path bag = WriteSequenceRos2Bag(seq, dir_ / "kitti.mcap", how);
  Replay(seq, "dir");
  const nlohmann::json summary = Replay(bag, "bag", kBagKeys);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_EQ(Slurp(dir_ / "bag" / "trajectory.tum"), Slurp(dir_ / "dir" / "trajectory.tum"));
}

TEST_F(Ros2BagReplay, ACampaignTakesABagAsATraverse) {
  const fs::path bag = WriteSequenceRos2Bag(kTinyStereo, dir_ / "rover.mcap");
  const fs::path out = dir_ / "campaign";
  // The origin as keys: a campaign hands its replays every key's value in config.yaml, the
  // origin keys included, so a bag's NavSatFix would not be used there (docs/bags.md).
  const CommandResult r =
      Rovermap("campaign " + kTinyStereo.string() + " " + bag.string() + " --out " + out.string() +
               " " + kBagKeys +
               " --set bag.origin_latitude_deg=46.5191 --set bag.origin_longitude_deg=6.5668 "
               "--set bag.origin_altitude_m=400");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(summary["succeeded"], 2);
  EXPECT_EQ(summary["traverse"][1]["name"], "001-rover");
  EXPECT_EQ(summary["traverse"][1]["frames"], 3);
  EXPECT_EQ(Slurp(out / "traverses" / "001-rover" / "trajectory.tum"),
            Slurp(out / "traverses" / "000-sim_tiny_stereo" / "trajectory.tum"));
}

TEST_F(Ros2BagReplay, ABadBagStopsBeforeAnyOutput) {
  Ros2Recording how;
  how.mcap.compression = "brotli";
  const fs::path bag = WriteSequenceRos2Bag(kTinyStereo, dir_ / "bad.mcap", how);
  const CommandResult r = Rovermap("replay " + bag.string() + " --out " + (dir_ / "out").string());
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, bag.string() + ": chunk at byte "));
  EXPECT_TRUE(Contains(r.err, "unknown compression 'brotli'"));
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace

// Every NavSatFix with a fix is a GNSS fix of the pose graph (docs/graph.md), with the σ of its
// covariance when it gives one (else bag.navsat_sigma_m); `import` writes them to gnss.csv, and
// the imported sequence replays as the bag.
TEST_F(Ros2BagReplay, NavSatFixesHoldTheGraphAndImportWritesThem) {
  const fs::path tiny_cloud = kData / "sim_tiny_cloud";
  Ros2Recording how;
  how.navsat_track_sigma_m = 0.02;  // one fix of the true position with every frame
  const fs::path bag = WriteSequenceRos2Bag(tiny_cloud, dir_ / "fixes.mcap", how);
  const std::string keys = kBagKeys + " --set bag.sensor=cloud";
  const nlohmann::json summary = Replay(bag, "bag", keys);
  ASSERT_TRUE(summary.contains("graph")) << summary.dump();
  // Five frames, five fixes: the origin's (no covariance: 5 m) stands for frame 0's, which has
  // the same stamp.
  EXPECT_EQ(summary["graph"]["gnss_fixes"], 5);
  EXPECT_EQ(summary["graph"]["gnss_used"], 5);
  EXPECT_TRUE(summary["graph"]["solved"].get<bool>());
  EXPECT_TRUE(fs::exists(dir_ / "bag" / "trajectory_f2f.tum"));

  const fs::path seq = dir_ / "imported";
  const CommandResult r =
      Rovermap("import " + bag.string() + " --out " + seq.string() + " " + keys);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["gnss_fixes"], 5);
  const std::vector<rovermap::io::GnssFix> fixes = rovermap::io::ReadGnssCsv(seq / "gnss.csv");
  ASSERT_EQ(fixes.size(), 5u);
  EXPECT_EQ(fixes[0].sigma_enu_m, Eigen::Vector3d::Constant(5.0));
  EXPECT_NEAR(fixes[1].sigma_enu_m.x(), 0.02, 1e-12);
  EXPECT_NEAR(fixes[1].sigma_enu_m.z(), 0.02, 1e-12);
  Replay(seq, "seq");
  for (const char* file : {"trajectory.tum", "trajectory_f2f.tum", "dem.tif"}) {
    EXPECT_EQ(Slurp(dir_ / "seq" / file), Slurp(dir_ / "bag" / file)) << file;
  }
  // Without the track (the origin's fix alone) there is no graph.
  const fs::path origin_only = WriteSequenceRos2Bag(tiny_cloud, dir_ / "origin.mcap");
  EXPECT_FALSE(Replay(origin_only, "origin", keys).contains("graph"));
}
