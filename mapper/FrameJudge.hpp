#pragma once
// Step 4 of the pipeline: is a registration good enough to replace dead reckoning?

#include <Eigen/Geometry>
#include <string>

#include "mapper/MapperOptions.hpp"
#include "mapper/PoseChain.hpp"  // Matrix6d
#include "registration/Icp.hpp"

namespace rovermap::mapper {

/// Why a frame's increment came wholly from dead reckoning (drift.csv `fallback_reason`).
enum class FallbackReason {
  kNone,                   ///< registered
  kFirstFrame,             ///< frame 0: the chain starts at odometry pose 0
  kBadFrame,               ///< unreadable, empty or too few points: not registered, not fused
  kNoReference,            ///< nothing to register onto yet (every earlier frame was bad)
  kRegistrationFailed,     ///< status other than converged / max_iterations
  kLowInlierRatio,         ///< inlier_ratio < mapper.min_inlier_ratio
  kHighRms,                ///< rms > mapper.max_rms_m
  kImplausibleCorrection,  ///< correction beyond mapper.correction_gate_sigma of odometry's error
  kMissing,                ///< a frame that never arrived (serve's gap timeout)
};

/// "none", "first_frame", "bad_frame", ... (the drift.csv spelling).
const char* ToString(FallbackReason reason);

/// The verdict on one registration.
struct Judgement {
  bool accepted = false;
  FallbackReason reason = FallbackReason::kNone;
  std::string detail;  ///< e.g. "inlier_ratio 0.12 < 0.3"
};

/// What wheel odometry can be wrong by over one step of `step_length_m`: translation σ [m] and
/// rotation σ [rad] (MapperOptions' odometry error model).
struct OdometrySigma {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};
OdometrySigma OdometryStepSigma(double step_length_m, const MapperOptions& options);
/// What wheel odometry is typically wrong by over such a step (MapperOptions'
/// `odometry_noise_*`): the covariance of what the chain takes from dead reckoning.
OdometrySigma OdometryNoiseSigma(double step_length_m, const MapperOptions& options);
/// The diagonal covariance [rx ry rz tx ty tz] (rad², m²) of those σ.
Matrix6d CovarianceOf(const OdometrySigma& sigma);

/// Status, inlier ratio and RMS of `result`. Never throws.
Judgement JudgeRegistration(const registration::RegistrationResult& result,
                            const MapperOptions& options);

/// The correction `T_predicted⁻¹ · T_registered` (both the same increment) within
/// correction_gate_sigma × OdometryStepSigma of the predicted step's length. Never throws.
Judgement JudgeCorrection(const Eigen::Isometry3d& T_predicted,
                          const Eigen::Isometry3d& T_registered, const MapperOptions& options);

}  // namespace rovermap::mapper
