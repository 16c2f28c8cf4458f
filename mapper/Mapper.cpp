#include "mapper/Mapper.hpp"

#include <chrono>
#include <stdexcept>
#include <utility>

#include "core/Skew.hpp"
#include "core/Stopwatch.hpp"
#include "mapper/Degeneracy.hpp"
#include "mapper/ImageCheck.hpp"
#include "mapper/OutlierFilter.hpp"
#include "mapper/SystematicRates.hpp"
#include "registration/RangeVoxels.hpp"
#include "stereo/Stereo.hpp"

namespace rovermap::mapper {
namespace {

using Clock = std::chrono::steady_clock;
using core::MsSince;

dem::ElevationMapOptions GridAlongProjection(dem::ElevationMapOptions options,
                                             const io::Georeference& georef) {
  // dem.tif is north-up in the projection without resampling when the cells run along its axes.
  options.grid_rotation_rad = georef.convergence_rad();
  return options;
}

io::Georeference MakeGeoreference(const io::SequenceInfo& sequence) {
  return io::Georeference(sequence.origin, io::ParseBody(sequence.body));
}

}  // namespace

// The sensor as the pipeline uses it: stereo.num_disparities 0 resolved from the camera's
// height and tilt above the ground.
SensorSetup ResolveSensor(const io::SequenceInfo& sequence, const stereo::StereoOptions& options,
                          const dem::ElevationMapOptions& dem, bool image_check) {
  SensorSetup sensor;
  sensor.type = sequence.sensor_type;
  sensor.camera = sequence.camera;
  sensor.T_body_sensor = sequence.T_body_sensor;
  sensor.stereo = options;
  sensor.image_landmarks = image_check && sequence.sensor_type == io::SensorType::kStereo;
  if (sequence.camera) {
    const io::CameraModel& c = *sequence.camera;
    sensor.stereo = stereo::ResolveDisparities(options, StereoCameraOf(c), c.width, c.height,
                                               sequence.T_body_sensor);
  }
  // The DEM tests the world frame's horizontal σ, this the body frame's: a margin for the tilt.
  constexpr double kFillSigmaMargin = 1.25;
  if (dem.max_horizontal_sigma_cells > 0.0)
    sensor.stereo.fill_max_horizontal_sigma_m =
        kFillSigmaMargin * dem.max_horizontal_sigma_cells * dem.cell_size_m;
  return sensor;
}

const char* ToString(FrameStatus status) {
  switch (status) {
    case FrameStatus::kFirst:
      return "first";
    case FrameStatus::kRegistered:
      return "registered";
    case FrameStatus::kPartial:
      return "partial";
    case FrameStatus::kFallback:
      return "fallback";
    case FrameStatus::kBadFrame:
      return "bad_frame";
  }
  return "unknown";
}

// The outcome of steps 2-5 for one frame.
struct Mapper::Registered {
  FrameStatus status = FrameStatus::kFirst;
  FallbackReason reason = FallbackReason::kFirstFrame;
  std::string detail;
  std::optional<Eigen::Isometry3d> T_world_body;  ///< nullopt: dead reckoning
  Matrix6d covariance_in_previous = Matrix6d::Zero();
  unsigned odometry_directions = 0;
  std::optional<registration::RegistrationResult> matcher;
  double reference_distance_m = 0.0;  ///< the matcher's D (0: keep the last one)
  BiasEstimate odometry_bias;         ///< the bias estimate if this frame is chained
  ImageCheckOutcome image_check = ImageCheckOutcome::kNone;
};

Mapper::Mapper(const io::SequenceInfo& sequence, const PipelineOptions& options)
    : sequence_(sequence),
      options_(options),
      sensor_(ResolveSensor(sequence, options.stereo, options.dem, ImageCheckOn(options.mapper))),
      georef_(MakeGeoreference(sequence)),
      attitude_(options.mapper.odometry_attitude_sigma_deg,
                options.mapper.registration_attitude_sigma_deg),
      elevation_map_(GridAlongProjection(options.dem, georef_)),
      octomap_(options.octomap),
      local_map_(static_cast<std::size_t>(std::max(1, options.mapper.local_map_frames))) {
  if (options.mapper.local_map_frames < 1) {
    throw std::invalid_argument("mapper.local_map_frames: must be >= 1");
  }
}

FrameResult Mapper::ProcessFrame(const io::Frame& frame, double load_ms) {
  return ProcessPrepared(frame, Prepare(frame), load_ms);
}

FrameResult Mapper::ProcessLoaded(const io::Frame& frame, LoadedFrame loaded, double load_ms) {
  return ProcessPrepared(frame, Prepare(std::move(loaded)), load_ms);
}

FrameResult Mapper::ProcessPrepared(const io::Frame& frame, PreparedFrame prepared,
                                    double load_ms) {
  return Process(frame, std::move(prepared), load_ms, nullptr);
}

PreparedFrame Mapper::Prepare(const io::Frame& frame) const {
  return Prepare(LoadFrame(frame, sensor_, options_.mapper.min_points));
}

PreparedFrame Mapper::Prepare(LoadedFrame loaded) const {
  PreparedFrame p;
  p.loaded = std::move(loaded);
  if (!p.loaded.ok) return p;
  // 1. Load (done by LoadFrame): index the body-frame points; flag the isolated ones
  // (docs/design.md §9a).
  const auto start = Clock::now();
  const Eigen::Vector3d origin = sensor_.T_body_sensor.translation();
  const MapperOptions& m = options_.mapper;
  if (sensor_.type == io::SensorType::kStereo && sensor_.camera && m.registration_cell_px > 0.0) {
    // Registration on range-aware voxels. The outlier test stays on the frame's own points
    // (on the voxels it let a mismatch merged with good points through, and a 1.7 m spike
    // into a simulated traverse's DEM).
    const registration::KdTree tree(p.loaded.cloud.points);
    p.isolated = FindIsolatedPoints(p.loaded.cloud.points, tree, origin, m.outlier_radius_factor,
                                    m.outlier_min_neighbors);
    // The isolated points go into no voxel: a mismatch would move its voxel's mean.
    registration::RangeVoxels merged = registration::RangeVoxelDownsample(
        p.loaded.cloud, origin, m.registration_cell_px / sensor_.camera->fx, 0.001,
        &p.isolated.keep);
    // Zhang's D from the frame's own spacing, not the voxels' (the simulator's traverses
    // lost a fifth of their accuracy to a D three times larger).
    const double spacing = sensor_.stereo.voxel_size_m > 0.0 ? 0.0 : p.loaded.spacing_m;
    p.source = std::make_unique<registration::IndexedCloud>(std::move(merged.cloud),
                                                            options_.registration, spacing);
  } else {
    p.source = std::make_unique<registration::IndexedCloud>(std::move(p.loaded.cloud),
                                                            options_.registration);
    p.loaded.cloud = registration::PointCloud();
    p.isolated = FindIsolatedPoints(p.source->cloud().points, p.source->tree(), origin,
                                    m.outlier_radius_factor, m.outlier_min_neighbors);
  }
  p.prepare_ms = MsSince(start);
  return p;
}

FrameResult Mapper::Process(const io::Frame& frame, PreparedFrame prepared, double load_ms,
                            const FrameResult* recorded) {
  const auto start = Clock::now();
  const LoadedFrame& loaded = prepared.loaded;
  if (!loaded.ok) {
    SkipFrame(frame.index, frame.timestamp, frame.T_world_body_odom, FallbackReason::kBadFrame,
              loaded.reason, frame.T_world_body_truth);
    FrameResult& bad = results_.back();
    bad.time.load_ms = load_ms;
    bad.time.stereo_ms = loaded.stereo_ms;
    bad.time.total_ms = loaded.stereo_ms;
    bad.dropped_nonfinite = loaded.dropped_nonfinite;
    return bad;
  }
  FrameResult r = Begin(frame, prepared, load_ms);
  // 1. Load and prepare: done by Prepare, maybe on another thread while the last frame ran.
  const registration::PointCloud& fused = prepared.Fused();  // lives on in `source` below
  std::unique_ptr<registration::IndexedCloud> source = std::move(prepared.source);
  const OutlierMask& isolated = prepared.isolated;

  // 2-5. Predict from dead reckoning, register onto the reference, judge, blend per direction
  // (or, re-applying a journalled frame, what that gave).
  const auto register_start = Clock::now();
  const Registered reg =
      recorded ? Recorded(*recorded)
               : RegisterOntoReference(*source, frame.T_world_body_odom, &loaded.landmarks);
  r.time.register_ms = MsSince(register_start);

  // 6. Chain the accepted increment (or dead reckoning's); a registered one updates the
  // estimate of dead reckoning's bias.
  r.step = Chain(frame, reg.T_world_body, reg.covariance_in_previous,
                 reg.reason == FallbackReason::kImplausibleCorrection);
  r.odometry_bias = reg.T_world_body && !r.step.fallback ? reg.odometry_bias : OdometryBias();

  // 7. Fuse the points at the chained pose into the DEM and the OctoMap.
  Fuse(fused, isolated.keep, loaded.fill, r.step, &r);

  // 8. Report; this frame becomes the next one's reference.
  Report(reg, &r);
  KeepAsReference(std::move(source), r.step, r.reference_distance_m);
  previous_landmarks_ = std::move(prepared.loaded.landmarks);
  r.time.total_ms = loaded.stereo_ms + prepared.prepare_ms + MsSince(start);
  results_.push_back(r);
  return r;
}

FrameResult Mapper::Begin(const io::Frame& frame, const PreparedFrame& prepared, double load_ms) {
  FrameResult r;
  r.index = frame.index;
  r.timestamp = frame.timestamp;
  r.T_world_body_truth = frame.T_world_body_truth;
  r.points = prepared.Fused().size();
  r.dropped_nonfinite = prepared.loaded.dropped_nonfinite;
  r.outliers_removed = prepared.isolated.removed;
  r.time.load_ms = load_ms;
  r.time.stereo_ms = prepared.loaded.stereo_ms;
  r.time.prepare_ms = prepared.prepare_ms;
  return r;
}

void Mapper::Report(const Registered& reg, FrameResult* r) {
  r->T_world_body_registered = reg.T_world_body;
  r->increment_covariance = reg.covariance_in_previous;
  r->reference_distance_m = reg.reference_distance_m;
  r->status = reg.status;
  r->fallback_reason = reg.reason;
  r->detail = reg.detail;
  r->odometry_directions = reg.odometry_directions;
  r->image_check = reg.image_check;
  if (reg.T_world_body && r->step.fallback) {  // PoseChain refused it: not a finite rigid motion
    r->status = FrameStatus::kFallback;
    r->fallback_reason = FallbackReason::kRegistrationFailed;
    r->detail = "registered increment is not a finite rigid transform";
    r->odometry_directions = kRoll | kPitch | kYaw | kX | kY | kZ;
  }
  if (reg.matcher) {
    r->matcher_status = registration::ToString(reg.matcher->status);
    r->iterations = reg.matcher->iterations;
    r->inliers = reg.matcher->inliers;
    r->inlier_ratio = reg.matcher->inlier_ratio;
    r->rms_m = reg.matcher->rms_m;
    r->conditioning = reg.matcher->conditioning;
  }
}

FrameResult Mapper::SkipFrame(std::size_t index, double timestamp,
                              const Eigen::Isometry3d& T_world_body_odom, FallbackReason reason,
                              const std::string& detail,
                              const std::optional<Eigen::Isometry3d>& T_world_body_truth) {
  FrameResult r;
  r.index = index;
  r.timestamp = timestamp;
  r.status = FrameStatus::kBadFrame;
  r.fallback_reason = reason;
  r.detail = detail;
  r.T_world_body_truth = T_world_body_truth;
  io::Frame meta;
  meta.index = index;
  meta.timestamp = timestamp;
  meta.T_world_body_odom = T_world_body_odom;
  r.step = Chain(meta, std::nullopt, Matrix6d::Zero());
  r.odometry_directions = kRoll | kPitch | kYaw | kX | kY | kZ;
  r.odometry_bias = OdometryBias();
  results_.push_back(r);
  return r;
}

FrameResult Mapper::Reapply(const FrameResult& recorded, const io::Frame* frame, FrameBins* bins) {
  const std::string where = "frame " + std::to_string(recorded.index) + ": ";
  if (recorded.status == FrameStatus::kBadFrame) {
    SkipFrame(recorded.index, recorded.timestamp, recorded.step.T_world_body_odom,
              recorded.fallback_reason, recorded.detail, recorded.T_world_body_truth);
  } else {
    if (frame == nullptr || frame->index != recorded.index) {
      throw ReapplyError(where + "its files are needed to re-apply it");
    }
    PreparedFrame prepared = Prepare(*frame);
    if (!prepared.loaded.ok) {
      throw ReapplyError(where + "could be read before, not now: " + prepared.loaded.reason);
    }
    if (bins) *bins = BinFrame(prepared.Fused(), prepared.isolated.keep);
    Process(*frame, std::move(prepared), 0.0, &recorded);
  }
  // Re-applied, the chain must land on the very pose it reached the first time.
  const ChainStep& now = results_.back().step;
  if (results_.back().status != recorded.status ||
      now.T_world_body.matrix() != recorded.step.T_world_body.matrix() ||
      now.covariance != recorded.step.covariance) {
    throw ReapplyError(where + "re-applied, it does not reach the recorded pose");
  }
  results_.back() = recorded;
  return recorded;
}

Mapper::Registered Mapper::Recorded(const FrameResult& recorded) {
  Registered out;
  out.status = recorded.status;
  out.reason = recorded.fallback_reason;
  out.detail = recorded.detail;
  out.T_world_body = recorded.T_world_body_registered;
  out.covariance_in_previous = recorded.increment_covariance;
  out.odometry_directions = recorded.odometry_directions;
  out.reference_distance_m = recorded.reference_distance_m;
  out.odometry_bias = recorded.odometry_bias;
  out.image_check = recorded.image_check;
  return out;
}

Mapper::Registered Mapper::RegisterOntoReference(const registration::IndexedCloud& source,
                                                 const Eigen::Isometry3d& T_world_body_odom,
                                                 const stereo::ImageLandmarks* landmarks) {
  Registered out;
  out.odometry_bias = OdometryBias();
  if (!chain_) return out;  // frame 0: the chain starts at its dead-reckoning pose
  if (!reference_index_) {
    out.reason = FallbackReason::kNoReference;
    out.detail = "no earlier frame could be used";
    return out;
  }
  out.status = FrameStatus::kFallback;
  const ChainStep& last = chain_->back();
  const Eigen::Isometry3d T_world_ref = results_[*reference_index_].step.T_world_body;
  // 2. Predict: dead reckoning's increment applied to the last chained pose, seen from the
  // reference frame (the last good frame; the same as the last frame unless it was bad).
  const Eigen::Isometry3d T_ref_predicted =
      T_world_ref.inverse() * last.T_world_body * chain_->PredictIncrement(T_world_body_odom);
  const OdometrySigma odometry_sigma =
      OdometryStepSigma(T_ref_predicted.translation().norm(), options_.mapper);
  const Matrix6d odometry_covariance = CovarianceOf(odometry_sigma);

  // 3. Register onto the previous good frame (its tree and normals reused) or the local map.
  std::unique_ptr<registration::IndexedCloud> local;
  if (options_.mapper.reference == Reference::kLocalMap) {
    const double voxel = options_.mapper.local_map_voxel_m > 0.0 ? options_.mapper.local_map_voxel_m
                                                                 : last_reference_distance_m_;
    local = local_map_.Build(T_world_ref, voxel, options_.registration);
  }
  const registration::IndexedCloud& target = local ? *local : *previous_;
  registration::RegistrationOptions registration = options_.registration;
  registration.use_uncertainty |= options_.mapper.use_point_covariances &&
                                  source.cloud().HasCovariances() &&
                                  target.cloud().HasCovariances();
  // The Mahalanobis gate opens by what dead reckoning may be wrong by over this step, unless
  // the configuration says how far the seed can be off.
  const double scale = options_.mapper.seed_gate_scale;
  if (registration.seed_rotation_sigma_deg <= 0.0)
    registration.seed_rotation_sigma_deg = scale * odometry_sigma.rotation_rad * 180.0 / M_PI;
  if (registration.seed_translation_sigma_m <= 0.0)
    registration.seed_translation_sigma_m = scale * odometry_sigma.translation_m;
  out.matcher = registration::Register(source, target, T_ref_predicted, registration);
  const registration::RegistrationResult& m = *out.matcher;
  out.reference_distance_m = m.reference_distance_m;

  // 4. Judge the registration itself.
  const Judgement judged = JudgeRegistration(m, options_.mapper);
  if (!judged.accepted) {
    out.reason = judged.reason;
    out.detail = judged.detail;
    return out;
  }
  // 5. Keep dead reckoning in the directions the data do not constrain, then judge the
  // correction that is left against what odometry can be wrong by.
  BlendedIncrement blended =
      BlendIncrement(T_ref_predicted, m.T_target_source, m.information, m.extent_m,
                     options_.mapper.min_information, odometry_covariance, OdometryBias().bias,
                     options_.mapper.bias_min_information, m.noise_information,
                     options_.mapper.min_information_over_noise);
  if (blended.constrained == 0) {
    out.reason = FallbackReason::kRegistrationFailed;
    out.detail =
        "no direction constrained (information below mapper.min_information or "
        "mapper.min_information_over_noise)";
    return out;
  }
  // The stereo error model treats every pixel's error as its own; neighbouring pixels share
  // theirs (the matcher's block, the sub-pixel window). Cloud frames keep their information as
  // it is (the simulator's cloud traverse, independent noise per point: z ~ 1).
  const double inflation =
      sensor_.type == io::SensorType::kStereo ? options_.mapper.stereo_covariance_scale : 1.0;
  // The directions kept from the prediction carry what dead reckoning is typically wrong by
  // (odometry_noise_*), not the gates' bound on it (odometry_sigma_*): on the simulated cloud
  // traverses, whose odometry errs as a rover's does, the bound put every frame within 2σ.
  const Matrix6d prediction = OdometryCovariance(T_ref_predicted, /*in_doubt=*/false);
  const Matrix6d& P_u = blended.prediction_projector;
  Matrix6d honest = inflation * blended.covariance_registered + P_u * prediction * P_u.transpose();
  // 5b. The image check: the increment the left images see, fused by information.
  if (ImageCheckOn(options_.mapper) && landmarks && !landmarks->empty() &&
      !previous_landmarks_.empty() && sensor_.camera) {
    const std::optional<ImageIncrement> image =
        ToBodyIncrement(stereo::EstimateImageMotion(previous_landmarks_, landmarks->left,
                                                    StereoCameraOf(*sensor_.camera), sensor_.image),
                        sensor_.T_body_sensor, options_.mapper.image_covariance_scale);
    out.image_check = ImageCheckOutcome::kFailed;
    if (image) {
      const ImageFusion fused = FuseImageIncrement(blended, inflation, prediction, *image,
                                                   options_.mapper.image_gate_scale);
      out.image_check = fused.outcome;
      if (fused.outcome == ImageCheckOutcome::kUsed) {
        blended.T = fused.T;
        blended.odometry_directions = fused.odometry_directions;
        honest = fused.covariance;
      }
    }
  }
  const Judgement plausible = JudgeCorrection(T_ref_predicted, blended.T, options_.mapper);
  if (!plausible.accepted) {
    out.reason = plausible.reason;
    out.detail = plausible.detail;
    return out;
  }
  out.status = blended.odometry_directions == 0 ? FrameStatus::kRegistered : FrameStatus::kPartial;
  out.reason = FallbackReason::kNone;
  out.odometry_directions = blended.odometry_directions;
  out.T_world_body = T_world_ref * blended.T;
  if (options_.mapper.odometry_bias_rate > 0.0) {
    const double ratio = options_.mapper.odometry_bias_prior_ratio;
    const Matrix6d prior = (ratio * ratio * odometry_covariance).inverse();
    out.odometry_bias =
        UpdateBias(OdometryBias(), blended.bias_correction, blended.bias_information, prior,
                   options_.mapper.odometry_bias_rate, odometry_covariance);
  }
  // The blended covariance is a left perturbation in the reference frame; move it to frame k−1.
  const Matrix6d A = Adjoint(last.T_world_body.inverse() * T_world_ref);
  out.covariance_in_previous = A * honest * A.transpose();
  FloorAttitudeVariance(&out.covariance_in_previous,
                        options_.mapper.registration_attitude_sigma_deg);
  return out;
}

ChainStep Mapper::Chain(const io::Frame& frame,
                        const std::optional<Eigen::Isometry3d>& T_world_body,
                        const Matrix6d& covariance_in_previous, bool odometry_in_doubt) {
  if (!chain_) {
    chain_ = std::make_unique<PoseChain>(frame.T_world_body_odom);
    return chain_->back();
  }
  if (!T_world_body) {
    const Eigen::Isometry3d odometry = chain_->PredictIncrement(frame.T_world_body_odom);
    return chain_->Add(frame.T_world_body_odom, std::nullopt,
                       OdometryCovariance(odometry, odometry_in_doubt));
  }
  // Roll and pitch pulled towards dead reckoning's absolute ones (AttitudePrior).
  const Eigen::Isometry3d T_world_body_prior =
      attitude_.Update(*T_world_body, frame.T_world_body_odom);
  Eigen::Isometry3d increment = chain_->back().T_world_body.inverse() * T_world_body_prior;
  // Products of many small rotations drift off orthogonality (the matcher's iterates, the
  // chain); PoseChain takes only proper rotations, so project onto the nearest one.
  increment.linear() = Eigen::Quaterniond(increment.linear()).normalized().toRotationMatrix();
  // Part of a step's error repeats from step to step, in proportion to the step
  // (SystematicError): the rig's calibration, and stereo's own bias (SystematicRatesOf).
  const MapperOptions& o = options_.mapper;
  const double length = increment.translation().norm();
  const SystematicRates rates = SystematicRatesOf(sensor_.type, rig_calibration(), o);
  SystematicError systematic;
  systematic.sigma << Eigen::Vector3d::Constant(rates.rotation_rad_per_m * length),
      Eigen::Vector3d::Constant(rates.translation_ratio * length);
  systematic.persistence = std::exp(-1.0 / o.stereo_systematic_frames);
  return chain_->Add(frame.T_world_body_odom, increment, covariance_in_previous, systematic);
}

Matrix6d Mapper::OdometryCovariance(const Eigen::Isometry3d& increment, bool in_doubt) const {
  // A correction refused as implausible may be dead reckoning's slip as well as a wrong match.
  const double length = increment.translation().norm();
  return CovarianceOf(in_doubt ? OdometryStepSigma(length, options_.mapper)
                               : OdometryNoiseSigma(length, options_.mapper));
}

void Mapper::Fuse(const registration::PointCloud& cloud, const std::vector<unsigned char>& keep,
                  const registration::PointCloud& fill, const ChainStep& step,
                  FrameResult* result) {
  const auto dem_start = Clock::now();
  const Eigen::Isometry3d& T = step.T_world_body;
  // The frame's points are read where they are (body frame), not copied: the kept ones, then
  // the fill.
  dem::FramePart measured{&cloud.points, &cloud.covariances, &cloud.normals, &keep};
  // The DEM's fill points go with the frame's own (one FuseFrame: a cell's points of one frame
  // weigh as one), not into the OctoMap, and only into cells that no measured point of this
  // frame reached (FrameContext::fill_from): they close the gaps between the rows and leave
  // measured cells to their measurements. They carry what the cloud carries, or are left out.
  dem::FramePart between;
  if ((fill.HasCovariances() || !cloud.HasCovariances()) &&
      (fill.HasNormals() || !cloud.HasNormals())) {
    between = {&fill.points, &fill.covariances, &fill.normals, nullptr};
  }
  dem::FrameContext ctx;
  ctx.frame = static_cast<std::uint32_t>(step.index);
  ctx.R_world_cov = T.linear();  // the covariances are in the body frame
  ctx.sensor_origin_world = T * sensor_.T_body_sensor.translation();
  // The chain's covariance is a right perturbation of T_world_body; FuseFrame wants a left one
  // in the world frame about the sensor: Ad([R, t − c]).
  Eigen::Isometry3d T_about_sensor = T;
  T_about_sensor.translation() -= ctx.sensor_origin_world;
  const Matrix6d A = Adjoint(T_about_sensor);
  ctx.pose_covariance = A * step.covariance * A.transpose();
  const io::RigCalibrationSigma rig = rig_calibration();
  const double rig_rotation_rad = rig.rotation_deg * M_PI / 180.0;
  ctx.rig_rotation_variance_rad2 = rig_rotation_rad * rig_rotation_rad;
  ctx.rig_scale_variance = rig.scale * rig.scale;
  if (ctx.rig_rotation_variance_rad2 > 0.0 || ctx.rig_scale_variance > 0.0) {
    // The rig's error turned and scaled every step before this one alike (FrameContext::rig_*):
    // a step Δc from a pose of rotation R moves by (Rω) × Δc = −[Δc]×R ω.
    const Eigen::Isometry3d* before = nullptr;
    for (const FrameResult& earlier : results_) {
      if (earlier.step.index >= step.index) break;
      if (before != nullptr)
        ctx.rig_drift -=
            core::Skew(earlier.step.T_world_body.translation() - before->translation()) *
            before->linear();
      before = &earlier.step.T_world_body;
    }
    if (before != nullptr) {
      ctx.rig_drift -= core::Skew(T.translation() - before->translation()) * before->linear();
      ctx.rig_scale_origin =
          results_.front().step.T_world_body * sensor_.T_body_sensor.translation();
    }
    ctx.R_world_body = T.linear();
  }
  result->dem = elevation_map_.FuseFrame(T, measured, between, ctx);
  // What stood where this frame sees through is gone (a car, a person, another rover).
  result->dem.cells_cleared =
      elevation_map_.ClearSeenThrough(T, measured, ctx.sensor_origin_world, ctx.frame)
          .cells_cleared;
  result->time.fuse_dem_ms = MsSince(dem_start);

  const auto octomap_start = Clock::now();
  if (options_.octomap.enabled) {
    std::vector<Eigen::Vector3d> points_world;
    points_world.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (keep[i]) points_world.push_back(T * cloud.points[i]);
    }
    octomap_.Insert(std::move(points_world), ctx.sensor_origin_world, ctx.frame);
  }
  result->time.fuse_octomap_ms = MsSince(octomap_start);
}

void Mapper::ResetMaps() {
  elevation_map_ = dem::ElevationMap(GridAlongProjection(options_.dem, georef_));
  octomap_.MutableFusion() = dem::OctoMapFusion(options_.octomap);
}

void Mapper::FuseAgain(const PreparedFrame& prepared, const ChainStep& step) {
  FrameResult scratch;
  Fuse(prepared.Fused(), prepared.isolated.keep, prepared.loaded.fill, step, &scratch);
}

void Mapper::KeepAsReference(std::unique_ptr<registration::IndexedCloud> cloud,
                             const ChainStep& step, double reference_distance_m) {
  reference_index_ = step.index;
  if (reference_distance_m > 0.0) last_reference_distance_m_ = reference_distance_m;
  if (options_.mapper.reference == Reference::kPrevious) {
    previous_ = std::move(cloud);
    return;
  }
  const double voxel = options_.mapper.local_map_voxel_m > 0.0 ? options_.mapper.local_map_voxel_m
                                                               : last_reference_distance_m_;
  local_map_.Add(cloud->cloud(), step.T_world_body, voxel);
}

}  // namespace rovermap::mapper
