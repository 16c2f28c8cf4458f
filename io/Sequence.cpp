#include "io/Sequence.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <vector>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "io/Rpy.hpp"
#include "io/SequenceYaml.hpp"

namespace rovermap::io {
namespace fs = std::filesystem;

namespace {

// What frames/ holds for one index.
struct FrameFiles {
  bool left = false;
  bool right = false;
  bool ply = false;
};

}  // namespace

bool ParseFrameFileName(const std::string& name, std::size_t* index, std::string* kind) {
  const auto dot = name.find('.');
  if (dot == 0 || dot == std::string::npos || dot > 12) return false;
  for (std::size_t i = 0; i < dot; ++i) {
    if (name[i] < '0' || name[i] > '9') return false;
  }
  const std::string rest = name.substr(dot + 1);
  if (rest != "left.png" && rest != "right.png" && rest != "ply" && rest != "odom" &&
      rest != "gt") {
    return false;
  }
  *index = std::stoul(name.substr(0, dot));
  *kind = rest;
  return true;
}

cv::Mat ReadStereoImage(const fs::path& file, const CameraModel& camera) {
  const cv::Mat image = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw IoError(file.string() + ": cannot read or decode the image");
  if (image.cols != camera.width || image.rows != camera.height) {
    throw IoError(file.string() + ": image is " + std::to_string(image.cols) + "x" +
                  std::to_string(image.rows) + ", sequence.yaml camera is " +
                  std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  return image;
}

void ReadFrameData(const fs::path& stem, const SequenceInfo& info, Frame* frame) {
  if (info.sensor_type == SensorType::kStereo) {
    frame->file = stem.string() + ".left.png";
    frame->left = ReadStereoImage(frame->file, *info.camera);
    frame->right = ReadStereoImage(stem.string() + ".right.png", *info.camera);
  } else {
    frame->file = stem.string() + ".ply";
    frame->cloud = ReadPly(frame->file, NonFinite::kKeep);  // the mapper drops and counts them
  }
}

void WriteSequenceYaml(const fs::path& dir, const SequenceInfo& info, const std::string& header) {
  const Eigen::Quaterniond q = info.body_sensor_quaternion
                                   ? *info.body_sensor_quaternion
                                   : Eigen::Quaterniond(info.T_body_sensor.linear());
  const Eigen::Vector3d& t = info.T_body_sensor.translation();
  char buffer[1024];
  std::string yaml = "# " + header + "\n";
  std::snprintf(buffer, sizeof(buffer),
                "sensor:\n"
                "  type: %s\n"
                "  T_body_sensor:\n"
                "    translation: [%.17g, %.17g, %.17g]\n"
                "    quaternion: [%.17g, %.17g, %.17g, %.17g]\n",
                info.sensor_type == SensorType::kCloud ? "cloud" : "stereo", t.x(), t.y(), t.z(),
                q.x(), q.y(), q.z(), q.w());
  yaml += buffer;
  if (info.calibration_sigma) {
    std::snprintf(buffer, sizeof(buffer),
                  "  calibration_sigma:\n    rotation_deg: %.17g\n    scale: %.17g\n",
                  info.calibration_sigma->rotation_deg, info.calibration_sigma->scale);
    yaml += buffer;
  }
  if (info.camera) {
    const CameraModel& c = *info.camera;
    std::snprintf(buffer, sizeof(buffer),
                  "camera:\n"
                  "  width: %d\n  height: %d\n  fx: %.17g\n  fy: %.17g\n  cx: %.17g\n  cy: %.17g\n"
                  "  baseline: %.17g\n",
                  c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.baseline_m);
    yaml += buffer;
  }
  std::snprintf(buffer, sizeof(buffer),
                "origin:\n  latitude: %.17g\n  longitude: %.17g\n  altitude: %.17g\n"
                "frame_rate: %.17g\n",
                info.origin.latitude_deg, info.origin.longitude_deg, info.origin.altitude_m,
                info.frame_rate_hz);
  yaml += buffer;
  if (info.body != "earth") yaml += "body: " + info.body + "\n";
  WriteFileAtomically(dir / "sequence.yaml", yaml);
}

void WriteFrameData(const fs::path& stem, const SequenceInfo& info, const Frame& frame) {
  if (info.sensor_type == SensorType::kCloud) {
    WritePly(stem.string() + ".ply", frame.cloud);
    return;
  }
  for (const bool left : {true, false}) {
    std::vector<unsigned char> png;
    const std::string file = stem.string() + (left ? ".left.png" : ".right.png");
    if (!cv::imencode(".png", left ? frame.left : frame.right, png)) {
      throw IoError(file + ": cannot encode the image as PNG");
    }
    WriteFileAtomically(file,
                        std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
  }
}

std::string FrameStem(std::size_t index) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%06zu", index);
  return buffer;
}

SequenceInfo ReadSequenceInfo(const fs::path& sequence_dir) {
  const SequenceYaml yaml = ReadSequenceYaml(sequence_dir / "sequence.yaml");
  SequenceInfo info;
  info.directory = sequence_dir;
  info.sensor_type = yaml.sensor_type == "cloud" ? SensorType::kCloud : SensorType::kStereo;
  info.camera = yaml.camera;
  info.T_body_sensor.translation() =
      Eigen::Vector3d(yaml.translation[0], yaml.translation[1], yaml.translation[2]);
  if (yaml.rotation_rpy_deg) {
    const auto& rpy = *yaml.rotation_rpy_deg;
    info.T_body_sensor.linear() = RotationFromRpyDeg(rpy[0], rpy[1], rpy[2]);
  } else {
    const auto& q = *yaml.quaternion_xyzw;
    info.body_sensor_quaternion = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
    info.T_body_sensor.linear() = RotationFromQuaternion(*info.body_sensor_quaternion);
  }
  info.calibration_sigma = yaml.calibration_sigma;
  info.origin = {yaml.latitude_deg, yaml.longitude_deg, yaml.altitude_m};
  info.frame_rate_hz = yaml.frame_rate_hz;
  info.body = yaml.body;
  return info;
}

SequenceReader::SequenceReader(const fs::path& sequence_dir) {
  std::error_code error;
  if (!fs::is_directory(sequence_dir, error)) {
    throw IoError(sequence_dir.string() + ": not a sequence directory (no such directory)");
  }
  info_ = ReadSequenceInfo(sequence_dir);

  const fs::path odometry_file = sequence_dir / "odometry.tum";
  if (!fs::is_regular_file(odometry_file, error)) {
    throw IoError(odometry_file.string() + ": missing (one dead-reckoning pose per frame)");
  }
  odometry_ = ReadTum(odometry_file);
  if (odometry_.empty()) throw IoError(odometry_file.string() + ": no poses");

  // GNSS fixes for the pose graph (docs/graph.md), checked with the rest before any frame.
  const fs::path gnss_file = sequence_dir / "gnss.csv";
  if (fs::exists(gnss_file, error)) gnss_ = ReadGnssCsv(gnss_file);

  const fs::path truth_file = sequence_dir / "groundtruth.tum";
  if (fs::exists(truth_file, error)) {
    groundtruth_ = ReadTum(truth_file);
    if (groundtruth_.size() != odometry_.size()) {
      throw IoError(truth_file.string() + ": " + std::to_string(groundtruth_.size()) +
                    " poses, but odometry.tum has " + std::to_string(odometry_.size()));
    }
    for (std::size_t i = 0; i < odometry_.size(); ++i) {
      if (std::abs(groundtruth_[i].timestamp - odometry_[i].timestamp) > 1e-6) {
        throw IoError(truth_file.string() + ":" + std::to_string(groundtruth_[i].line) +
                      ": timestamp " + std::to_string(groundtruth_[i].timestamp) +
                      " does not match odometry.tum:" + std::to_string(odometry_[i].line) + " (" +
                      std::to_string(odometry_[i].timestamp) + ") for frame " + std::to_string(i));
      }
    }
  }

  // One listing of frames/ (names only) against the poses.
  const fs::path frames_dir = sequence_dir / "frames";
  if (!fs::is_directory(frames_dir, error)) {
    throw IoError(frames_dir.string() + ": missing frames directory");
  }
  const bool stereo = info_.sensor_type == SensorType::kStereo;
  std::map<std::size_t, FrameFiles> found;
  fs::directory_iterator listing(frames_dir, error);
  if (error) throw IoError(frames_dir.string() + ": cannot list (" + error.message() + ")");
  for (const fs::directory_entry& entry : listing) {
    const std::string name = entry.path().filename().string();
    std::size_t index = 0;
    std::string kind;
    // Other files are not ours (an inbox's .odom and .gt lines neither: odometry.tum holds them).
    if (!ParseFrameFileName(name, &index, &kind) || kind == "odom" || kind == "gt") continue;
    if (name.compare(0, name.find('.'), FrameStem(index)) != 0) {
      throw IoError(entry.path().string() + ": frame files are named " + FrameStem(index) + "." +
                    kind + " (six or more digits, zero-padded)");
    }
    if (stereo == (kind == "ply")) {
      throw IoError(entry.path().string() + ": a " + (stereo ? "cloud" : "stereo") +
                    " frame in a sequence with sensor.type: " + (stereo ? "stereo" : "cloud"));
    }
    if (index >= odometry_.size()) {
      throw IoError(entry.path().string() + ": frame " + std::to_string(index) +
                    " has no pose: odometry.tum has " + std::to_string(odometry_.size()) +
                    " lines (frames 0.." + std::to_string(odometry_.size() - 1) + ")");
    }
    FrameFiles& files = found[index];
    if (kind == "left.png") files.left = true;
    if (kind == "right.png") files.right = true;
    if (kind == "ply") files.ply = true;
  }
  for (std::size_t i = 0; i < odometry_.size(); ++i) {
    const auto it = found.find(i);
    const FrameFiles files = it == found.end() ? FrameFiles{} : it->second;
    const fs::path stem = frames_dir / FrameStem(i);
    std::string missing;
    if (stereo && !files.left) missing = stem.string() + ".left.png";
    if (stereo && files.left && !files.right) missing = stem.string() + ".right.png";
    if (!stereo && !files.ply) missing = stem.string() + ".ply";
    if (!missing.empty()) {
      throw IoError(
          missing + ": missing frame file (odometry.tum:" + std::to_string(odometry_[i].line) +
          " has a pose for frame " + std::to_string(i) + "; " + std::to_string(found.size()) +
          " of " + std::to_string(odometry_.size()) + " frames present)");
    }
  }
}

void SequenceReader::LoadFrame(Frame* frame) const {
  ReadFrameData(info_.directory / "frames" / FrameStem(frame->index), info_, frame);
}

}  // namespace rovermap::io
