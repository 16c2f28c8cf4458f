#include "mapper/FrameLoader.hpp"

#include <chrono>
#include <utility>

#include "core/Stopwatch.hpp"
#include "stereo/Stereo.hpp"

namespace rovermap::mapper {
namespace {

// The stereo error model for points that come without covariances, when the sequence has a
// camera (docs/design.md §4: it "feeds the stereo error model of the points"). Sensor frame.
void AddStereoCovariances(registration::PointCloud* cloud, const io::CameraModel& c,
                          const stereo::StereoOptions& options) {
  const stereo::StereoCamera camera = StereoCameraOf(c);
  cloud->covariances.resize(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    cloud->covariances[i] = stereo::PointCovariance(
        cloud->points[i], camera, options.disparity_sigma_px, options.pixel_sigma_px);
  }
}

void SensorToBody(registration::PointCloud* cloud, const Eigen::Isometry3d& T_body_sensor) {
  const Eigen::Matrix3d R = T_body_sensor.linear();
  for (auto& p : cloud->points) p = T_body_sensor * p;
  for (auto& n : cloud->normals) n = R * n;
  for (auto& c : cloud->covariances) c = R * c * R.transpose();
}

// "frames/000003.ply: no usable points": a bad frame's reason names its file (docs/design.md §5).
std::string AboutFile(const io::Frame& frame, const std::string& reason) {
  return frame.file.empty() ? reason : frame.file.string() + ": " + reason;
}

}  // namespace

std::size_t DropNonFinite(registration::PointCloud* cloud) {
  const bool has_normals = cloud->HasNormals();
  const bool has_cov = cloud->HasCovariances();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const bool finite = cloud->points[i].allFinite() &&
                        (!has_normals || cloud->normals[i].allFinite()) &&
                        (!has_cov || cloud->covariances[i].allFinite());
    if (!finite) continue;
    if (kept != i) {  // all finite (the usual case): nothing moves, nothing is written
      cloud->points[kept] = cloud->points[i];
      if (has_normals) cloud->normals[kept] = cloud->normals[i];
      if (has_cov) cloud->covariances[kept] = cloud->covariances[i];
    }
    ++kept;
  }
  const std::size_t dropped = cloud->size() - kept;
  cloud->points.resize(kept);
  if (has_normals) cloud->normals.resize(kept);
  if (has_cov) cloud->covariances.resize(kept);
  cloud->chain_ids.clear();  // frames are surfaces
  return dropped;
}

LoadedFrame LoadFrame(const io::Frame& frame, const SensorSetup& setup, std::size_t min_points) {
  LoadedFrame out;
  if (setup.type == io::SensorType::kStereo) {
    if (!setup.camera) {
      out.reason = AboutFile(frame, "stereo sequence without a camera model");
      return out;
    }
    const io::CameraModel& c = *setup.camera;
    const stereo::StereoCamera camera = StereoCameraOf(c);
    const auto start = std::chrono::steady_clock::now();
    stereo::StereoPointsResult points =
        stereo::ComputePoints(frame.left, frame.right, camera, setup.T_body_sensor, setup.stereo);
    if (points.status != stereo::StereoStatus::kOk) {
      out.stereo_ms = core::MsSince(start);
      out.reason = AboutFile(frame, "stereo: " + points.message);
      return out;
    }
    if (setup.image_landmarks)
      out.landmarks = stereo::DetectLandmarks(frame.left, frame.right, camera, setup.image);
    out.stereo_ms = core::MsSince(start);
    out.input_points = points.pixels;
    out.cloud = std::move(points.cloud);
    out.fill = std::move(points.fill);
    out.spacing_m = points.spacing_m;
    DropNonFinite(&out.fill);
  } else {
    out.input_points = frame.cloud.size();
    out.cloud = frame.cloud;
    if (!out.cloud.HasCovariances() && setup.camera) {
      AddStereoCovariances(&out.cloud, *setup.camera, setup.stereo);
    }
    SensorToBody(&out.cloud, setup.T_body_sensor);
  }
  out.dropped_nonfinite = DropNonFinite(&out.cloud);
  if (out.cloud.size() < min_points) {
    out.reason =
        (out.cloud.empty() ? std::string("no usable points")
                           : "too few points (" + std::to_string(out.cloud.size()) +
                                 " < mapper.min_points " + std::to_string(min_points) + ")");
    if (out.dropped_nonfinite > 0)
      out.reason += ", " + std::to_string(out.dropped_nonfinite) + " non-finite dropped";
    out.reason = AboutFile(frame, out.reason);
    return out;
  }
  out.ok = true;
  return out;
}

}  // namespace rovermap::mapper
