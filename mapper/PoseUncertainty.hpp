#pragma once
// The chained pose's uncertainty as a user reads it (σ per axis, drift.csv) and as ground truth
// checks it (how often the true pose lies where the covariance says, summary.json).

#include <optional>
#include <vector>

#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

/// 1σ of a chained pose: position along the world axes [m], roll and pitch about the body's
/// x and y axes and yaw about the world's z axis [deg].
struct PoseSigmas {
  double x_m = 0.0, y_m = 0.0, z_m = 0.0;
  double roll_deg = 0.0, pitch_deg = 0.0, yaw_deg = 0.0;
};

/// From ChainStep::covariance (right perturbation in the body frame). Never throws.
PoseSigmas SigmasOf(const ChainStep& step);

/// The map from the right perturbation ξ of `T_world_body` to drift.csv's axes, in its order
/// (world x, y, z; roll and pitch about the body's x and y; yaw about the world's z): SigmasOf's
/// σ are the square roots of diag(J Σ Jᵀ). Never throws.
Matrix6d UserAxesJacobian(const Eigen::Isometry3d& T_world_body);

/// How the true poses fall against the chained covariances (frames with ground truth, frame 0
/// and frames with a singular covariance left out). The error of frame k is the right
/// perturbation ξ with T_true = T_k ∘ (Exp(ξr), ξt), the truth moved so that frame 0 coincides
/// with the chain's start (drift as the rover sees it, as ate_origin).
struct CalibrationCheck {
  std::size_t frames = 0;
  /// Frames whose NEES ξᵀΣ⁻¹ξ is within χ²₆(0.9545) = 12.85, the 6-D "within 2σ"; a calibrated
  /// covariance gives 0.954, an optimistic one less [ratio].
  double within_2sigma = 0.0;
  double nees_mean = 0.0;  ///< mean NEES; 6 when calibrated
  double nees_median = 0.0;
  /// Axis by axis, in drift.csv's σ axes (world x, y, z; roll, pitch; world yaw): the mean of
  /// error² / σ² over the frames; 1 when that axis is calibrated, above 1 too confident (its σ
  /// √ratio times too small), below 1 cautious. A 6-D NEES of 6 can hide one axis too
  /// confident behind others too cautious.
  Vector6d axis_ratio = Vector6d::Zero();
};

/// nullopt when no frame qualifies. Never throws.
std::optional<CalibrationCheck> CheckCalibration(const std::vector<FrameResult>& results);

/// The same for other poses and covariances of the same frames (`steps`, one per result: the
/// pose graph's): with `against_world` the truth as it is (a graph held by fixes or a reference
/// states its uncertainty against the world), frame 0 included. Never throws.
std::optional<CalibrationCheck> CheckCalibration(const std::vector<FrameResult>& results,
                                                 const std::vector<ChainStep>& steps,
                                                 bool against_world);

}  // namespace rovermap::mapper
