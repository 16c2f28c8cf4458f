#pragma once
// Trajectory metrics of docs/design.md §8: ATE after SE(3) Umeyama alignment, ATE aligned at the
// first pose, RPE over a travelled distance, KITTI-style segment errors. No I/O: the replay
// pipeline and `rovermap eval` both call EvaluateTrajectory / EvaluateAssociated and ToJson.

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "eval/EvalOptions.hpp"
#include "eval/TrajectoryIo.hpp"

namespace rovermap::eval {

/// RMSE, mean, median and max of a set of non-negative errors; NaN (JSON null) when empty.
struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
};
ErrorStats ComputeStats(std::vector<double> values);

/// Rigid T_target_source minimising Σ‖target_i − T·source_i‖² (Umeyama 1991, eqs. 34–43, without
/// scale). Needs two or more points of equal count; collinear points leave the rotation about
/// their line arbitrary (the residuals do not depend on it).
/// @throw std::invalid_argument if the counts differ or there are fewer than 2 points.
Eigen::Isometry3d AlignUmeyama(const std::vector<Eigen::Vector3d>& source,
                               const std::vector<Eigen::Vector3d>& target);

/// Rotation angle of `T` [rad], in [0, π] (the KITTI devkit's acos((trace − 1) / 2), as atan2).
double RotationAngle(const Eigen::Isometry3d& T);

/// Cumulative travelled distance along `poses` [m]: 0 for the first, Σ‖t_k − t_{k−1}‖.
std::vector<double> PathDistances(const std::vector<Eigen::Isometry3d>& poses);

/// Index pairs (estimate, ground truth) of poses taken to be the same instant.
struct Association {
  bool by_timestamp = false;  ///< false: by index (a file without timestamps)
  std::vector<std::size_t> estimate_index;
  std::vector<std::size_t> groundtruth_index;
  double max_time_difference_s = 0.0;  ///< largest |Δt| of a pair (0 by index)
  std::string message;                 ///< why there are no pairs, if so
};

/// By timestamp when both have them: each pair within `association_tolerance_s`, closest first,
/// each pose used at most once (as the TUM benchmark's associate.py), ordered by estimate time.
/// Otherwise by index, which needs equal lengths (else no pairs and a message).
Association Associate(const Trajectory& estimate, const Trajectory& groundtruth,
                      const EvalOptions& options);

enum class MetricStatus { kOk, kNoPairs, kTooFewPairs };
std::string ToString(MetricStatus status);

/// KITTI errors for one segment length.
struct SegmentError {
  double length_m = 0.0;
  std::size_t count = 0;       ///< segments found (one per start pose that reaches the length)
  double trans_percent = 0.0;  ///< mean translation error / length [%]
  double rot_deg_per_m = 0.0;  ///< mean rotation error / length [deg/m]
};

struct TrajectoryMetrics {
  MetricStatus status = MetricStatus::kOk;
  std::string message;  ///< why the status is not kOk
  std::size_t pairs = 0;
  double length_m = 0.0;  ///< ground-truth path length over the pairs [m]
  Eigen::Isometry3d T_groundtruth_estimate = Eigen::Isometry3d::Identity();  ///< Umeyama
  ErrorStats ate_m;                  ///< position error after T_groundtruth_estimate [m]
  ErrorStats ate_origin_m;           ///< position error with the first poses made to coincide [m]
  double rpe_delta_m = 0.0;          ///< the RPE pairs' ground-truth travel, as used [m]
  ErrorStats rpe_trans_m;            ///< RPE translation [m] (Sturm et al. 2012, eq. 3)
  ErrorStats rpe_rot_deg;            ///< RPE rotation [deg]
  double kitti_trans_percent = 0.0;  ///< mean over all segments of every length [%]
  double kitti_rot_deg_per_m = 0.0;  ///< mean over all segments of every length [deg/m]
  std::vector<SegmentError> segments;
  /// Per pair, for plots: ground-truth distance travelled [m], the errors [m], and the estimate
  /// positions after each alignment.
  std::vector<double> distance_m;
  std::vector<double> ate_error_m;
  std::vector<double> ate_origin_error_m;
  std::vector<Eigen::Vector3d> groundtruth_positions;
  std::vector<Eigen::Vector3d> aligned_positions;
  std::vector<Eigen::Vector3d> origin_aligned_positions;
};

/// Metrics of already associated poses (estimate[i] ↔ groundtruth[i]); never throws. Fewer than
/// 2 pairs: status kTooFewPairs. RPE and segment statistics that find no pair (trajectory shorter
/// than the delta or segment) are NaN with count 0.
TrajectoryMetrics EvaluateAssociated(const std::vector<Eigen::Isometry3d>& estimate,
                                     const std::vector<Eigen::Isometry3d>& groundtruth,
                                     const EvalOptions& options);

/// Associate, then EvaluateAssociated; no pairs: status kNoPairs with the association's message.
TrajectoryMetrics EvaluateTrajectory(const Trajectory& estimate, const Trajectory& groundtruth,
                                     const EvalOptions& options);

/// The §8 keys (ate_rmse_m, ate_rmse_origin_m, rpe_trans_rmse_m, rpe_rot_rmse_deg,
/// kitti_trans_percent, kitti_rot_deg_per_m, pairs, length_m) plus status, the mean / median /
/// max of each error, the per-length segments and the alignment. NaN → null.
nlohmann::json ToJson(const TrajectoryMetrics& metrics);

}  // namespace rovermap::eval
