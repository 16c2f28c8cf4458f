#pragma once
// The sequence simulator: a rover driving over a synthetic terrain (sim/Terrain), its mast
// stereo camera rendered by ray casting (or points with the stereo error model), and dead
// reckoning with configurable errors. Writes a sequence directory (docs/design.md §4).

#include <Eigen/Geometry>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "io/Gnss.hpp"
#include "io/Sequence.hpp"
#include "io/Tum.hpp"
#include "registration/PointCloud.hpp"
#include "sim/SimOptions.hpp"
#include "sim/Terrain.hpp"

namespace rovermap::sim {

/// What WriteSequence produced.
struct SimulateResult {
  std::size_t frames = 0;
  double path_length_m = 0.0;            ///< true distance travelled
  double final_odometry_error_m = 0.0;   ///< ‖t_odom − t_true‖ at the last frame
  double final_heading_error_deg = 0.0;  ///< odometry yaw − true yaw at the last frame
  std::size_t gnss_fixes = 0;            ///< fixes written to gnss.csv
  std::size_t points = 0;                ///< cloud mode: points written
  std::size_t outliers = 0;              ///< cloud mode: outliers among them
  double render_ms = 0.0;                ///< total time spent rendering frames
};

/// Cloud of one frame with its bookkeeping.
struct SimCloud {
  registration::PointCloud cloud;  ///< sensor frame, with true normals and model covariances
  std::size_t outliers = 0;
};

class Simulator {
 public:
  /// Builds the path, terrain, true poses and dead reckoning (cheap; no rendering).
  /// @throw std::invalid_argument if an option is out of range (config/ validates the same).
  explicit Simulator(const SimOptions& options);

  const SimOptions& options() const { return options_; }
  const Terrain& terrain() const { return terrain_; }
  /// True body poses T_world_body, one per frame.
  const std::vector<io::StampedPose>& truth() const { return truth_; }
  /// Dead-reckoning poses (same timestamps), starting at the true first pose.
  const std::vector<io::StampedPose>& odometry() const { return odometry_; }
  /// The mounting sequence.yaml states; the images are rendered from T_body_sensor_true().
  const Eigen::Isometry3d& T_body_sensor() const { return T_body_sensor_; }
  /// The mounting the images come from: T_body_sensor() turned by this traverse's draw of
  /// sim.mount_error_deg (the same when it is 0).
  const Eigen::Isometry3d& T_body_sensor_true() const { return T_body_sensor_true_; }
  /// The baseline the images come from [m]: sim.baseline_m scaled by this traverse's draw of
  /// sim.baseline_error; camera() states sim.baseline_m.
  double baseline_true_m() const { return baseline_true_m_; }
  io::CameraModel camera() const;

  /// Rectified 8-bit grey pair of frame `index` (left camera = sensor frame, right camera
  /// baseline_m along its x axis). Deterministic for (seed, index).
  void RenderStereo(std::size_t index, cv::Mat* left, cv::Mat* right) const;
  /// Points of frame `index` in the sensor frame: ray-cast depth perturbed by the stereo error
  /// model (σ_d, σ_px), plus outliers.
  SimCloud RenderCloud(std::size_t index) const;

  /// Writes sequence.yaml, frames/, odometry.tum and groundtruth.tum into `dir` (created if
  /// needed; every file written atomically). `progress(done, total)` is called after each
  /// frame (may be empty). terrain.tif: see sim/TerrainGeoTiff.hpp.
  /// @throw io::IoError naming the file if something cannot be written.
  SimulateResult WriteSequence(const std::filesystem::path& dir,
                               const std::function<void(std::size_t, std::size_t)>& progress) const;

  /// The GNSS fixes gnss.csv holds (SimOptions::gnss_every_frames; none when 0), in the
  /// sequence's geodetic frame (sim.origin_*). Deterministic in sim.seed.
  std::vector<io::GnssFix> GnssFixes() const;

 private:
  Eigen::Isometry3d CameraPose(std::size_t index, bool right) const;

  struct Path {
    std::vector<Eigen::Vector2d> dense_xy;  // every few cm from the default start pose (rocks)
    std::vector<Eigen::Vector2d> frame_xy;  // per frame, from the start pose
    std::vector<double> frame_heading;      // per frame [rad]
  };
  static Path MakePath(const SimOptions& options);

  SimOptions options_;
  Path path_;
  Terrain terrain_;
  std::vector<io::StampedPose> truth_;
  std::vector<io::StampedPose> odometry_;
  Eigen::Isometry3d T_body_sensor_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_body_sensor_true_ = Eigen::Isometry3d::Identity();
  double baseline_true_m_ = 0.0;
};

}  // namespace rovermap::sim
