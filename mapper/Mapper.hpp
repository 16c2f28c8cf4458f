#pragma once
// The pipeline, one frame at a time (docs/design.md §1): load, predict, register, judge, blend the
// degenerate directions, chain, fuse, report. `rovermap replay` and `rovermap serve` both
// drive this class.

#include <Eigen/Geometry>
#include <cstddef>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dem/ElevationMap.hpp"
#include "dem/OctoMapFusion.hpp"
#include "dem/OctoMapOptions.hpp"
#include "io/Georeference.hpp"
#include "io/Sequence.hpp"
#include "mapper/AttitudePrior.hpp"
#include "mapper/BiasEstimate.hpp"
#include "mapper/Degeneracy.hpp"
#include "mapper/FrameJudge.hpp"
#include "mapper/FrameLoader.hpp"
#include "mapper/ImageCheck.hpp"
#include "mapper/LocalMap.hpp"
#include "mapper/MapperOptions.hpp"
#include "mapper/OctoMapWorker.hpp"
#include "mapper/OutlierFilter.hpp"
#include "mapper/Patches.hpp"
#include "mapper/PoseChain.hpp"
#include "registration/Icp.hpp"
#include "stereo/StereoOptions.hpp"
#include "terrain/TerrainOptions.hpp"

namespace rovermap::mapper {

/// Every option the pipeline reads (config sections mapper, registration, stereo, dem, octomap,
/// terrain).
struct PipelineOptions {
  MapperOptions mapper;
  registration::RegistrationOptions registration;
  stereo::StereoOptions stereo;
  dem::ElevationMapOptions dem;
  dem::OctoMapOptions octomap;
  terrain::TerrainOptions terrain;  ///< the layers written with the DEM (service/Outputs)
};

/// Wall time of each stage of one frame [ms]. `load_ms` (reading files) is filled by whoever
/// reads the frame; the mapper fills the rest.
struct StageTimes {
  double load_ms = 0.0;
  double stereo_ms = 0.0;    ///< disparity + triangulation (stereo frames)
  double prepare_ms = 0.0;   ///< sensor → body, outlier search, indexing of the reference
  double register_ms = 0.0;  ///< the matcher (incl. its trees and normals)
  double fuse_dem_ms = 0.0;
  double fuse_octomap_ms = 0.0;  ///< handing the frame to the OctoMap's thread (waits if busy)
  double total_ms = 0.0;         ///< ProcessFrame as a whole (without load_ms)
};

/// How a frame's increment was obtained (drift.csv `status`).
enum class FrameStatus {
  kFirst,       ///< frame 0 (or the first good frame): the chain's start or no reference
  kRegistered,  ///< the whole increment from registration
  kPartial,     ///< registration in the constrained directions, dead reckoning in the others
  kFallback,    ///< the whole increment from dead reckoning (registration rejected)
  kBadFrame,    ///< the frame could not be used: pose from dead reckoning, not fused
};
const char* ToString(FrameStatus status);

/// What happened to one frame: one drift.csv row and more.
struct FrameResult {
  std::size_t index = 0;
  double timestamp = 0.0;
  FrameStatus status = FrameStatus::kFirst;
  FallbackReason fallback_reason = FallbackReason::kNone;
  std::string detail;  ///< the judge's or loader's explanation, if any
  ChainStep step;      ///< pose, dead reckoning, corrections, covariance
  std::optional<Eigen::Isometry3d> T_world_body_truth;  ///< when the frame carries it
  unsigned odometry_directions = 0;                     ///< Direction bits kept from dead reckoning
  ImageCheckOutcome image_check = ImageCheckOutcome::kNone;  ///< step 5b
  /// The matcher's result (status "-" when it did not run).
  std::string matcher_status = "-";
  int iterations = 0;
  std::size_t inliers = 0;
  double inlier_ratio = 0.0;
  double rms_m = 0.0;
  double conditioning = 0.0;
  std::size_t points = 0;            ///< usable points of the frame [count]
  std::size_t outliers_removed = 0;  ///< isolated points not fused [count]
  std::size_t dropped_nonfinite = 0;
  dem::FusionStats dem;
  StageTimes time;
  /// What step 6 chained: the registered pose before the attitude prior (nullopt: dead
  /// reckoning's increment), the increment's covariance, and the registration's D that the
  /// next frame inherits. A checkpoint's journal keeps them to re-apply the frame (Reapply)
  /// without registering it again.
  std::optional<Eigen::Isometry3d> T_world_body_registered;
  Matrix6d increment_covariance = Matrix6d::Zero();
  double reference_distance_m = 0.0;
  /// Dead reckoning's estimated bias per increment after this frame, and the information it
  /// rests on (BiasEstimate): a left perturbation [rx ry rz (rad) tx ty tz (m)] in the previous
  /// body frame.
  BiasEstimate odometry_bias;
};

/// Step 1's outcome: a frame's points loaded, indexed (tree built) and their isolated points
/// flagged. It depends on the frame alone, so it can be made while an earlier frame is processed.
struct PreparedFrame {
  /// ok, reason and counts. Its cloud is moved into `source` when ok, unless the matcher
  /// registers merged points (MapperOptions::registration_cell_px): then it stays, for the DEM.
  LoadedFrame loaded;
  std::unique_ptr<registration::IndexedCloud> source;  ///< null when !loaded.ok
  OutlierMask isolated;                                ///< over the points fused (Fused())
  /// The points the DEM and the OctoMap take: the loaded cloud, or `source`'s when it was moved.
  const registration::PointCloud& Fused() const {
    return loaded.cloud.empty() && source ? source->cloud() : loaded.cloud;
  }
  double prepare_ms = 0.0;  ///< indexing and the outlier search
};

/// A journalled frame that does not re-apply to the state it is given (another configuration,
/// changed input files).
class ReapplyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The sensor as the pipeline uses it: sequence.yaml's, with stereo.num_disparities 0 resolved
/// from the camera's height and tilt above the ground, and the stereo fill limited to the points
/// the DEM would fuse (StereoOptions::fill_max_horizontal_sigma_m). Never throws.
SensorSetup ResolveSensor(const io::SequenceInfo& sequence, const stereo::StereoOptions& options,
                          const dem::ElevationMapOptions& dem, bool image_check = false);

/// Whether `options` run the image check (step 5b): mapper.image_check with the previous frame
/// as the reference (the local map has no single frame whose image the corners come from).
inline bool ImageCheckOn(const MapperOptions& options) {
  return options.image_check && options.reference == Reference::kPrevious;
}

/// One sequence's pipeline. Holds the previous frame's indexed cloud (or the local map), the
/// pose chain and the two maps; no frame's points are kept beyond the next frame (beyond K
/// frames with the local map), so memory follows the mapped area, not the frame count.
class Mapper {
 public:
  /// `sequence`: sensor, calibration, T_body_sensor and geodetic origin (for the DEM's grid
  /// rotation). @throw std::invalid_argument naming the option if an option is invalid, or if
  /// the origin is invalid.
  Mapper(const io::SequenceInfo& sequence, const PipelineOptions& options);

  /// The recipe: LoadFrame, then ProcessLoaded. Frames must come in index order, frame 0 first
  /// (a frame that could not be read goes to SkipFrame). `load_ms`: the caller's time reading
  /// the frame, for the report. Never throws on data.
  FrameResult ProcessFrame(const io::Frame& frame, double load_ms = 0.0);

  /// The same with the points already loaded (LoadFrame is thread-safe, so a caller may load the
  /// next frame while this one is registered). `frame`'s images / cloud are not read.
  FrameResult ProcessLoaded(const io::Frame& frame, LoadedFrame loaded, double load_ms = 0.0);

  /// Step 1 alone: LoadFrame, then the index and the outlier flags. Reads only the sensor and
  /// the options, so it may run on another thread while this mapper processes an earlier frame
  /// (ReadAhead does). Never throws on data.
  PreparedFrame Prepare(const io::Frame& frame) const;
  PreparedFrame Prepare(LoadedFrame loaded) const;
  /// Steps 2-8 for a frame made by Prepare.
  FrameResult ProcessPrepared(const io::Frame& frame, PreparedFrame prepared, double load_ms = 0.0);

  /// A frame that could not be read (or never arrived): its pose is the dead-reckoning
  /// prediction from `T_world_body_odom`, nothing is fused, and the next frame registers onto
  /// the last good one.
  FrameResult SkipFrame(std::size_t index, double timestamp,
                        const Eigen::Isometry3d& T_world_body_odom, FallbackReason reason,
                        const std::string& detail,
                        const std::optional<Eigen::Isometry3d>& T_world_body_truth = {});

  /// Re-applies a frame processed before (a checkpoint's journal, service/Checkpoint): chains
  /// `recorded`'s increment and fuses the frame's points (read from `frame`, which a bad frame
  /// does not need: pass nullptr) without registering; the state then equals the one
  /// ProcessFrame left, and results() ends with `recorded`.
  /// @throw ReapplyError if the frame cannot be read now or the chained pose differs.
  /// `bins`: when given, the frame's points binned for the pose graph's tracks (BinFrame).
  FrameResult Reapply(const FrameResult& recorded, const io::Frame* frame,
                      FrameBins* bins = nullptr);

  /// Empties the DEM and the OctoMap, keeping the results and the chain: the pose graph's
  /// re-fusion (GnssGraph's RefuseFrames) fuses every frame again at its optimised pose.
  void ResetMaps();
  /// Step 7 alone: fuses `prepared` at `step`'s pose with its covariance, as ProcessPrepared
  /// did; registers, chains and records nothing. Never throws on data.
  void FuseAgain(const PreparedFrame& prepared, const ChainStep& step);

  /// Every frame's result so far, in order.
  const std::vector<FrameResult>& results() const { return results_; }
  /// The chain (nullptr before the first frame).
  const PoseChain* chain() const { return chain_.get(); }
  const dem::ElevationMap& elevation_map() const { return elevation_map_; }
  /// The OctoMap, once every frame processed so far is in it (insertion runs on its own thread).
  const dem::OctoMapFusion& octomap() const { return octomap_.Fusion(); }
  /// The OctoMap's bytes once the frames processed so far are in, made on its thread (no wait
  /// here; see OctoMapWorker::SerialiseWhenQueuedIn).
  /// With `corrections`, the bytes of the tree moved with them (OctoMapWorker::Corrections,
  /// per chain step index).
  std::shared_future<std::optional<OctoMapWorker::TreeBytes>> OctoMapBytes(
      bool with_ot, std::shared_ptr<const OctoMapWorker::Corrections> corrections = nullptr) const {
    return octomap_.SerialiseWhenQueuedIn(with_ot, std::move(corrections));
  }
  const io::Georeference& georeference() const { return georef_; }
  const io::SequenceInfo& sequence() const { return sequence_; }
  const PipelineOptions& options() const { return options_; }
  const SensorSetup& sensor() const { return sensor_; }
  /// The rig's calibration σ that the DEM's σ carries: sequence.yaml's sensor.calibration_sigma
  /// when the recording states it, else mapper.rig_rotation_sigma_deg and rig_scale_sigma.
  io::RigCalibrationSigma rig_calibration() const {
    return sequence_.calibration_sigma.value_or(io::RigCalibrationSigma{
        options_.mapper.rig_rotation_sigma_deg, options_.mapper.rig_scale_sigma});
  }

 private:
  struct Registered;               // the outcome of register + judge + blend
  friend struct CheckpointAccess;  // service/Checkpoint: the state to and from disk
  FrameResult Process(const io::Frame& frame, PreparedFrame prepared, double load_ms,
                      const FrameResult* recorded);
  static Registered Recorded(const FrameResult& recorded);
  static FrameResult Begin(const io::Frame& frame, const PreparedFrame& prepared, double load_ms);
  static void Report(const Registered& reg, FrameResult* result);
  Registered RegisterOntoReference(const registration::IndexedCloud& source,
                                   const Eigen::Isometry3d& T_world_body_odom,
                                   const stereo::ImageLandmarks* landmarks = nullptr);
  /// `odometry_in_doubt`: the registration disagreed with dead reckoning beyond the gate, so a
  /// fallback step carries the gates' bound (odometry_sigma_*) rather than the typical error.
  ChainStep Chain(const io::Frame& frame, const std::optional<Eigen::Isometry3d>& T_world_body,
                  const Matrix6d& covariance_in_previous, bool odometry_in_doubt = false);
  /// A fallback step's covariance: what dead reckoning is typically wrong by (odometry_noise_*),
  /// or, `in_doubt`, what it can be wrong by (odometry_sigma_*).
  Matrix6d OdometryCovariance(const Eigen::Isometry3d& increment, bool in_doubt) const;
  /// Dead reckoning's estimated bias per increment (see BlendIncrement): the last frame's.
  BiasEstimate OdometryBias() const {
    return results_.empty() ? BiasEstimate{} : results_.back().odometry_bias;
  }
  void Fuse(const registration::PointCloud& cloud, const std::vector<unsigned char>& keep,
            const registration::PointCloud& fill, const ChainStep& step, FrameResult* result);
  void KeepAsReference(std::unique_ptr<registration::IndexedCloud> cloud, const ChainStep& step,
                       double reference_distance_m);

  io::SequenceInfo sequence_;
  PipelineOptions options_;
  SensorSetup sensor_;
  io::Georeference georef_;
  std::unique_ptr<PoseChain> chain_;
  AttitudePrior attitude_;
  dem::ElevationMap elevation_map_;
  OctoMapWorker octomap_;
  // The registration reference: the last good frame (its index in the chain and its cloud),
  // or the local map of the last K good frames.
  std::optional<std::size_t> reference_index_;
  std::unique_ptr<registration::IndexedCloud> previous_;
  stereo::ImageLandmarks previous_landmarks_;  ///< the reference frame's, for the image check
  LocalMap local_map_;
  double last_reference_distance_m_ = 0.0;
  std::vector<FrameResult> results_;
};

}  // namespace rovermap::mapper
