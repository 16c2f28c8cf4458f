#pragma once
// What a recording is and what one of its frames holds, wherever they come from (a sequence
// directory, docs/design.md §4, or a bag).

#include <Eigen/Geometry>
#include <cstddef>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "io/CameraModel.hpp"
#include "io/Georeference.hpp"  // GeodeticOrigin
#include "io/RigCalibration.hpp"
#include "io/SensorType.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::io {

/// Everything sequence.yaml says (or what a recording in another form says instead).
struct SequenceInfo {
  std::filesystem::path directory;  ///< the sequence directory (or recording file)
  SensorType sensor_type = SensorType::kStereo;
  std::optional<CameraModel> camera;  ///< always set for stereo
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  /// The unit quaternion T_body_sensor's rotation was made from (RotationFromQuaternion), when
  /// it was: WriteSequenceYaml writes it as it is, so that the rotation reads back bit for bit
  /// (a quaternion recomputed from the matrix can differ in its last bit, and the matcher's
  /// stopping point with it).
  std::optional<Eigen::Quaterniond> body_sensor_quaternion;
  /// How well the rig is calibrated, when the recording says (sensor.calibration_sigma); else
  /// the mapper assumes a field calibration's (mapper.rig_*_sigma).
  std::optional<RigCalibrationSigma> calibration_sigma;
  GeodeticOrigin origin;  ///< of the world (local ENU) frame
  double frame_rate_hz = 0.0;
  std::string body = "earth";  ///< earth|moon|mars
};

/// One frame of a recording.
struct Frame {
  std::size_t index = 0;
  double timestamp = 0.0;  ///< [s], of the odometry pose (odometry.tum)
  Eigen::Isometry3d T_world_body_odom = Eigen::Isometry3d::Identity();
  std::optional<Eigen::Isometry3d> T_world_body_truth;  ///< when the recording has ground truth
  cv::Mat left;                    ///< stereo: 8-bit grey, camera.width × camera.height
  cv::Mat right;                   ///< stereo: same size as left
  registration::PointCloud cloud;  ///< cloud: points in the sensor frame
  std::filesystem::path file;      ///< left image or PLY file (for messages)
};

}  // namespace rovermap::io
