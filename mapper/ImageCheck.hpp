#pragma once
// Step 5b of the pipeline, the image check: the increment the left images see (corners of the
// reference frame tracked into this one, stereo::EstimateImageMotion) fused with the registered
// one by information. Pixels hold the rotation at any range, where a far stereo point's depth
// is uncertain by decimetres: on KITTI the images know the heading better than the points, on
// the simulator's renderings far better (docs/replay.md, step 5b).

#include <Eigen/Geometry>
#include <optional>

#include "mapper/Degeneracy.hpp"
#include "stereo/ImageMotion.hpp"

namespace rovermap::mapper {

/// What the image check did with a frame (drift.csv `image_check`).
enum class ImageCheckOutcome {
  kNone,       ///< not run: a cloud frame, the option off, or no reference frame's corners
  kUsed,       ///< fused with the registered increment
  kDisagreed,  ///< beyond the gate: the registered increment kept as it was
  kFailed,     ///< the images gave no estimate (too few corners tracked or fitted)
};
const char* ToString(ImageCheckOutcome outcome);

/// The image estimate of an increment, in the body frame: T_target_source (the reference body
/// frame from this one) and its covariance for a left perturbation [rx ry rz tx ty tz] in the
/// target frame, as RegistrationResult's. `motion` is the camera's (stereo::ImageMotion);
/// `T_body_camera` the sensor's mounting; `covariance_scale` multiplies the inverse of its
/// information. nullopt when `motion` is not ok or its information is singular. Never throws.
struct ImageIncrement {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();
};
std::optional<ImageIncrement> ToBodyIncrement(const stereo::ImageMotion& motion,
                                              const Eigen::Isometry3d& T_body_camera,
                                              double covariance_scale);

/// The blended increment (BlendIncrement's `blended`, whose covariance is
/// `registration_scale` × covariance_registered + P_u·prediction_covariance·P_uᵀ) and the image
/// estimate, fused: with I_b the information of the blend (the pseudo-inverse of each part) and
/// I_i the image's, δ = (I_b + I_i)⁻¹ I_i · Log(T_image · T_blend⁻¹) moves the blend, and the
/// covariance is (I_b + I_i)⁻¹. Only when the two agree: the squared Mahalanobis distance of
/// their difference under gate_scale × the blend's covariance + the image's is within χ²₆
/// 99.9 % (22.46); otherwise `outcome` is kDisagreed and T, covariance are the blend's.
/// `odometry_directions`: the blend's, less those where the fused variance is below half of
/// what dead reckoning's prediction had there (the images hold them now).
struct ImageFusion {
  ImageCheckOutcome outcome = ImageCheckOutcome::kDisagreed;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();
  unsigned odometry_directions = 0;
  double mahalanobis2 = 0.0;  ///< of the difference, under the gate's covariance
};
ImageFusion FuseImageIncrement(const BlendedIncrement& blended, double registration_scale,
                               const Matrix6d& prediction_covariance, const ImageIncrement& image,
                               double gate_scale);

}  // namespace rovermap::mapper
