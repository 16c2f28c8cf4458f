#pragma once
// Options of the mapping pipeline (config keys under `mapper.`). Plain struct, no dependencies.

namespace rovermap::mapper {

/// What a new frame is registered onto.
/// kPrevious: the previous good frame (its indexed cloud is reused, never rebuilt).
/// kLocalMap: the last `local_map_frames` registered frames, voxel-thinned, in one cloud.
enum class Reference { kPrevious, kLocalMap };

struct MapperOptions {
  Reference reference = Reference::kPrevious;
  /// kLocalMap: registered frames kept in the local map [count].
  int local_map_frames = 5;
  /// kLocalMap: voxel edge of the local map's thinning [m]; 0 = the registration's D as used
  /// on the previous frame.
  double local_map_voxel_m = 0.0;

  /// A frame with fewer usable points than this is a bad frame: not registered, not fused
  /// [count].
  int min_points = 100;
  /// Radius outlier removal before registration and fusion: a point is dropped when fewer than
  /// `outlier_min_neighbors` other points lie within `outlier_radius_factor` × its expected
  /// sample spacing (range × median angular spacing of the frame). 0 = off.
  double outlier_radius_factor = 3.0;
  int outlier_min_neighbors = 2;
  /// Stereo frames: the points the matcher registers (and keeps as the next frame's reference)
  /// are merged into range-aware voxels whose edge is this many pixels' footprint at their
  /// range (registration::RangeVoxelDownsample): a KITTI frame's 260 000 points, dense near
  /// the rig and sparse far from it, become about 30 000 that sample the ground evenly. The
  /// outlier test runs on the merged points; the DEM and the OctoMap still take every point of
  /// a kept voxel [px]. 0 = register every point.
  double registration_cell_px = 0.0;

  /// Register with the points' covariances (registration.use_uncertainty: pairs weighted by
  /// their inverse covariance, gated by Mahalanobis distance) whenever both frames carry them
  /// (stereo frames; clouds with a camera in sequence.yaml). Far stereo points, whose depth is
  /// uncertain by decimetres, then stop pulling the estimate.
  bool use_point_covariances = true;
  /// With point covariances, the Mahalanobis gate first opens by this many times dead
  /// reckoning's per-step σ (odometry_sigma_*), then closes as the matcher's steps shrink
  /// (registration.seed_*_sigma, which win when set): pairs the seed's heading error displaced
  /// are kept until they have turned it back [ratio]. 0 = the sensor's gate alone.
  double seed_gate_scale = 1.0;

  /// Acceptance of a registration (FrameJudge). The result is rejected (the whole increment
  /// falls back to dead reckoning) when its inlier ratio is below this [ratio]...
  double min_inlier_ratio = 0.2;
  /// ...or its RMS residual above this [m]...
  double max_rms_m = 0.15;
  /// ...or its correction of the dead-reckoning increment exceeds `correction_gate_sigma` times
  /// what wheel odometry can be wrong by over that step: translation σ = ratio × step length +
  /// floor, rotation σ = deg_per_m × step length + floor [sigma].
  double correction_gate_sigma = 3.0;
  double odometry_sigma_translation_ratio = 0.05;  ///< [ratio] of the step length
  double odometry_sigma_translation_m = 0.02;      ///< [m] per step, floor
  double odometry_sigma_rotation_deg_per_m = 2.0;  ///< [deg/m] of the step length
  double odometry_sigma_rotation_deg = 0.5;        ///< [deg] per step, floor
  /// What dead reckoning is typically wrong by over a step, where the `odometry_sigma_*` model
  /// above bounds what it can be wrong by (a slip, a seed as bad as the 1° a frame):
  /// the covariance of what the chain takes from it (the directions a partial frame keeps from
  /// the prediction, a fallback frame's whole step), so that drift.csv's σ and the DEM's carry
  /// a rover's odometry error rather than the gates' bound. A wheeled or skid-steer rover's
  /// heading drifts by tenths of a degree per metre and its distance by a few percent; the
  /// simulator's odometry errs by 0.23–0.36°/m and 3 % (rms per step). Same form as above.
  double odometry_noise_translation_ratio = 0.03;  ///< [ratio] of the step length
  double odometry_noise_translation_m = 0.002;     ///< [m] per step, floor
  double odometry_noise_rotation_deg_per_m = 0.3;  ///< [deg/m] of the step length
  double odometry_noise_rotation_deg = 0.02;       ///< [deg] per step, floor

  /// Dead reckoning's roll and pitch as an absolute measurement (IMU, inclinometers), σ [deg];
  /// 0 = roll and pitch from the chain alone (they drift: see AttitudePrior). Off by default:
  /// on KITTI the registered steps' own height bias then drove the height off (docs/replay.md,
  /// "Choosing the options").
  double odometry_attitude_sigma_deg = 0.0;
  /// Roll and pitch uncertainty one registered increment adds to the chain [deg]: a floor under
  /// the registration's own covariance for these angles (FloorAttitudeVariance), and the step
  /// of AttitudePrior. 0 = the registration's covariance alone.
  double registration_attitude_sigma_deg = 0.05;
  /// What a registered stereo increment is wrong by beyond its information, which treats every
  /// pixel's error as independent: neighbouring pixels share theirs (the matcher's block, the
  /// sub-pixel window), and a rig's calibration errors are common to all. The registration's
  /// covariance of stereo frames is multiplied by this [ratio of variances]. On KITTI the
  /// systematic part below dominates the chained covariance; 10 puts 0.954 of the frames of
  /// eight simulated traverses, pooled, within 2σ (docs/replay.md, "What happens to each
  /// frame"). Cloud frames keep theirs.
  double stereo_covariance_scale = 10.0;
  /// Step 5b, the image check (stereo frames, reference `previous`): corners of the reference
  /// frame's left image with their stereo depth are tracked into this frame's left image and
  /// give the increment as the images see it (stereo::EstimateImageMotion). It is fused with
  /// the registered increment by information: pixels hold the rotation at any range, where a
  /// far stereo point's depth is uncertain by decimetres. On KITTI it takes the registration's
  /// heading drift from +0.032° to +0.010° a frame (docs/replay.md, step 5b).
  bool image_check = true;
  /// The image estimate's covariance (the inverse of its reprojection information) × this
  /// [ratio of variances], like stereo_covariance_scale for the points: 10 on both.
  double image_covariance_scale = 10.0;
  /// The image estimate is used only when it agrees with the registered one: squared
  /// Mahalanobis distance of their difference within χ²₆ 99.9 % (22.46), the registration's
  /// covariance × this [ratio of variances]. A single step's registration errs by 4–14 times
  /// its (already scaled) variance (KITTI and the simulator, frame by frame); its chain, not
  /// its step, is what stereo_covariance_scale calibrates.
  double image_gate_scale = 8.0;

  /// The part of a registered stereo increment's error that repeats from step to step, per
  /// metre of the step: a rig's calibration (baseline, focal length, rectification) scales and
  /// turns every step alike [ratio of the step's length; deg per metre]. Stereo only; the rig's
  /// own calibration (rig_*_sigma, or what sequence.yaml states) sets it for clouds and bounds
  /// it from below for stereo (SystematicRatesOf).
  /// Chained as a systematic error (PoseChain, SystematicError) that persists over about
  /// `stereo_systematic_frames` steps [frames], so it adds up linearly instead of as a
  /// random walk. On KITTI (1 m steps) these give a chained NEES close to the 6 expected
  /// (docs/replay.md, "Known limits").
  double stereo_systematic_ratio = 0.007;
  double stereo_systematic_deg_per_m = 0.03;
  double stereo_systematic_frames = 100.0;

  /// The rig's calibration error assumed for a recording whose sequence.yaml does not state it
  /// (sensor.calibration_sigma): σ of the sensor's mounting rotation about each axis [deg] and
  /// of its depths' scale [ratio]. Every frame repeats it, so the DEM's published σ does not
  /// average it away (dem::FrameContext::rig_*): a 0.4° tilt is 3.5 cm at 5 m. The defaults are
  /// what stereo_systematic_ratio stands for (0.7 % of a step along and across it, 0.4°).
  double rig_rotation_sigma_deg = 0.4;
  double rig_scale_sigma = 0.007;

  /// Degeneracy: a direction of the registration's information whose eigenvalue, relative to
  /// the largest (rotations scaled by the cloud's extent, as `conditioning`), falls below this
  /// keeps the dead-reckoning prediction [ratio]. 0 = always take the registration.
  double min_information = 1e-4;
  /// Degeneracy against the noise: a direction must also hold this many times the information
  /// the errors of the matched normals alone would give it (RegistrationResult::
  /// noise_information): on featureless ground with real noise, range bins or disparity pixel
  /// locking, the in-plane directions get information from those errors and nothing else
  /// [ratio]. 0 = off.
  double min_information_over_noise = 6.0;
  /// Dead reckoning's bias: in the directions kept from dead reckoning, the prediction is moved
  /// by an estimate of its systematic error per frame (a heading-rate bias, a wheel-scale
  /// error): the mean of the registration's corrections in the directions they inform, each
  /// weighted by the registration's information (BiasEstimate). Each frame forgets this
  /// fraction of the evidence before it, so the estimate follows a bias that changes over
  /// about 1/rate frames [1/frame]. 0 = off.
  double odometry_bias_rate = 0.02;
  /// The estimate's zero-mean prior: σ of the bias per step as a fraction of dead reckoning's
  /// per-step σ (odometry_sigma_*) [ratio]. The weak directions of single frames on gently
  /// rolling ground are a degree off; this keeps their noise out of the estimate until enough
  /// frames agree.
  double odometry_bias_prior_ratio = 0.07;
  /// Directions whose information ratio (as min_information) is at least this inform the bias
  /// estimate [ratio]: below, on a plane's x, y and yaw, the registration's answer is noise.
  double bias_min_information = 1e-6;
};

}  // namespace rovermap::mapper
