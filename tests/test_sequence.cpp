// Sequence directories (docs/design.md §4): reading, streaming, and every validation error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "io/Rpy.hpp"
#include "io/Sequence.hpp"
#include "io/Tum.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

using rovermap::testing::Contains;

std::string ErrorOf(const std::function<void()>& f) {
  return rovermap::testing::ErrorOf<IoError>(f);
}

void Write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

const char* kCloudYaml = R"(sensor:
  type: cloud
  T_body_sensor:
    translation: [0.5, 0.0, 1.2]
    rotation_rpy_deg: [-90, 0, -90]
origin: {latitude: 46.5, longitude: 6.6, altitude: 400}
frame_rate: 2
)";

const char* kStereoYaml = R"(sensor:
  type: stereo
  T_body_sensor:
    translation: [0, 0, 1]
    quaternion: [-0.5, 0.5, -0.5, 0.5]
camera:
  width: 32
  height: 24
  fx: 30
  fy: 30
  cx: 16
  cy: 12
  baseline: 0.2
origin: {latitude: 0, longitude: 0, altitude: 0}
frame_rate: 10
body: mars
)";

std::string TumLines(int n, double t0 = 0.0) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  for (int i = 0; i < n; ++i) {
    text += std::to_string(t0 + 0.5 * i) + " " + std::to_string(0.3 * i) + " 0 0 0 0 0 1\n";
  }
  return text;
}

// A fresh cloud sequence of `n` frames in the test's temporary directory.
fs::path MakeCloudSequence(const std::string& name, int n) {
  const fs::path dir = rovermap::testing::ScratchDir() / name;
  fs::remove_all(dir);
  fs::create_directories(dir / "frames");
  Write(dir / "sequence.yaml", kCloudYaml);
  Write(dir / "odometry.tum", TumLines(n));
  Write(dir / "groundtruth.tum", TumLines(n));
  for (int i = 0; i < n; ++i) {
    registration::PointCloud cloud;
    for (int k = 0; k < 5; ++k) cloud.points.emplace_back(i, k, 2.0 + k);
    WritePly(dir / "frames" / (FrameStem(i) + ".ply"), cloud);
  }
  return dir;
}

fs::path MakeStereoSequence(const std::string& name, int n) {
  const fs::path dir = rovermap::testing::ScratchDir() / name;
  fs::remove_all(dir);
  fs::create_directories(dir / "frames");
  Write(dir / "sequence.yaml", kStereoYaml);
  Write(dir / "odometry.tum", TumLines(n));
  for (int i = 0; i < n; ++i) {
    const cv::Mat image(24, 32, CV_8U, cv::Scalar(10 * i));
    cv::imwrite((dir / "frames" / (FrameStem(i) + ".left.png")).string(), image);
    cv::imwrite((dir / "frames" / (FrameStem(i) + ".right.png")).string(), image);
  }
  return dir;
}

TEST(Sequence, CloudSequenceStreamsFramesInOrder) {
  const fs::path dir = MakeCloudSequence("cloud_ok", 3);
  SequenceReader reader(dir);
  EXPECT_EQ(reader.frame_count(), 3u);
  EXPECT_TRUE(reader.has_groundtruth());
  EXPECT_EQ(reader.info().sensor_type, SensorType::kCloud);
  EXPECT_FALSE(reader.info().camera.has_value());
  EXPECT_DOUBLE_EQ(reader.info().frame_rate_hz, 2.0);
  EXPECT_EQ(reader.info().body, "earth");
  EXPECT_DOUBLE_EQ(reader.info().origin.latitude_deg, 46.5);
  // rpy [-90, 0, -90]: a level forward-looking OpenCV camera, z (optical axis) -> body x,
  // x (right) -> body -y, y (down) -> body -z.
  const Eigen::Matrix3d R = reader.info().T_body_sensor.linear();
  EXPECT_TRUE((R * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE((R * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE((R * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_TRUE(reader.info().T_body_sensor.translation().isApprox(Eigen::Vector3d(0.5, 0, 1.2)));

  Frame frame;
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(reader.next_index(), i);
    ASSERT_TRUE(reader.Next(&frame));
    EXPECT_EQ(frame.index, i);
    EXPECT_DOUBLE_EQ(frame.timestamp, 0.5 * i);
    EXPECT_NEAR(frame.T_world_body_odom.translation().x(), 0.3 * i, 1e-9);
    ASSERT_TRUE(frame.T_world_body_truth.has_value());
    ASSERT_EQ(frame.cloud.size(), 5u);
    EXPECT_DOUBLE_EQ(frame.cloud.points[0].x(), static_cast<double>(i));
  }
  EXPECT_FALSE(reader.Next(&frame));
  reader.Rewind();
  ASSERT_TRUE(reader.Next(&frame));
  EXPECT_EQ(frame.index, 0u);
}

TEST(Sequence, StereoSequenceWithQuaternionAndBody) {
  const fs::path dir = MakeStereoSequence("stereo_ok", 2);
  SequenceReader reader(dir);
  ASSERT_TRUE(reader.info().camera.has_value());
  EXPECT_EQ(reader.info().camera->width, 32);
  EXPECT_DOUBLE_EQ(reader.info().camera->baseline_m, 0.2);
  EXPECT_EQ(reader.info().body, "mars");
  EXPECT_FALSE(reader.has_groundtruth());
  // The quaternion is the same level camera as rpy [-90, 0, -90].
  const Eigen::Matrix3d R = reader.info().T_body_sensor.linear();
  EXPECT_TRUE((R * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX(), 1e-9));
  Frame frame;
  ASSERT_TRUE(reader.Next(&frame));
  ASSERT_TRUE(reader.Next(&frame));
  EXPECT_EQ(frame.left.cols, 32);
  EXPECT_EQ(frame.left.type(), CV_8U);
  EXPECT_EQ(frame.right.at<unsigned char>(3, 3), 10);
  EXPECT_FALSE(reader.Next(&frame));
}

TEST(Sequence, TumRoundTrip) {
  const fs::path file = rovermap::testing::ScratchDir() / "rovermap_test_roundtrip.tum";
  std::vector<StampedPose> poses(2);
  poses[0].timestamp = 1.25;
  poses[1].timestamp = 2.5;
  poses[1].T_world_body.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  poses[1].T_world_body.translation() = Eigen::Vector3d(1.0 / 3, -2, 1e-7);
  WriteTum(file, poses);
  const std::vector<StampedPose> back = ReadTum(file);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].line, 3);
  EXPECT_DOUBLE_EQ(back[1].timestamp, 2.5);
  EXPECT_TRUE(back[1].T_world_body.isApprox(poses[1].T_world_body, 1e-12));
}

// A TUM file keeps each pose's quaternion as it was made from (a bag's, a TUM line's), so that
// it reads back to the same matrix, to the bit; a stale one (the matrix changed since) is not
// written, nor is qw < 0.
TEST(Sequence, TumKeepsEachPosesQuaternionToTheBit) {
  const fs::path file = rovermap::testing::ScratchDir() / "rovermap_test_quaternions.tum";
  std::srand(11);
  std::vector<StampedPose> poses(200);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::Vector4d::Random()).normalized();
    poses[i].timestamp = static_cast<double>(i);
    poses[i].T_world_body.linear() = RotationFromQuaternion(q);
    poses[i].quaternion = q;
  }
  WriteTum(file, poses);
  std::vector<StampedPose> back = ReadTum(file);
  ASSERT_EQ(back.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    EXPECT_TRUE(back[i].T_world_body.linear() == poses[i].T_world_body.linear()) << i;
    const Eigen::Quaterniond& q = *poses[i].quaternion;
    EXPECT_EQ(back[i].quaternion->coeffs(), (q.w() < 0 ? -q.coeffs() : q.coeffs()).eval()) << i;
  }
  // Read and written again: the same file.
  const std::string text = ReadWholeFile(file);
  WriteTum(file, back);
  EXPECT_EQ(ReadWholeFile(file), text);

  back[0].T_world_body.linear() = Eigen::Matrix3d::Identity();  // its quaternion now stale
  WriteTum(file, back);
  EXPECT_TRUE(ReadTum(file)[0].T_world_body.linear() == Eigen::Matrix3d::Identity());
}

// sequence.yaml keeps T_body_sensor's rotation as a quaternion: the one it was made from
// reads back to the same matrix, to the bit; one recomputed from the matrix often does not.
TEST(Sequence, YamlKeepsTheBodySensorQuaternionToTheBit) {
  const fs::path dir = rovermap::testing::ScratchDir() / "rovermap_test_quaternion";
  fs::create_directories(dir);
  std::srand(7);
  int recomputed_differs = 0;
  for (int i = 0; i < 200; ++i) {
    SequenceInfo info;
    info.sensor_type = SensorType::kCloud;
    info.frame_rate_hz = 10.0;
    const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::Vector4d::Random()).normalized();
    info.T_body_sensor.linear() = RotationFromQuaternion(q);
    info.T_body_sensor.translation() = Eigen::Vector3d::Random();
    info.body_sensor_quaternion = q;
    WriteSequenceYaml(dir, info, "test");
    const SequenceInfo back = ReadSequenceInfo(dir);
    ASSERT_TRUE(back.body_sensor_quaternion);
    EXPECT_EQ(back.body_sensor_quaternion->coeffs(), q.coeffs());
    EXPECT_TRUE(back.T_body_sensor.linear() == info.T_body_sensor.linear()) << i;
    EXPECT_TRUE(back.T_body_sensor.translation() == info.T_body_sensor.translation()) << i;

    info.body_sensor_quaternion.reset();  // the former way: a quaternion from the matrix
    WriteSequenceYaml(dir, info, "test");
    recomputed_differs +=
        ReadSequenceInfo(dir).T_body_sensor.linear() != info.T_body_sensor.linear();
  }
  EXPECT_GT(recomputed_differs, 0);  // measured: 161 of 200
}

// sensor.calibration_sigma: how well the rig is calibrated, when the recording says; written
// back as read, absent when not stated (the mapper then assumes mapper.rig_*_sigma).
TEST(Sequence, CalibrationSigmaIsReadAndWrittenBack) {
  const fs::path dir = MakeStereoSequence("calibration_sigma", 1);
  EXPECT_FALSE(SequenceReader(dir).info().calibration_sigma.has_value());
  std::string yaml = kStereoYaml;
  const std::string after = "    quaternion: [-0.5, 0.5, -0.5, 0.5]\n";
  yaml.insert(yaml.find(after) + after.size(),
              "  calibration_sigma: {rotation_deg: 0.25, scale: 0.004}\n");
  Write(dir / "sequence.yaml", yaml);
  SequenceInfo info = SequenceReader(dir).info();
  ASSERT_TRUE(info.calibration_sigma.has_value());
  EXPECT_EQ(info.calibration_sigma->rotation_deg, 0.25);
  EXPECT_EQ(info.calibration_sigma->scale, 0.004);
  info.calibration_sigma = RigCalibrationSigma{0.1 / 3.0, 0.0};
  WriteSequenceYaml(dir, info, "test");
  const SequenceInfo back = ReadSequenceInfo(dir);
  ASSERT_TRUE(back.calibration_sigma.has_value());
  EXPECT_EQ(back.calibration_sigma->rotation_deg, 0.1 / 3.0);  // to the bit
  EXPECT_EQ(back.calibration_sigma->scale, 0.0);
  info.calibration_sigma.reset();
  WriteSequenceYaml(dir, info, "test");
  EXPECT_FALSE(ReadSequenceInfo(dir).calibration_sigma.has_value());
}

TEST(Sequence, ShippedSimulatedSequencesAreValid) {
  const fs::path datasets(ROVERMAP_DATASETS_DIR);
  for (const char* name : {"sim_tiny_cloud", "sim_tiny_stereo"}) {
    SequenceReader reader(datasets / name);
    EXPECT_TRUE(reader.has_groundtruth()) << name;
    std::size_t frames = 0;
    Frame frame;
    while (reader.Next(&frame)) {
      ++frames;
      if (reader.info().sensor_type == SensorType::kCloud) {
        EXPECT_GT(frame.cloud.size(), 500u);
      } else {
        EXPECT_EQ(frame.left.size(), frame.right.size());
      }
    }
    EXPECT_EQ(frames, reader.frame_count()) << name;
  }
}

// ---- errors: each names the file (and line) at fault --------------------------------------

TEST(SequenceErrors, MissingFrameFile) {
  const fs::path dir = MakeCloudSequence("missing_frame", 4);
  fs::remove(dir / "frames" / "000002.ply");
  const std::string message = ErrorOf([&] { SequenceReader reader(dir); });
  EXPECT_TRUE(Contains(message, "000002.ply: missing frame file"));
  EXPECT_TRUE(Contains(message, "odometry.tum:4"));
}

TEST(SequenceErrors, MissingRightImage) {
  const fs::path dir = MakeStereoSequence("missing_right", 2);
  fs::remove(dir / "frames" / "000001.right.png");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }), "000001.right.png: missing"));
}

TEST(SequenceErrors, MoreFramesThanOdometryLines) {
  const fs::path dir = MakeCloudSequence("extra_frame", 3);
  Write(dir / "odometry.tum", TumLines(2));
  Write(dir / "groundtruth.tum", TumLines(2));
  const std::string message = ErrorOf([&] { SequenceReader reader(dir); });
  EXPECT_TRUE(Contains(message, "000002.ply: frame 2 has no pose: odometry.tum has 2 lines"));
}

TEST(SequenceErrors, GroundTruthLineCountMismatch) {
  const fs::path dir = MakeCloudSequence("gt_count", 3);
  Write(dir / "groundtruth.tum", TumLines(2));
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "groundtruth.tum: 2 poses, but odometry.tum has 3"));
}

TEST(SequenceErrors, GroundTruthTimestampMismatch) {
  const fs::path dir = MakeCloudSequence("gt_time", 3);
  Write(dir / "groundtruth.tum",
        "# header\n0 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n1.7 0 0 0 0 0 0 1\n");
  const std::string message = ErrorOf([&] { SequenceReader reader(dir); });
  EXPECT_TRUE(Contains(message, "groundtruth.tum:4: timestamp"));
  EXPECT_TRUE(Contains(message, "odometry.tum:4"));
}

TEST(SequenceErrors, NonMonotonicTimestamps) {
  const fs::path dir = MakeCloudSequence("non_monotonic", 3);
  Write(dir / "odometry.tum", "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "odometry.tum:3: timestamp 1.000000 is not after the previous one"));
}

TEST(SequenceErrors, NonUnitQuaternion) {
  const fs::path dir = MakeCloudSequence("non_unit", 2);
  Write(dir / "odometry.tum", "0 0 0 0 0 0 0 1\n# comment\n1 0 0 0 0 0 0.5 1\n");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "odometry.tum:3: quaternion is not unit length"));
}

TEST(SequenceErrors, WrongColumnCountAndBadNumbers) {
  const fs::path dir = MakeCloudSequence("columns", 2);
  Write(dir / "odometry.tum", "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "odometry.tum:2: 7 columns, expected 8"));
  Write(dir / "odometry.tum", "0 0 0 0 0 0 0 1\n1 0 x 0 0 0 0 1\n");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "odometry.tum:2: not a finite number 'x'"));
}

TEST(SequenceErrors, MissingOdometryAndDirectory) {
  const fs::path dir = MakeCloudSequence("no_odometry", 2);
  fs::remove(dir / "odometry.tum");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }), "odometry.tum: missing"));
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir / "nope"); }), "nope: not a"));
  fs::remove(dir / "sequence.yaml");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }), "sequence.yaml: missing"));
}

// Replaces `from` by `to` in the stereo sequence.yaml and returns the error message.
std::string StereoYamlError(const std::string& from, const std::string& to) {
  const fs::path dir = MakeStereoSequence("yaml", 1);
  std::string yaml = kStereoYaml;
  const auto at = yaml.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  yaml.replace(at, from.size(), to);
  Write(dir / "sequence.yaml", yaml);
  return ErrorOf([&] { SequenceReader reader(dir); });
}

TEST(SequenceErrors, BadCalibration) {
  EXPECT_TRUE(
      Contains(StereoYamlError("fx: 30", "fx: -30"), "sequence.yaml:9: camera.fx: must be > 0"));
  EXPECT_TRUE(Contains(StereoYamlError("baseline: 0.2", "baseline: 0"),
                       "sequence.yaml:13: camera.baseline: must be > 0"));
  EXPECT_TRUE(Contains(StereoYamlError("cx: 16", "cx: 40"),
                       "sequence.yaml:11: camera.cx: principal point outside"));
  EXPECT_TRUE(Contains(StereoYamlError("width: 32", "width: 32.5"),
                       "sequence.yaml:7: camera.width: expected an integer"));
  EXPECT_TRUE(
      Contains(StereoYamlError("fy: 30", "fy: abc"), "camera.fy: expected a finite number"));
  EXPECT_TRUE(Contains(StereoYamlError("  fy: 30\n", ""), "camera.fy: missing"));
  EXPECT_TRUE(Contains(StereoYamlError("frame_rate: 10", "frame_rate: 0"),
                       "sequence.yaml:15: frame_rate: must be > 0"));
  EXPECT_TRUE(Contains(StereoYamlError("[-0.5, 0.5, -0.5, 0.5]", "[0, 0, 0, 2]"),
                       "sensor.T_body_sensor.quaternion: not a unit quaternion"));
  EXPECT_TRUE(Contains(StereoYamlError("latitude: 0", "latitude: 91"),
                       "origin.latitude: must be in [-90, 90]"));
}

TEST(SequenceErrors, UnknownKeysAndStructure) {
  EXPECT_TRUE(Contains(StereoYamlError("  baseline: 0.2\n", "  baseline: 0.2\n  k1: 0.01\n"),
                       "sequence.yaml:14: camera.k1: unknown key"));
  EXPECT_TRUE(Contains(StereoYamlError("body: mars", "body: venus"),
                       "body: must be one of earth|moon|mars (got venus)"));
  EXPECT_TRUE(
      Contains(StereoYamlError("type: stereo", "type: lidar"), "sensor.type: must be one of"));
  EXPECT_TRUE(Contains(StereoYamlError("    quaternion: [-0.5, 0.5, -0.5, 0.5]\n", ""),
                       "sensor.T_body_sensor: missing rotation_rpy_deg (or quaternion)"));
  EXPECT_TRUE(Contains(StereoYamlError("translation: [0, 0, 1]", "translation: [0, 1]"),
                       "sensor.T_body_sensor.translation: expected a list of 3 numbers"));
  EXPECT_TRUE(Contains(StereoYamlError("camera:\n", "camera_:\n"), "camera_: unknown key"));
  EXPECT_TRUE(Contains(StereoYamlError("frame_rate: 10\n", "frame_rate: [10\n"), "invalid YAML"));
}

TEST(SequenceErrors, BadCalibrationSigma) {
  const std::string at = "    quaternion: [-0.5, 0.5, -0.5, 0.5]\n";
  auto with = [&](const std::string& sigma) {
    return StereoYamlError(at, at + "  calibration_sigma: " + sigma + "\n");
  };
  EXPECT_TRUE(
      Contains(with("{rotation_deg: -0.1, scale: 0}"),
               "sequence.yaml:6: sensor.calibration_sigma.rotation_deg: must be in [0, 10]"));
  EXPECT_TRUE(Contains(with("{rotation_deg: 0.4, scale: 0.5}"),
                       "sensor.calibration_sigma.scale: must be in [0, 0.2]"));
  EXPECT_TRUE(Contains(with("{rotation_deg: 0.4}"), "sensor.calibration_sigma.scale: missing"));
  EXPECT_TRUE(Contains(with("{rotation_deg: 0.4, scale: 0, tilt: 1}"),
                       "sensor.calibration_sigma.tilt: unknown key"));
  EXPECT_TRUE(Contains(with("0.4"), "sensor.calibration_sigma: expected a mapping"));
  EXPECT_TRUE(Contains(with("{rotation_deg: x, scale: 0}"),
                       "sensor.calibration_sigma.rotation_deg: expected a finite number"));
}

TEST(SequenceErrors, StereoNeedsCamera) {
  const fs::path dir = MakeCloudSequence("stereo_no_camera", 1);
  std::string yaml = kCloudYaml;
  yaml.replace(yaml.find("type: cloud"), 11, "type: stereo");
  Write(dir / "sequence.yaml", yaml);
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "camera: missing (required for sensor.type: stereo)"));
}

TEST(SequenceErrors, FrameOfTheWrongKind) {
  const fs::path dir = MakeStereoSequence("wrong_kind", 1);
  registration::PointCloud cloud;
  cloud.points.emplace_back(1, 2, 3);
  WritePly(dir / "frames" / "000000.ply", cloud);
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "000000.ply: a cloud frame in a sequence with sensor.type: stereo"));
}

TEST(SequenceErrors, NonCanonicalFrameName) {
  const fs::path dir = MakeCloudSequence("frame_name", 2);
  fs::rename(dir / "frames" / "000001.ply", dir / "frames" / "1.ply");
  EXPECT_TRUE(Contains(ErrorOf([&] { SequenceReader reader(dir); }),
                       "1.ply: frame files are named 000001.ply"));
}

TEST(SequenceErrors, BadImageIsReportedWhenReadAndSkippable) {
  const fs::path dir = MakeStereoSequence("bad_image", 3);
  cv::imwrite((dir / "frames" / "000001.left.png").string(), cv::Mat(10, 10, CV_8U));
  Write(dir / "frames" / "000002.right.png", "not a png");
  SequenceReader reader(dir);  // contents are checked frame by frame
  Frame frame;
  ASSERT_TRUE(reader.Next(&frame));
  EXPECT_TRUE(Contains(ErrorOf([&] { reader.Next(&frame); }),
                       "000001.left.png: image is 10x10, sequence.yaml camera is 32x24"));
  EXPECT_TRUE(
      Contains(ErrorOf([&] { reader.Next(&frame); }), "000002.right.png: cannot read or decode"));
  EXPECT_FALSE(reader.Next(&frame));
}

}  // namespace
}  // namespace rovermap::io
