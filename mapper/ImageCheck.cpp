#include "mapper/ImageCheck.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace rovermap::mapper {
namespace {

// χ² with 6 degrees of freedom at 99.9 %.
constexpr double kImageGate = 22.46;

// The information of a covariance that may be singular (a blend's parts live in complementary
// directions): its pseudo-inverse, eigenvalues below `floor` taken as zero. The floor must come
// from outside: the prediction's part of a blend that took the registration whole is round-off
// (1e-30), whose inverse would swamp everything.
Matrix6d PseudoInverse(const Matrix6d& covariance, double floor) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(covariance);
  Matrix6d out = Matrix6d::Zero();
  for (int i = 0; i < 6; ++i) {
    const double lambda = eig.eigenvalues()(i);
    if (!(lambda > floor)) continue;
    const Vector6d v = eig.eigenvectors().col(i);
    out += v * v.transpose() / lambda;
  }
  return out;
}

}  // namespace

const char* ToString(ImageCheckOutcome outcome) {
  switch (outcome) {
    case ImageCheckOutcome::kNone:
      return "none";
    case ImageCheckOutcome::kUsed:
      return "used";
    case ImageCheckOutcome::kDisagreed:
      return "disagreed";
    case ImageCheckOutcome::kFailed:
      return "failed";
  }
  return "none";
}

std::optional<ImageIncrement> ToBodyIncrement(const stereo::ImageMotion& motion,
                                              const Eigen::Isometry3d& T_body_camera,
                                              double covariance_scale) {
  if (!motion.ok) return std::nullopt;
  const Eigen::FullPivLU<Matrix6d> lu(motion.information);
  if (!lu.isInvertible()) return std::nullopt;
  // T_body = T_bc T_cam T_cb, so a left perturbation δc of T_cam is Ad(T_bc)·δc of T_body.
  const Matrix6d Ad = Adjoint(T_body_camera);
  ImageIncrement out;
  out.T_target_source = T_body_camera * motion.T_previous_current * T_body_camera.inverse();
  out.covariance = covariance_scale * Ad * lu.inverse() * Ad.transpose();
  if (!out.covariance.allFinite()) return std::nullopt;
  return out;
}

ImageFusion FuseImageIncrement(const BlendedIncrement& blended, double registration_scale,
                               const Matrix6d& prediction_covariance, const ImageIncrement& image,
                               double gate_scale) {
  ImageFusion out;
  out.T = blended.T;
  out.odometry_directions = blended.odometry_directions;
  const Matrix6d& P_u = blended.prediction_projector;
  const Matrix6d kept = P_u * prediction_covariance * P_u.transpose();
  out.covariance = registration_scale * blended.covariance_registered + kept;
  const Vector6d difference = LeftDifference(image.T_target_source, blended.T);
  const Eigen::LDLT<Matrix6d> gate(gate_scale * out.covariance + image.covariance);
  if (gate.info() != Eigen::Success) return out;
  out.mahalanobis2 = difference.dot(gate.solve(difference));
  if (!(out.mahalanobis2 <= kImageGate)) return out;
  // The blend's information: the registration's in its constrained directions, the
  // prediction's in the others (each part's pseudo-inverse). A direction of the prediction
  // counts when it keeps more than a millionth of the prediction's largest variance (P_u is a
  // projector: its directions keep all of theirs, the others round-off); a prediction without
  // variance (odometry_noise_* all 0) adds none.
  Matrix6d blend_information = blended.information_registered / registration_scale;
  const double largest = prediction_covariance.diagonal().cwiseAbs().maxCoeff();
  if (blended.constrained < 6 && largest > 0.0)
    blend_information += PseudoInverse(kept, 1e-6 * largest);
  const Matrix6d image_information = image.covariance.inverse();
  const Eigen::LLT<Matrix6d> total(blend_information + image_information);
  if (total.info() != Eigen::Success) return out;
  const Vector6d delta = total.solve(image_information * difference);
  if (!delta.allFinite()) return out;
  out.outcome = ImageCheckOutcome::kUsed;
  out.T = ApplyLeft(delta, blended.T);
  out.covariance = total.solve(Matrix6d::Identity());
  for (int i = 0; i < 6; ++i)
    if (out.covariance(i, i) < 0.5 * kept(i, i)) out.odometry_directions &= ~(1u << i);
  return out;
}

}  // namespace rovermap::mapper
