#pragma once
// Options of the sequence simulator behind `rovermap simulate` (config keys under `sim.`).

#include <vector>

namespace rovermap::sim {

enum class PathShape { kStraight, kCurves, kLoop, kOutAndBack };
enum class SensorKind { kStereo, kCloud };

struct SimOptions {
  int seed = 1;     ///< everything random derives from it (deterministic output)
  int frames = 30;  ///< frames in the sequence [count]
  double frame_rate_hz = 2.0;
  double speed_m_s = 0.3;  ///< rover ground speed

  double origin_latitude_deg = 46.5191;  ///< geodetic origin written to sequence.yaml
  double origin_longitude_deg = 6.5668;
  double origin_altitude_m = 400.0;

  // Terrain: a square heightfield centred on the world origin.
  double terrain_size_m = 40.0;       ///< edge of the square
  double terrain_cell_m = 0.04;       ///< heightfield sample spacing
  double relief_m = 0.6;              ///< amplitude of the fractal relief (largest octave)
  double relief_wavelength_m = 10.0;  ///< wavelength of the largest octave
  int octaves = 7;                    ///< fractal noise octaves (each half the wavelength)
  double roughness = 0.5;             ///< amplitude ratio between octaves (persistence)
  double slope_x_deg = 2.0;           ///< regional slope rising towards +x (east)
  double slope_y_deg = 0.0;           ///< regional slope rising towards +y (north)
  int craters = 15;                   ///< crater count
  double crater_max_radius_m = 3.0;
  int rocks = 400;  ///< rock count
  double rock_max_radius_m = 0.3;
  double keep_out_m = 1.0;  ///< no rocks within this distance of the rover path

  // Rover and path.
  PathShape path = PathShape::kCurves;
  /// [m] loop radius / tightest curve radius / the out-and-back's U-turn radius (the return leg
  /// runs 2 × this beside the outbound one)
  double turn_radius_m = 6.0;
  // Start pose in the terrain's frame: the path is driven from it. The terrain (relief,
  // craters, rocks) does not depend on it, so traverses from other start poses see one ground.
  double start_x_m = 0.0;      ///< start position east of the terrain's centre [m]
  double start_y_m = 0.0;      ///< start position north of the terrain's centre [m]
  double start_yaw_deg = 0.0;  ///< start heading, from east counter-clockwise [deg]
  double wheelbase_m = 0.6;    ///< front-back wheel distance (pitch from the terrain)
  double track_m = 0.5;        ///< left-right wheel distance (roll from the terrain)

  // Mast stereo camera (defaults: a small rover's navigation cameras).
  SensorKind sensor = SensorKind::kStereo;
  double mast_height_m = 1.0;     ///< left camera above the body origin
  double mast_forward_m = 0.2;    ///< left camera ahead of the body origin
  double camera_tilt_deg = 30.0;  ///< optical axis below the horizontal
  double baseline_m = 0.2;
  double focal_px = 300.0;
  int image_width = 480;
  int image_height = 360;
  double sun_elevation_deg = 40.0;
  double sun_azimuth_deg = 135.0;  ///< from east, counter-clockwise
  double image_noise = 2.0;        ///< sensor noise σ [grey levels]
  double max_range_m = 20.0;       ///< rays longer than this see sky
  /// The rig's calibration error: the images (and cloud points) come from a rig that differs
  /// from the one sequence.yaml states, drawn once per traverse from `seed`, as a field
  /// calibration leaves it: the baseline's scale and the camera's mounting rotation on the
  /// body. A baseline error scales every depth (and every registered step) alike; a mounting
  /// error turns every step's direction and tilts the points. 0 = the rig is exactly as stated.
  double baseline_error = 0.0;   ///< σ of the true baseline's relative error [ratio]
  double mount_error_deg = 0.0;  ///< σ of the true mounting's error about each axis [deg]

  // Cloud mode: ray-cast points with the stereo error model.
  int cloud_stride_px = 4;  ///< one point per stride × stride pixels
  double disparity_sigma_px = 0.2;
  double pixel_sigma_px = 0.3;
  double outlier_fraction = 0.01;  ///< points moved to a random depth on their ray
  /// Sensor-fixed artefacts real sensors leave and smooth noise does not: sub-pixel disparity
  /// pulled toward whole pixels (0 = none, 1 = whole-pixel disparities: a matcher's pixel
  /// locking) and range rounded to bins of this size along the ray [m] (a lidar's range bins;
  /// 0 = off). Both are fixed to the sensor, not to the ground.
  double disparity_locking = 0.0;
  double range_quantisation_m = 0.0;
  bool cloud_normals = true;  ///< PLY frames carry the terrain's true normals (else none)

  // Dead reckoning.
  int odometry_seed = 0;                       ///< seeds the odometry errors alone; 0 = sim.seed's
  double odom_scale_error = 0.02;              ///< wheel odometry distance scale error (ratio)
  double odom_slip_mean = 0.01;                ///< mean extra wheel travel from slip (ratio)
  double odom_slip_sigma = 0.02;               ///< per-step slip σ (ratio)
  double heading_bias_deg_s = 0.05;            ///< heading-rate bias
  double heading_random_walk_deg_rt_s = 0.05;  ///< heading random walk [deg/√s]

  // GNSS (gnss.csv beside the sequence, docs/graph.md): a fix of the body origin every
  // `gnss_every_frames` frames (0 = none), with Gaussian noise of the σ it reports, and a
  // fraction of fixes thrown `gnss_outlier_m` off in a random horizontal direction (multipath),
  // still reporting the nominal σ.
  int gnss_every_frames = 0;
  double gnss_sigma_m = 0.5;     ///< [m] horizontal σ, east and north
  double gnss_sigma_up_m = 1.0;  ///< [m] vertical σ
  double gnss_outlier_fraction = 0.0;
  double gnss_outlier_m = 10.0;  ///< [m]

  // A reference DEM (reference_dem.tif beside the sequence, docs/graph.md), as an orbital
  // product has it: the true terrain averaged over posts of `reference_post_m` (0 = none), with
  // Gaussian noise of `reference_sigma_m` (band 2 says so), misplaced by `reference_offset_m`
  // (east, north) in its georeferencing.
  double reference_post_m = 0.0;                        ///< [m]
  double reference_sigma_m = 0.2;                       ///< [m]
  std::vector<double> reference_offset_m = {0.5, 0.0};  ///< [m] east, north
};

}  // namespace rovermap::sim
