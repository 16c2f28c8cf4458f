#include "mapper/Degeneracy.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace rovermap::mapper {

Vector6d LeftDifference(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b) {
  const Eigen::Isometry3d D = T_a * T_b.inverse();
  const Eigen::AngleAxisd aa(D.linear());
  Vector6d delta;
  delta << aa.angle() * aa.axis(), D.translation();
  return delta;
}

Eigen::Isometry3d ApplyLeft(const Vector6d& delta, const Eigen::Isometry3d& T) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  const double angle = delta.head<3>().norm();
  if (angle > 0.0)
    D.linear() = Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
  D.translation() = delta.tail<3>();
  return D * T;
}

namespace {

// The eigen-directions of `A` (the information, scaled) that hold what `B` says a direction
// needs: vᵀAv >= vᵀBv (> 0 when `keep_all`). A's own eigenvectors, because a least-squares
// estimate slides along the weakest of them: that is where its error lies, and an orthogonal
// split keeps it out of the directions taken.
struct Split {
  Matrix6d projector = Matrix6d::Zero();    // orthogonal, onto the passed eigenvectors
  Matrix6d information = Matrix6d::Zero();  // A within them
  Matrix6d covariance = Matrix6d::Zero();   // A⁻¹ within them
  int passed = 0;
};

Split SplitDirections(const Eigen::SelfAdjointEigenSolver<Matrix6d>& A, const Matrix6d& B,
                      bool keep_all) {
  Split out;
  for (int i = 5; i >= 0; --i) {
    const double lambda = A.eigenvalues()(i);
    const Vector6d v = A.eigenvectors().col(i);
    if (!(lambda > 0.0) || (!keep_all && lambda < v.dot(B * v))) continue;
    out.projector += v * v.transpose();
    out.information += lambda * v * v.transpose();
    out.covariance += v * v.transpose() / lambda;
    ++out.passed;
  }
  return out;
}

}  // namespace

BlendedIncrement BlendIncrement(const Eigen::Isometry3d& T_predicted,
                                const Eigen::Isometry3d& T_registered, const Matrix6d& information,
                                double extent_m, double min_information,
                                const Matrix6d& odometry_covariance, const Vector6d& odometry_bias,
                                double bias_min_information, const Matrix6d& noise_information,
                                double min_information_over_noise) {
  BlendedIncrement out;
  // Scaled coordinates δs = S⁻¹δ with S = diag(1/extent ×3, 1 ×3): rotations in metres of arc.
  Vector6d s = Vector6d::Ones();
  s.head<3>().setConstant(1.0 / std::max(extent_m, 1e-9));
  const Matrix6d scaled = s.asDiagonal() * information * s.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(scaled);
  const double largest = eig.eigenvalues()(5);
  if (!information.allFinite() || !noise_information.allFinite() || !(largest > 0.0)) {
    out.T = T_predicted;
    out.odometry_directions = kRoll | kPitch | kYaw | kX | kY | kZ;
    out.covariance = odometry_covariance;
    out.prediction_projector = Matrix6d::Identity();
    return out;
  }
  out.min_ratio = std::max(0.0, eig.eigenvalues()(0)) / largest;

  // What a direction needs: min_information × the best direction's information, and k × what
  // the sensor's noise alone gives it (the noise floor).
  const double k = std::max(0.0, min_information_over_noise);
  const Matrix6d noise_scaled = s.asDiagonal() * noise_information * s.asDiagonal();
  auto needed = [&](double ratio) {
    return Matrix6d(k * noise_scaled + std::max(ratio, 0.0) * largest * Matrix6d::Identity());
  };
  const Split constrained =
      SplitDirections(eig, needed(min_information), min_information <= 0.0 && k <= 0.0);
  const Split informed = SplitDirections(eig, needed(bias_min_information), false);
  out.constrained = constrained.passed;

  // Name each direction left to dead reckoning by its largest component not already named.
  unsigned taken = 0;
  const Matrix6d left = Matrix6d::Identity() - constrained.projector;
  for (int i = 5; i >= 0; --i) {
    const Vector6d v = eig.eigenvectors().col(i);
    if (v.dot(left * v) < 0.5) continue;  // taken from the registration
    int best = -1;
    for (int a = 0; a < 6; ++a) {
      if (taken & (1u << a)) continue;
      if (best < 0 || std::abs(v(a)) > std::abs(v(best))) best = a;
    }
    taken |= 1u << best;
  }
  out.odometry_directions = taken;

  // The registration where it is constrained, dead reckoning plus its bias elsewhere.
  const Vector6d delta_scaled = LeftDifference(T_registered, T_predicted).cwiseQuotient(s);
  const Vector6d bias_scaled = odometry_bias.cwiseQuotient(s);
  Vector6d delta_used = constrained.projector * delta_scaled;
  if (out.constrained < 6) delta_used += left * bias_scaled;
  const Vector6d delta = delta_used.cwiseProduct(s);
  out.T = ApplyLeft(delta, T_predicted);
  // A correction dead reckoning cannot have needed (beyond 3σ of its error model) says
  // nothing of its bias: on nearly flat ground a weakly informed direction can slide metres.
  const Vector6d informed_delta = (informed.projector * delta_scaled).cwiseProduct(s);
  // Nor does a frame whose directions the noise floor took away: its sensor-fixed artefacts
  // bias the others too (range bins tilt the fitted plane and slide it forward together), and
  // the eigenvectors that mix them would carry that into the bias's x and yaw.
  const bool noise_limited =
      k > 0.0 &&
      SplitDirections(eig, needed(bias_min_information) - k * noise_scaled, false).passed >
          informed.passed;
  const Eigen::LDLT<Matrix6d> odometry(odometry_covariance);
  if (!noise_limited && odometry.info() == Eigen::Success &&
      informed_delta.dot(odometry.solve(informed_delta)) <= 9.0) {
    out.bias_correction = informed_delta;
    // Back from scaled coordinates: I = S⁻¹ I_scaled S⁻¹.
    out.bias_information =
        s.cwiseInverse().asDiagonal() * informed.information * s.cwiseInverse().asDiagonal();
  }

  // Σ = S V_c Λ_c⁻¹ V_cᵀ S  +  P_u Σ_odometry P_uᵀ, P_u = S (I − P_c) S⁻¹.
  const Matrix6d unconstrained = s.asDiagonal() * left * s.cwiseInverse().asDiagonal();
  out.covariance_registered = s.asDiagonal() * constrained.covariance * s.asDiagonal();
  out.information_registered =
      s.cwiseInverse().asDiagonal() * constrained.information * s.cwiseInverse().asDiagonal();
  out.prediction_projector = unconstrained;
  out.covariance =
      out.covariance_registered + unconstrained * odometry_covariance * unconstrained.transpose();
  return out;
}

}  // namespace rovermap::mapper
