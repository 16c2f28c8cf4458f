#pragma once
// Roll and pitch of dead reckoning as an absolute measurement. A rover's IMU or inclinometers
// measure them against gravity, so they do not drift; frame-to-frame registration estimates the
// relative attitude with a small bias that accumulates along the chain (docs/replay.md, "Known
// limits"), and the DEM tilts with it. A scalar Kalman filter per angle pulls the chained roll and pitch towards
// dead reckoning's; yaw and position stay the registration's.

#include <Eigen/Geometry>

namespace rovermap::mapper {

class AttitudePrior {
 public:
  /// `odometry_sigma_deg`: σ of dead reckoning's roll and pitch (0 = no prior: Update returns
  /// its input); `step_sigma_deg`: σ a registered increment adds to the chained roll and pitch.
  AttitudePrior(double odometry_sigma_deg, double step_sigma_deg);

  bool enabled() const { return odometry_variance_ > 0.0; }

  /// `T_world_body` with its roll and pitch moved towards those of `T_world_body_odom` by the
  /// Kalman gain of one step (variance grown by the step's, then updated). Never throws.
  Eigen::Isometry3d Update(const Eigen::Isometry3d& T_world_body,
                           const Eigen::Isometry3d& T_world_body_odom);

  /// Current variance of the chained roll and pitch [rad²].
  double variance() const { return variance_; }
  /// Restores the variance a saved prior had (service/Checkpoint).
  void RestoreVariance(double variance) { variance_ = variance; }

 private:
  double odometry_variance_ = 0.0;  // [rad²]
  double step_variance_ = 0.0;      // [rad²]
  double variance_ = 0.0;           // [rad²] the chain's, 0 at frame 0 (odometry pose 0)
};

/// Raises the roll and pitch variances (indices 0 and 1, rotations about the body's x and y) of
/// a registered increment's 6×6 covariance (order rx ry rz tx ty tz) to at least
/// `step_sigma_deg`². The registration's own covariance states about 0.01° per step where the
/// simulated traverses' steps err by 0.04–0.05° (its residuals are not independent), and the
/// DEM's σ takes the chained pose's covariance.
void FloorAttitudeVariance(Eigen::Matrix<double, 6, 6>* covariance, double step_sigma_deg);

}  // namespace rovermap::mapper
