#include "sim/Simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/Stopwatch.hpp"
#include "core/Units.hpp"
#include "io/FileUtil.hpp"
#include "io/Georeference.hpp"
#include "io/Gnss.hpp"
#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "io/Rpy.hpp"

namespace rovermap::sim {
namespace {

using core::kDegToRad;
namespace fs = std::filesystem;

// Hash salts: one stream per use, so that changing one part leaves the others unchanged.
constexpr std::uint64_t kSaltImageNoise = 1000;
constexpr std::uint64_t kSaltCloud = 2000;
constexpr std::uint64_t kSaltOdometry = 3000;
constexpr std::uint64_t kSaltGnss = 4000;
constexpr std::uint64_t kSaltRig = 5000;

double WrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

double Yaw(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); }

void Require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("sim: ") + what);
}

const SimOptions& Validated(const SimOptions& o) {
  Require(o.frames >= 1, "frames must be >= 1");
  Require(o.frame_rate_hz > 0 && o.speed_m_s >= 0, "frame_rate_hz > 0, speed_m_s >= 0");
  Require(
      o.terrain_size_m > 0 && o.terrain_cell_m > 0 && o.terrain_size_m / o.terrain_cell_m < 20000,
      "terrain_size_m / terrain_cell_m must be in (0, 20000)");
  Require(o.turn_radius_m > 0 && o.wheelbase_m > 0 && o.track_m > 0, "rover sizes must be > 0");
  Require(o.baseline_m > 0 && o.focal_px > 0 && o.image_width >= 16 && o.image_height >= 16,
          "camera: baseline, focal > 0, image >= 16 px");
  Require(o.cloud_stride_px >= 1, "cloud_stride_px >= 1");
  Require(o.max_range_m > 0, "max_range_m > 0");
  Require(o.disparity_locking >= 0 && o.disparity_locking <= 1, "disparity_locking in [0, 1]");
  Require(o.range_quantisation_m >= 0, "range_quantisation_m >= 0");
  Require(o.baseline_error >= 0 && o.baseline_error <= 0.2, "baseline_error in [0, 0.2]");
  Require(o.mount_error_deg >= 0 && o.mount_error_deg <= 5, "mount_error_deg in [0, 5]");
  return o;
}

}  // namespace

Simulator::Path Simulator::MakePath(const SimOptions& o) {
  // Heading as a function of arc length s: straight 0; curves (λ/R)·sin(s/λ) with λ = R/2
  // (curvature never above 1/R); loop s/R; out and back: straight, a U-turn of radius R
  // halfway, straight back 2R beside the way out.
  const double length = o.frames * o.speed_m_s / o.frame_rate_hz;
  const double turn_start = 0.5 * (length - M_PI * o.turn_radius_m);
  auto heading = [&](double s) {
    switch (o.path) {
      case PathShape::kStraight:
        return 0.0;
      case PathShape::kCurves: {
        const double lambda = 0.5 * o.turn_radius_m;
        return (lambda / o.turn_radius_m) * std::sin(s / lambda);
      }
      case PathShape::kLoop:
        return s / o.turn_radius_m;
      case PathShape::kOutAndBack:
        return std::clamp((s - turn_start) / o.turn_radius_m, 0.0, M_PI);
    }
    return 0.0;
  };
  Path path;
  const double step = o.speed_m_s / o.frame_rate_hz;
  const int sub = 50;
  Eigen::Vector2d p(0, 0);
  double s = 0;
  for (int k = 0; k < o.frames; ++k) {
    path.frame_xy.push_back(p);
    path.frame_heading.push_back(heading(s));
    for (int i = 0; i < sub; ++i) {  // midpoint integration
      const double ds = step / sub;
      const double h = heading(s + 0.5 * ds);
      p += ds * Eigen::Vector2d(std::cos(h), std::sin(h));
      s += ds;
      path.dense_xy.push_back(p);
    }
  }
  path.dense_xy.insert(path.dense_xy.begin(), Eigen::Vector2d(0, 0));
  // The frames are driven from the start pose; dense_xy stays the path from the default start
  // pose (the origin, heading east), so that the rocks do not depend on the start pose.
  const double start_yaw = o.start_yaw_deg * kDegToRad;
  const Eigen::Rotation2Dd R_start(start_yaw);
  const Eigen::Vector2d start(o.start_x_m, o.start_y_m);
  for (std::size_t k = 0; k < path.frame_xy.size(); ++k) {
    path.frame_xy[k] = start + R_start * path.frame_xy[k];
    path.frame_heading[k] += start_yaw;
  }
  return path;
}

Simulator::Simulator(const SimOptions& options)
    : options_(Validated(options)), path_(MakePath(options_)), terrain_(options_, path_.dense_xy) {
  const SimOptions& o = options_;
  // Mast camera: a level forward-looking OpenCV camera is rpy [-90, 0, -90]; tilt it down
  // about the body y axis.
  T_body_sensor_.linear() =
      Eigen::AngleAxisd(o.camera_tilt_deg * kDegToRad, Eigen::Vector3d::UnitY())
          .toRotationMatrix() *
      io::RotationFromRpy(-M_PI / 2, 0, -M_PI / 2);
  T_body_sensor_.translation() = Eigen::Vector3d(o.mast_forward_m, 0, o.mast_height_m);
  // The rig the images come from: one draw per traverse (sim.baseline_error, mount_error_deg).
  const Eigen::Vector3d mount_error =
      o.mount_error_deg * kDegToRad *
      Eigen::Vector3d(HashNormal(o.seed, kSaltRig, 0, 0), HashNormal(o.seed, kSaltRig, 0, 1),
                      HashNormal(o.seed, kSaltRig, 0, 2));
  T_body_sensor_true_ = T_body_sensor_;
  if (mount_error.norm() > 0.0) {
    T_body_sensor_true_.linear() =
        T_body_sensor_.linear() *
        Eigen::AngleAxisd(mount_error.norm(), mount_error.normalized()).toRotationMatrix();
  }
  baseline_true_m_ = o.baseline_m * (1.0 + o.baseline_error * HashNormal(o.seed, kSaltRig, 0, 3));

  // True poses: height, roll and pitch from the terrain under the four wheels.
  for (int k = 0; k < o.frames; ++k) {
    const Eigen::Vector2d& p = path_.frame_xy[k];
    const double yaw = path_.frame_heading[k];
    const Eigen::Rotation2Dd R(yaw);
    auto ground = [&](double fwd, double left) {
      const Eigen::Vector2d w = p + R * Eigen::Vector2d(fwd, left);
      return terrain_.Height(w.x(), w.y());
    };
    const double L = o.wheelbase_m / 2, W = o.track_m / 2;
    const double fl = ground(L, W), fr = ground(L, -W), rl = ground(-L, W), rr = ground(-L, -W);
    if (!std::isfinite(fl + fr + rl + rr)) {
      std::ostringstream message;
      message << "sim: the rover leaves the terrain square (+-" << 0.5 * o.terrain_size_m
              << " m) at frame " << k << ", at x " << p.x() << " m, y " << p.y()
              << " m: change sim.start_x_m, sim.start_y_m or sim.start_yaw_deg, or use fewer "
                 "sim.frames or a larger sim.terrain_size_m";
      throw std::invalid_argument(message.str());
    }
    const double pitch = std::atan2(0.5 * (rl + rr) - 0.5 * (fl + fr), o.wheelbase_m);
    const double roll = std::atan2(0.5 * (fl + rl) - 0.5 * (fr + rr), o.track_m);
    io::StampedPose pose;
    pose.timestamp = k / o.frame_rate_hz;
    pose.T_world_body.linear() = io::RotationFromRpy(roll, pitch, yaw);
    pose.T_world_body.translation() = Eigen::Vector3d(p.x(), p.y(), 0.25 * (fl + fr + rl + rr));
    truth_.push_back(pose);
  }

  // Dead reckoning: each true increment's travel scaled by (1 + scale error)(1 + slip), the
  // heading increment off by bias·dt plus a random walk; roll and pitch from the (true)
  // inclinometers; integrated in 3-D from the true first pose.
  const double dt = 1.0 / o.frame_rate_hz;
  const int odometry_seed = o.odometry_seed != 0 ? o.odometry_seed : o.seed;
  odometry_.push_back(truth_[0]);
  double yaw_error = 0.0;
  for (int k = 1; k < o.frames; ++k) {
    const Eigen::Isometry3d delta = truth_[k - 1].T_world_body.inverse() * truth_[k].T_world_body;
    const double slip =
        o.odom_slip_mean + o.odom_slip_sigma * HashNormal(odometry_seed, kSaltOdometry, k, 0);
    const double scale = (1.0 + o.odom_scale_error) * (1.0 + slip);
    yaw_error += o.heading_bias_deg_s * kDegToRad * dt +
                 o.heading_random_walk_deg_rt_s * kDegToRad * std::sqrt(dt) *
                     HashNormal(odometry_seed, kSaltOdometry, k, 1);
    const Eigen::Matrix3d& R_prev_est = odometry_.back().T_world_body.linear();
    const Eigen::Vector3d step_world = R_prev_est * (scale * delta.translation());
    const Eigen::Vector3d rpy_true = [&] {
      const Eigen::Matrix3d& R = truth_[k].T_world_body.linear();
      return Eigen::Vector3d(std::atan2(R(2, 1), R(2, 2)),
                             std::asin(-std::clamp(R(2, 0), -1.0, 1.0)), Yaw(R));
    }();
    io::StampedPose pose;
    pose.timestamp = truth_[k].timestamp;
    pose.T_world_body.linear() =
        io::RotationFromRpy(rpy_true.x(), rpy_true.y(), rpy_true.z() + yaw_error);
    pose.T_world_body.translation() = odometry_.back().T_world_body.translation() + step_world;
    odometry_.push_back(pose);
  }
}

io::CameraModel Simulator::camera() const {
  const SimOptions& o = options_;
  return io::CameraModel{o.image_width,       o.image_height,       o.focal_px,  o.focal_px,
                         0.5 * o.image_width, 0.5 * o.image_height, o.baseline_m};
}

Eigen::Isometry3d Simulator::CameraPose(std::size_t index, bool right) const {
  Eigen::Isometry3d T = truth_.at(index).T_world_body * T_body_sensor_true_;
  if (right) T = T * Eigen::Translation3d(baseline_true_m_, 0, 0);
  return T;
}

void Simulator::RenderStereo(std::size_t index, cv::Mat* left, cv::Mat* right) const {
  const SimOptions& o = options_;
  const io::CameraModel c = camera();
  const Eigen::Vector3d sun = Eigen::Vector3d(
      std::cos(o.sun_elevation_deg * kDegToRad) * std::cos(o.sun_azimuth_deg * kDegToRad),
      std::cos(o.sun_elevation_deg * kDegToRad) * std::sin(o.sun_azimuth_deg * kDegToRad),
      std::sin(o.sun_elevation_deg * kDegToRad));
  constexpr double kAmbient = 0.25, kSky = 190.0;
  for (int eye = 0; eye < 2; ++eye) {
    cv::Mat& image = eye == 0 ? *left : *right;
    image.create(c.height, c.width, CV_8U);
    const Eigen::Isometry3d T_world_camera = CameraPose(index, eye == 1);
    const Eigen::Vector3d origin = T_world_camera.translation();
#pragma omp parallel for schedule(dynamic, 4)
    for (int v = 0; v < c.height; ++v) {
      unsigned char* row = image.ptr<unsigned char>(v);
      for (int u = 0; u < c.width; ++u) {
        const Eigen::Vector3d ray_camera((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
        const Eigen::Vector3d direction = (T_world_camera.linear() * ray_camera).normalized();
        double t = 0;
        double value = kSky;
        if (terrain_.Raycast(origin, direction, o.max_range_m, &t)) {
          const Eigen::Vector3d hit = origin + t * direction;
          const double footprint = t / c.fx;
          const double shade =
              kAmbient + (1 - kAmbient) * std::max(0.0, terrain_.Normal(hit.x(), hit.y()).dot(sun));
          value = 255.0 * terrain_.Albedo(hit.x(), hit.y(), footprint) * shade;
        }
        value += o.image_noise * HashNormal(o.seed, kSaltImageNoise + eye, index,
                                            static_cast<std::uint64_t>(v) * c.width + u);
        row[u] = static_cast<unsigned char>(std::clamp(std::lround(value), 0L, 255L));
      }
    }
  }
}

SimCloud Simulator::RenderCloud(std::size_t index) const {
  const SimOptions& o = options_;
  const io::CameraModel c = camera();
  const Eigen::Isometry3d T_world_camera = CameraPose(index, false);
  const Eigen::Matrix3d R_camera_world = T_world_camera.linear().transpose();
  const double fb = c.fx * c.baseline_m;
  // The disparity comes from the true baseline; the sensor triangulates with the stated one.
  const double fb_true = c.fx * baseline_true_m_;
  SimCloud out;
  for (int v = 0; v < c.height; v += o.cloud_stride_px) {
    for (int u = 0; u < c.width; u += o.cloud_stride_px) {
      const Eigen::Vector3d ray_camera((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
      const Eigen::Vector3d direction = (T_world_camera.linear() * ray_camera).normalized();
      double t = 0;
      if (!terrain_.Raycast(T_world_camera.translation(), direction, o.max_range_m, &t)) continue;
      const Eigen::Vector3d hit = T_world_camera.translation() + t * direction;
      const double z_true = (T_world_camera.inverse() * hit).z();
      const std::uint64_t pixel = static_cast<std::uint64_t>(v) * c.width + u;
      // Stereo error model: noisy (u, v, d) triangulated again.
      const double un = u + o.pixel_sigma_px * HashNormal(o.seed, kSaltCloud, index, 4 * pixel);
      const double vn = v + o.pixel_sigma_px * HashNormal(o.seed, kSaltCloud, index, 4 * pixel + 1);
      double d = fb_true / z_true +
                 o.disparity_sigma_px * HashNormal(o.seed, kSaltCloud, index, 4 * pixel + 2);
      if (Hash01(o.seed, kSaltCloud + 1, index, pixel) < o.outlier_fraction) {
        // Outlier: a wrong match anywhere on the ray between 0.5 m and max range.
        const double z = 0.5 + (o.max_range_m - 0.5) * Hash01(o.seed, kSaltCloud + 2, index, pixel);
        d = fb / z;
        ++out.outliers;
      }
      // Pixel locking: the sub-pixel part of the disparity shrunk toward the whole pixel.
      if (o.disparity_locking > 0.0) {
        const double whole = std::round(d);
        d = whole + (1.0 - o.disparity_locking) * (d - whole);
      }
      if (!(d > 0)) continue;
      const double z = fb / d;
      Eigen::Vector3d p((un - c.cx) * z / c.fx, (vn - c.cy) * z / c.fy, z);
      if (o.range_quantisation_m > 0.0) {  // range bins along the ray, fixed to the sensor
        const double range = p.norm();
        const double binned =
            std::max(1.0, std::round(range / o.range_quantisation_m)) * o.range_quantisation_m;
        p *= binned / range;
      }
      // Covariance by the same first-order model as stereo::PointCovariance.
      const Eigen::Vector3d j_d = -p / d;
      Eigen::Matrix3d cov = o.disparity_sigma_px * o.disparity_sigma_px * j_d * j_d.transpose();
      cov(0, 0) += std::pow(o.pixel_sigma_px * z / c.fx, 2);
      cov(1, 1) += std::pow(o.pixel_sigma_px * z / c.fy, 2);
      out.cloud.points.push_back(p);
      if (o.cloud_normals)
        out.cloud.normals.push_back(R_camera_world * terrain_.Normal(hit.x(), hit.y()));
      out.cloud.covariances.push_back(cov);
    }
  }
  return out;
}

std::vector<io::GnssFix> Simulator::GnssFixes() const {
  const SimOptions& o = options_;
  const io::Georeference georef(
      {o.origin_latitude_deg, o.origin_longitude_deg, o.origin_altitude_m});
  std::vector<io::GnssFix> fixes;
  if (o.gnss_every_frames <= 0) return fixes;
  for (std::size_t k = 0; k < truth_.size(); k += static_cast<std::size_t>(o.gnss_every_frames)) {
    Eigen::Vector3d p = truth_[k].T_world_body.translation();
    p.x() += o.gnss_sigma_m * HashNormal(o.seed, kSaltGnss, k, 0);
    p.y() += o.gnss_sigma_m * HashNormal(o.seed, kSaltGnss, k, 1);
    p.z() += o.gnss_sigma_up_m * HashNormal(o.seed, kSaltGnss, k, 2);
    if (Hash01(o.seed, kSaltGnss + 1, k, 0) < o.gnss_outlier_fraction) {
      const double angle = 2.0 * M_PI * Hash01(o.seed, kSaltGnss + 1, k, 1);
      p += o.gnss_outlier_m * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
    }
    const Eigen::Vector3d geo = georef.EnuToGeodetic(p.x(), p.y(), p.z());
    io::GnssFix f;
    f.timestamp = truth_[k].timestamp;
    f.latitude_deg = geo.x();
    f.longitude_deg = geo.y();
    f.altitude_m = geo.z();
    f.sigma_enu_m = Eigen::Vector3d(o.gnss_sigma_m, o.gnss_sigma_m, o.gnss_sigma_up_m);
    fixes.push_back(f);
  }
  return fixes;
}

SimulateResult Simulator::WriteSequence(
    const fs::path& dir, const std::function<void(std::size_t, std::size_t)>& progress) const {
  const SimOptions& o = options_;
  std::error_code error;
  fs::create_directories(dir / "frames", error);
  if (error) throw io::IoError((dir / "frames").string() + ": cannot create: " + error.message());

  io::SequenceInfo info;
  info.sensor_type =
      o.sensor == SensorKind::kCloud ? io::SensorType::kCloud : io::SensorType::kStereo;
  info.camera = camera();
  info.T_body_sensor = T_body_sensor_;
  // The rig's calibration as a calibration report would state it: the σ the error was drawn
  // from (0 for the exact rig), so that the DEM's σ carries what the rig may be off by.
  info.calibration_sigma = io::RigCalibrationSigma{o.mount_error_deg, o.baseline_error};
  info.origin = {o.origin_latitude_deg, o.origin_longitude_deg, o.origin_altitude_m};
  info.frame_rate_hz = o.frame_rate_hz;
  io::WriteSequenceYaml(dir, info,
                        "Written by rovermap simulate (seed " + std::to_string(o.seed) +
                            "): docs/design.md section 4.");

  SimulateResult result;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < truth_.size(); ++k) {
    const fs::path stem = dir / "frames" / io::FrameStem(k);
    io::Frame frame;
    if (o.sensor == SensorKind::kStereo) {
      RenderStereo(k, &frame.left, &frame.right);
    } else {
      SimCloud cloud = RenderCloud(k);
      cloud.cloud.covariances.clear();  // PLY carries points and normals
      frame.cloud = std::move(cloud.cloud);
      result.points += frame.cloud.size();
      result.outliers += cloud.outliers;
    }
    io::WriteFrameData(stem, info, frame);
    if (progress) progress(k + 1, truth_.size());
  }
  result.render_ms = core::MsSince(start);
  io::WriteTum(dir / "groundtruth.tum", truth_);
  io::WriteTum(dir / "odometry.tum", odometry_);
  if (o.gnss_every_frames > 0) {
    const std::vector<io::GnssFix> fixes = GnssFixes();
    io::WriteGnssCsv(dir / "gnss.csv", fixes);
    result.gnss_fixes = fixes.size();
  }

  result.frames = truth_.size();
  for (std::size_t k = 1; k < truth_.size(); ++k) {
    result.path_length_m +=
        (truth_[k].T_world_body.translation() - truth_[k - 1].T_world_body.translation()).norm();
  }
  result.final_odometry_error_m =
      (odometry_.back().T_world_body.translation() - truth_.back().T_world_body.translation())
          .norm();
  result.final_heading_error_deg = WrapAngle(Yaw(odometry_.back().T_world_body.linear()) -
                                             Yaw(truth_.back().T_world_body.linear())) /
                                   kDegToRad;
  return result;
}

}  // namespace rovermap::sim
