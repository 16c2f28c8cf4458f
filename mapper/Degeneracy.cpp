#include "mapper/Degeneracy.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace rovermap::mapper {
namespace {

// δ with T_registered = (Exp(δr), δt) ∘ T_predicted: the parameterisation of the information.
Vector6d LeftDifference(const Eigen::Isometry3d& T_registered,
                        const Eigen::Isometry3d& T_predicted) {
  const Eigen::Isometry3d D = T_registered * T_predicted.inverse();
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

}  // namespace

BlendedIncrement BlendIncrement(const Eigen::Isometry3d& T_predicted,
                                const Eigen::Isometry3d& T_registered, const Matrix6d& information,
                                double extent_m, double min_information,
                                const Matrix6d& odometry_covariance, const Vector6d& odometry_bias,
                                double bias_min_information) {
  BlendedIncrement out;
  // Scaled coordinates δs = S⁻¹δ with S = diag(1/extent ×3, 1 ×3): rotations in metres of arc.
  Vector6d s = Vector6d::Ones();
  s.head<3>().setConstant(1.0 / std::max(extent_m, 1e-9));
  const Matrix6d scaled = s.asDiagonal() * information * s.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(scaled);
  const Vector6d lambda = eig.eigenvalues();  // ascending
  const Matrix6d V = eig.eigenvectors();
  const double largest = lambda(5);
  if (!information.allFinite() || !(largest > 0.0)) {
    out.T = T_predicted;
    out.odometry_directions = kRoll | kPitch | kYaw | kX | kY | kZ;
    out.covariance = odometry_covariance;
    return out;
  }
  out.min_ratio = std::max(0.0, lambda(0)) / largest;

  Matrix6d projector_scaled = Matrix6d::Zero();  // onto the constrained eigenvectors
  Matrix6d informed_scaled = Matrix6d::Zero();   // onto those that inform the bias
  Matrix6d informed_information_scaled = Matrix6d::Zero();
  Matrix6d covariance_scaled = Matrix6d::Zero();
  unsigned taken = 0;
  for (int i = 5; i >= 0; --i) {
    const Vector6d v = V.col(i);
    if (lambda(i) > 0.0 && lambda(i) >= bias_min_information * largest) {
      informed_scaled += v * v.transpose();
      informed_information_scaled += lambda(i) * v * v.transpose();
    }
    if (lambda(i) > 0.0 && (min_information <= 0.0 || lambda(i) >= min_information * largest)) {
      projector_scaled += v * v.transpose();
      covariance_scaled += v * v.transpose() / lambda(i);
      ++out.constrained;
      continue;
    }
    // Name the direction by its largest component not already named.
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
  Vector6d delta_used = projector_scaled * delta_scaled;
  if (out.constrained < 6) delta_used += (Matrix6d::Identity() - projector_scaled) * bias_scaled;
  const Vector6d delta = delta_used.cwiseProduct(s);
  out.T = ApplyLeft(delta, T_predicted);
  // A correction dead reckoning cannot have needed (beyond 3σ of its error model) says
  // nothing of its bias: on nearly flat ground a weakly informed direction can slide metres.
  const Vector6d informed = (informed_scaled * delta_scaled).cwiseProduct(s);
  const Eigen::LDLT<Matrix6d> odometry(odometry_covariance);
  if (odometry.info() == Eigen::Success && informed.dot(odometry.solve(informed)) <= 9.0) {
    out.bias_correction = (informed_scaled * delta_scaled).cwiseProduct(s);
    // Back from scaled coordinates: I = S⁻¹ I_scaled S⁻¹.
    out.bias_information =
        s.cwiseInverse().asDiagonal() * informed_information_scaled * s.cwiseInverse().asDiagonal();
  }

  // Σ = S V_c Λ_c⁻¹ V_cᵀ S  +  P_u Σ_odometry P_uᵀ, P_u = S (I − P_c) S⁻¹.
  const Matrix6d unconstrained =
      s.asDiagonal() * (Matrix6d::Identity() - projector_scaled) * s.cwiseInverse().asDiagonal();
  out.covariance = s.asDiagonal() * covariance_scaled * s.asDiagonal() +
                   unconstrained * odometry_covariance * unconstrained.transpose();
  return out;
}

}  // namespace rovermap::mapper
