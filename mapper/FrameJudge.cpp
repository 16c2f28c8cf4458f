#include "mapper/FrameJudge.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>

#include "core/Units.hpp"

namespace rovermap::mapper {
namespace {

using core::kDegToRad;

Judgement Reject(FallbackReason reason, const std::string& detail) {
  return {false, reason, detail};
}

}  // namespace

const char* ToString(FallbackReason reason) {
  switch (reason) {
    case FallbackReason::kNone:
      return "none";
    case FallbackReason::kFirstFrame:
      return "first_frame";
    case FallbackReason::kBadFrame:
      return "bad_frame";
    case FallbackReason::kNoReference:
      return "no_reference";
    case FallbackReason::kRegistrationFailed:
      return "registration_failed";
    case FallbackReason::kLowInlierRatio:
      return "low_inlier_ratio";
    case FallbackReason::kHighRms:
      return "high_rms";
    case FallbackReason::kImplausibleCorrection:
      return "implausible_correction";
    case FallbackReason::kMissing:
      return "missing";
  }
  return "unknown";
}

namespace {

// Both odometry models: a fraction of the step plus a floor, for translation and rotation.
OdometrySigma LinearInStep(double step_length_m, double ratio, double floor_m, double deg_per_m,
                           double floor_deg) {
  const double length = std::abs(step_length_m);
  return {ratio * length + floor_m, (deg_per_m * length + floor_deg) * kDegToRad};
}

}  // namespace

OdometrySigma OdometryStepSigma(double step_length_m, const MapperOptions& o) {
  return LinearInStep(step_length_m, o.odometry_sigma_translation_ratio,
                      o.odometry_sigma_translation_m, o.odometry_sigma_rotation_deg_per_m,
                      o.odometry_sigma_rotation_deg);
}

OdometrySigma OdometryNoiseSigma(double step_length_m, const MapperOptions& o) {
  return LinearInStep(step_length_m, o.odometry_noise_translation_ratio,
                      o.odometry_noise_translation_m, o.odometry_noise_rotation_deg_per_m,
                      o.odometry_noise_rotation_deg);
}

Judgement JudgeRegistration(const registration::RegistrationResult& result,
                            const MapperOptions& options) {
  using registration::RegistrationStatus;
  std::ostringstream why;
  if (result.status != RegistrationStatus::kConverged &&
      result.status != RegistrationStatus::kMaxIterations) {
    why << registration::ToString(result.status);
    if (!result.message.empty()) why << ": " << result.message;
    return Reject(FallbackReason::kRegistrationFailed, why.str());
  }
  if (!(result.inlier_ratio >= options.min_inlier_ratio)) {
    why << "inlier_ratio " << result.inlier_ratio << " < " << options.min_inlier_ratio;
    return Reject(FallbackReason::kLowInlierRatio, why.str());
  }
  if (!(result.rms_m <= options.max_rms_m)) {
    why << "rms " << result.rms_m << " m > " << options.max_rms_m << " m";
    return Reject(FallbackReason::kHighRms, why.str());
  }
  return {true, FallbackReason::kNone, ""};
}

Judgement JudgeCorrection(const Eigen::Isometry3d& T_predicted,
                          const Eigen::Isometry3d& T_registered, const MapperOptions& options) {
  const Eigen::Isometry3d correction = T_predicted.inverse() * T_registered;
  const OdometrySigma sigma = OdometryStepSigma(T_predicted.translation().norm(), options);
  const double dt = correction.translation().norm();
  const double dr = Eigen::AngleAxisd(correction.linear()).angle();
  const double k = options.correction_gate_sigma;
  std::ostringstream why;
  if (!(dt <= k * sigma.translation_m)) {
    why << "translation correction " << dt << " m > " << k << " sigma (" << sigma.translation_m
        << " m)";
    return Reject(FallbackReason::kImplausibleCorrection, why.str());
  }
  if (!(dr <= k * sigma.rotation_rad)) {
    why << "rotation correction " << dr / kDegToRad << " deg > " << k << " sigma ("
        << sigma.rotation_rad / kDegToRad << " deg)";
    return Reject(FallbackReason::kImplausibleCorrection, why.str());
  }
  return {true, FallbackReason::kNone, ""};
}

Matrix6d CovarianceOf(const OdometrySigma& sigma) {
  Matrix6d cov = Matrix6d::Zero();
  cov.diagonal() << Eigen::Vector3d::Constant(sigma.rotation_rad * sigma.rotation_rad),
      Eigen::Vector3d::Constant(sigma.translation_m * sigma.translation_m);
  return cov;
}

}  // namespace rovermap::mapper
