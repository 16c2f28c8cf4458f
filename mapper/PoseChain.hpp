#pragma once
// Chaining of frame-to-frame increments into world poses, and the per-frame correction of
// dead reckoning that drift.csv reports (docs/design.md §6).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <vector>

#include "core/Skew.hpp"

namespace rovermap::mapper {

/// Roll, pitch, yaw [rad] with R = Rz(yaw)·Ry(pitch)·Rx(roll); roll and yaw in [−π, π], pitch
/// in [−π/2, π/2]. Inverse of io::RotationFromRpy (io/Rpy.hpp) for |pitch| < π/2 (angles taken
/// modulo 2π).
/// Gimbal lock (|pitch| = π/2, cos(pitch) < 1e-12): only yaw − roll (pitch = +π/2) or
/// yaw + roll (pitch = −π/2) is defined, so roll is returned as 0 and yaw carries that
/// combination; io::RotationFromRpy of the result still gives R back.
/// `R` must be a rotation; a non-finite R gives non-finite angles.
Eigen::Vector3d EulerRpyFromRotation(const Eigen::Matrix3d& R);

/// A transform as drift.csv writes it.
struct TransformComponents {
  double dx_m = 0.0;
  double dy_m = 0.0;
  double dz_m = 0.0;
  double droll_deg = 0.0;  ///< R = Rz(dyaw)·Ry(dpitch)·Rx(droll), see EulerRpyFromRotation
  double dpitch_deg = 0.0;
  double dyaw_deg = 0.0;
};

/// Translation [m] and roll, pitch, yaw [deg] of `T`. Never fails; see EulerRpyFromRotation for
/// the gimbal-lock case.
TransformComponents CorrectionComponents(const Eigen::Isometry3d& T);

/// True if `T` is finite and its linear part a proper rotation (‖RᵀR − I‖∞ <= 1e-6, det R > 0).
bool IsFiniteRigid(const Eigen::Isometry3d& T);

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Adjoint of `T` (core/Skew.hpp), in RegistrationResult's convention (left: T' = (Exp(δr),
/// δt) ∘ T): a right perturbation ξ of T equals the left perturbation Ad(T)·ξ.
using core::Adjoint;

/// One frame of the chain. The increments are T_{body k−1}_{body k}: they map points of
/// frame k into frame k−1 (registration of frame k onto frame k−1).
struct ChainStep {
  /// Frame index, 0 = first.
  std::size_t index = 0;
  /// The chained pose of frame k.
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  /// The dead-reckoning pose of frame k, as given to Add.
  Eigen::Isometry3d T_world_body_odom = Eigen::Isometry3d::Identity();
  /// T_prev_curr by dead reckoning: T_world_body_odom(k−1)⁻¹ · T_world_body_odom(k).
  Eigen::Isometry3d odom_increment = Eigen::Isometry3d::Identity();
  /// T_prev_curr chained: the registered increment, or odom_increment on fallback.
  Eigen::Isometry3d used_increment = Eigen::Isometry3d::Identity();
  /// odom_increment⁻¹ · used_increment: what registration changed in this step, expressed in
  /// the body frame dead reckoning predicted for frame k.
  Eigen::Isometry3d increment_correction = Eigen::Isometry3d::Identity();
  /// T_world_body_odom⁻¹ · T_world_body: the chained pose in the current odometry body frame,
  /// i.e. the total correction of dead reckoning so far.
  Eigen::Isometry3d cumulative_correction = Eigen::Isometry3d::Identity();
  /// Dead reckoning was used for this step (no registered increment, or it was not a finite
  /// rigid transform). Frame 0 is never a fallback.
  bool fallback = false;
  /// Covariance of T_world_body for a right perturbation in the body frame
  /// (T = T̂ ∘ (Exp(ξr), ξt)), [rx ry rz tx ty tz] (rad, m): zero at frame 0, then
  /// Σ_k = A (Σ_{k−1} + Σ_increment) Aᵀ with A = Adjoint(used_increment⁻¹).
  Matrix6d covariance = Matrix6d::Zero();
  /// Cross-covariance of that pose error with the registration's systematic error b (a unit
  /// Gauss-Markov vector, Add's `systematic_sigma` scales it per step): what lets errors that
  /// repeat from step to step add up linearly instead of as a random walk. Zero at frame 0.
  Matrix6d systematic_cross = Matrix6d::Zero();
};

/// The part of an increment's error that repeats from one step to the next: σ per direction
/// [rx ry rz (rad), tx ty tz (m)] in frame k−1 (as the covariance), and how much of it the
/// next step keeps (b_k = persistence·b_{k−1} + √(1 − persistence²)·w, in [0, 1)).
struct SystematicError {
  Eigen::Matrix<double, 6, 1> sigma = Eigen::Matrix<double, 6, 1>::Zero();
  double persistence = 0.0;
};

/// Chains increments from the first dead-reckoning pose. The chain starts where dead
/// reckoning starts (frame 0: zero correction), so registration only corrects the motion.
/// It keeps only its last step (what the next one is chained from) and running counters, so
/// its memory does not grow with the frames; Add returns each step for the caller to keep
/// (the mapper keeps it in the frame's result, once).
class PoseChain {
 public:
  /// Starts the chain at frame 0 with T_world_body = `T_world_body0_odom`.
  /// @throw std::invalid_argument if `T_world_body0_odom` is not IsFiniteRigid.
  explicit PoseChain(const Eigen::Isometry3d& T_world_body0_odom);

  /// A chain as saved (service/Checkpoint): every step Add returned, frame 0 first; the
  /// counters are recomputed as Add kept them. @throw std::invalid_argument if `steps` is empty.
  explicit PoseChain(const std::vector<ChainStep>& steps);

  /// Dead-reckoning increment from the last frame to a frame at `T_world_body_odom`: the
  /// registration seed T_prev_curr. Never fails (non-finite input gives non-finite output).
  Eigen::Isometry3d PredictIncrement(const Eigen::Isometry3d& T_world_body_odom) const;

  /// Appends the next frame: T_world_body(k) = T_world_body(k−1) · used increment, where the
  /// used increment is `T_prev_curr_registered`, or the dead-reckoning increment (flagged
  /// `fallback`) when it is nullopt or not IsFiniteRigid. `increment_covariance` is the used
  /// increment's, for a left perturbation in the frame k−1 (RegistrationResult's convention);
  /// it is propagated into the step's `covariance`, and so is `systematic`: with x = [ξ; b],
  /// ξ_k = A(ξ_{k−1} + L b_k + n), L = diag(systematic.sigma), b of unit variance,
  ///   Σ_k = A (Σ_{k−1} + Σ_increment + L Lᵀ + φ(C Lᵀ + L Cᵀ)) Aᵀ,  C_k = A (φ C_{k−1} + L).
  /// @return the new step (now back()).
  /// @throw std::invalid_argument if `T_world_body_odom` is not IsFiniteRigid; the chain is
  ///        then unchanged.
  ChainStep Add(const Eigen::Isometry3d& T_world_body_odom,
                const std::optional<Eigen::Isometry3d>& T_prev_curr_registered,
                const Matrix6d& increment_covariance = Matrix6d::Zero(),
                const SystematicError& systematic = {});

  /// The last step (frame 0's at first).
  const ChainStep& back() const { return last_; }
  /// Steps so far, frame 0 included [count].
  std::size_t size() const { return last_.index + 1; }
  /// Steps that used dead reckoning [count].
  std::size_t fallbacks() const { return fallbacks_; }
  /// Travelled distance: Σ ‖translation of used_increment‖ over the steps [m].
  double path_length_m() const { return path_length_m_; }

 private:
  ChainStep last_;
  std::size_t fallbacks_ = 0;
  double path_length_m_ = 0.0;
};

}  // namespace rovermap::mapper
