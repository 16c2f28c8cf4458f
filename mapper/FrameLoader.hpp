#pragma once
// Step 1 of the pipeline: a frame as read from disk -> body-frame points with per-point
// covariances and normals, or the reason it cannot be used.

#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <string>

#include "io/CameraModel.hpp"
#include "io/Sequence.hpp"
#include "registration/PointCloud.hpp"
#include "stereo/ImageMotion.hpp"
#include "stereo/Stereo.hpp"
#include "stereo/StereoOptions.hpp"

namespace rovermap::mapper {

/// How a sequence's frames become points: what sequence.yaml says plus the stereo options.
struct SensorSetup {
  io::SensorType type = io::SensorType::kStereo;
  std::optional<io::CameraModel> camera;  ///< required for stereo
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  stereo::StereoOptions stereo;
  /// Detect the left image's corners with their depth (LoadedFrame::landmarks) for the image
  /// check, with these options.
  bool image_landmarks = false;
  stereo::ImageMotionOptions image;
};

/// One frame's points in the body frame.
struct LoadedFrame {
  bool ok = false;
  std::string reason;              ///< why not ok ("stereo: ...", "no finite points", ...)
  registration::PointCloud cloud;  ///< body frame; covariances when the sensor gives them
  /// Stereo only: points between neighbouring pixels, for the DEM alone (stereo.fill_spacing_m).
  registration::PointCloud fill;
  /// Stereo only: the left image's corners with their depth, for the image check (step 5b).
  stereo::ImageLandmarks landmarks;
  std::size_t input_points = 0;       ///< cloud: points read; stereo: pixels examined [count]
  std::size_t dropped_nonfinite = 0;  ///< non-finite points or covariances [count]
  double stereo_ms = 0.0;             ///< disparity + triangulation (stereo only)
  /// Stereo only: the points' median spacing from their pixel neighbours
  /// (StereoPointsResult::spacing_m) [m]; 0 = unknown.
  double spacing_m = 0.0;
};

/// The stereo module's camera from a sequence's camera model (rectified: no disparity offset).
inline stereo::StereoCamera StereoCameraOf(const io::CameraModel& c) {
  return {c.fx, c.fy, c.cx, c.cy, c.baseline_m, 0.0};
}

/// Keeps the points (with their normals and covariances) that are all finite, in order; clears
/// chain_ids (frames are surfaces). Returns how many were dropped.
std::size_t DropNonFinite(registration::PointCloud* cloud);

/// Turns `frame` into body-frame points: stereo::ComputePoints for a stereo pair; for a cloud,
/// points, normals and covariances moved from the sensor frame by T_body_sensor (a cloud without
/// covariances gets the stereo error model's, stereo::PointCovariance, when the sequence has a
/// camera). Non-finite
/// points are dropped and counted. Fewer than `min_points` usable points: ok = false with the
/// reason. Never throws.
LoadedFrame LoadFrame(const io::Frame& frame, const SensorSetup& setup, std::size_t min_points);

}  // namespace rovermap::mapper
