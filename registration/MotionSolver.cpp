#include "registration/MotionSolver.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace rovermap::registration {
namespace {

bool SumWeights(const std::vector<WeightedPair>& pairs, double* total) {
  *total = 0.0;
  if (pairs.size() < 3) return false;
  for (const auto& p : pairs) {
    if (!(p.weight > 0.0) || !p.source.allFinite() || !p.target.allFinite()) return false;
    *total += p.weight;
  }
  return *total > 0.0;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d k;
  k << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return k;
}

// Zhang 1994 Appendix B, for q = (q̌, q4) stored as (x, y, z, w):
// Q(q) = [[q4 I + K(q̌), q̌], [−q̌ᵀ, q4]],  W(q) = [[q4 I − K(q̌), q̌], [−q̌ᵀ, q4]].
Eigen::Matrix4d QMatrix(const Eigen::Vector3d& v, double w) {
  Eigen::Matrix4d m;
  m.topLeftCorner<3, 3>() = w * Eigen::Matrix3d::Identity() + Skew(v);
  m.topRightCorner<3, 1>() = v;
  m.bottomLeftCorner<1, 3>() = -v.transpose();
  m(3, 3) = w;
  return m;
}

Eigen::Matrix4d WMatrix(const Eigen::Vector3d& v, double w) {
  Eigen::Matrix4d m;
  m.topLeftCorner<3, 3>() = w * Eigen::Matrix3d::Identity() - Skew(v);
  m.topRightCorner<3, 1>() = v;
  m.bottomLeftCorner<1, 3>() = -v.transpose();
  m(3, 3) = w;
  return m;
}

}  // namespace

MotionEstimate SolveMotionSvd(const std::vector<WeightedPair>& pairs) {
  MotionEstimate out;
  double total = 0.0;
  if (!SumWeights(pairs, &total)) return out;

  Eigen::Vector3d x_mean = Eigen::Vector3d::Zero(), y_mean = Eigen::Vector3d::Zero();
  for (const auto& p : pairs) {
    x_mean += p.weight * p.source;
    y_mean += p.weight * p.target;
  }
  x_mean /= total;
  y_mean /= total;

  // H = Σ w x̃ ỹᵀ on centred coordinates.
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (const auto& p : pairs) h += p.weight * (p.source - x_mean) * (p.target - y_mean).transpose();

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (v * u.transpose()).determinant() < 0.0 ? -1.0 : 1.0;  // reflection guard
  const Eigen::Matrix3d r = v * d * u.transpose();

  out.T_target_source.linear() = r;
  out.T_target_source.translation() = y_mean - r * x_mean;
  out.valid = out.T_target_source.matrix().allFinite();
  return out;
}

MotionEstimate SolveMotionDualQuaternion(const std::vector<WeightedPair>& pairs) {
  MotionEstimate out;
  double total = 0.0;
  if (!SumWeights(pairs, &total)) return out;

  // Points as pure quaternions (v, 0), used as they are (no centring), as in the paper.
  Eigen::Matrix4d c1 = Eigen::Matrix4d::Zero();
  Eigen::Matrix4d c2 = Eigen::Matrix4d::Zero();
  for (const auto& p : pairs) {
    const Eigen::Matrix4d wx = WMatrix(p.source, 0.0);
    const Eigen::Matrix4d qy = QMatrix(p.target, 0.0);
    c1 += -2.0 * p.weight * qy.transpose() * wx;
    c2 += 2.0 * p.weight * (wx - qy);
  }
  // A = ½ [C2ᵀ C2 / (2W) − C1 − C1ᵀ]; q = eigenvector of its largest eigenvalue.
  const Eigen::Matrix4d a = 0.5 * (c2.transpose() * c2 / (2.0 * total) - c1 - c1.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(a);
  if (eig.info() != Eigen::Success) return out;
  const Eigen::Vector4d q = eig.eigenvectors().col(3);  // eigenvalues ascending
  const Eigen::Quaterniond rotation(q(3), q(0), q(1), q(2));

  // s = −C2 q / (2W); t = vector part of W(q)ᵀ s.
  const Eigen::Vector4d s = -c2 * q / (2.0 * total);
  const Eigen::Vector4d t4 = WMatrix(q.head<3>(), q(3)).transpose() * s;
  out.T_target_source.linear() = rotation.normalized().toRotationMatrix();
  out.T_target_source.translation() = t4.head<3>();
  out.valid = out.T_target_source.matrix().allFinite();
  return out;
}

}  // namespace rovermap::registration
