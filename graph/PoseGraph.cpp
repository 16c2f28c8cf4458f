#include "graph/PoseGraph.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "core/Skew.hpp"

namespace rovermap::graph {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// Upper-triangular L with LᵀL = Σ⁻¹ (the whitening of a residual), eigenvalues of Σ floored at
// `floor_variance`: a direction given as exact still weighs finitely.
template <int N>
Eigen::Matrix<double, N, N> SqrtInformation(const Eigen::Matrix<double, N, N>& covariance,
                                            const Eigen::Matrix<double, N, 1>& floor_variance) {
  const Eigen::Matrix<double, N, N> floor = floor_variance.asDiagonal();
  const Eigen::Matrix<double, N, N> sym = 0.5 * (covariance + covariance.transpose()) + floor;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(sym);
  const Eigen::Matrix<double, N, 1> values = eig.eigenvalues().cwiseMax(floor_variance.minCoeff());
  // Σ⁻¹ = V diag(1/λ) Vᵀ; its Cholesky factor's transpose whitens.
  const Eigen::Matrix<double, N, N> information =
      eig.eigenvectors() * values.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  return Eigen::LLT<Eigen::Matrix<double, N, N>>(information).matrixU();
}

template <int N>
void CheckCovariance(const Eigen::Matrix<double, N, N>& c, const std::string& what) {
  if (!c.allFinite()) throw std::invalid_argument(what + ": covariance is not finite");
  if ((c - c.transpose()).cwiseAbs().maxCoeff() > 1e-9 * std::max(1.0, c.cwiseAbs().maxCoeff()))
    throw std::invalid_argument(what + ": covariance is not symmetric");
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(c);
  if (eig.eigenvalues().minCoeff() < -1e-9 * std::max(1.0, eig.eigenvalues().maxCoeff()))
    throw std::invalid_argument(what + ": covariance is not positive semi-definite");
}

// A node: rotation as Eigen's quaternion (x, y, z, w in memory) and translation.
struct Node {
  double q[4];
  double t[3];
};

Node ToNode(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  return {{q.x(), q.y(), q.z(), q.w()},
          {T.translation().x(), T.translation().y(), T.translation().z()}};
}

Eigen::Isometry3d FromNode(const Node& n) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(n.q[3], n.q[0], n.q[1], n.q[2]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(n.t[0], n.t[1], n.t[2]);
  return T;
}

// [log(R_D); t_D] of D = T_est ∘ T_meas⁻¹: the left perturbation that takes the measurement to
// the estimate, in the measurement's reference frame.
template <typename T>
void LeftError(const Eigen::Quaternion<T>& q_est, const Eigen::Matrix<T, 3, 1>& t_est,
               const Eigen::Quaterniond& q_meas, const Eigen::Vector3d& t_meas, T* e) {
  const Eigen::Quaternion<T> q_d = q_est * q_meas.conjugate().cast<T>();
  const Eigen::Matrix<T, 3, 1> t_d = t_est - q_d * t_meas.cast<T>();
  const T wxyz[4] = {q_d.w(), q_d.x(), q_d.y(), q_d.z()};
  ceres::QuaternionToAngleAxis(wxyz, e);
  e[3] = t_d.x();
  e[4] = t_d.y();
  e[5] = t_d.z();
}

// A measured pose with its whitening: the residual of an estimate is L·[log(R_D); t_D].
struct PoseMeasurement {
  Eigen::Quaterniond q_meas;
  Eigen::Vector3d t_meas;
  Matrix6d sqrt_information;

  template <typename T>
  void Whitened(const Eigen::Quaternion<T>& q_est, const Eigen::Matrix<T, 3, 1>& t_est,
                T* residual) const {
    Eigen::Matrix<T, 6, 1> e;
    LeftError(q_est, t_est, q_meas, t_meas, e.data());
    Eigen::Map<Eigen::Matrix<T, 6, 1>> out(residual);
    out = sqrt_information.cast<T>() * e;
  }
};

// Relative factor: T_est = T_i⁻¹ T_j against the measured increment.
struct RelativeCost {
  PoseMeasurement measured;

  template <typename T>
  bool operator()(const T* qi, const T* ti, const T* qj, const T* tj, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> Qi(qi), Qj(qj);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> Ti(ti), Tj(tj);
    measured.Whitened(Eigen::Quaternion<T>(Qi.conjugate() * Qj),
                      Eigen::Matrix<T, 3, 1>(Qi.conjugate() * (Tj - Ti)), residual);
    return true;
  }
};

// Prior on a node's whole pose, in the world frame.
struct PriorCost {
  PoseMeasurement measured;

  template <typename T>
  bool operator()(const T* q, const T* t, T* residual) const {
    measured.Whitened(Eigen::Quaternion<T>(Eigen::Map<const Eigen::Quaternion<T>>(q)),
                      Eigen::Matrix<T, 3, 1>(Eigen::Map<const Eigen::Matrix<T, 3, 1>>(t)),
                      residual);
    return true;
  }
};

// Position fix of the node's point `lever` (body frame).
struct PositionCost {
  Eigen::Vector3d position;
  Eigen::Vector3d lever;
  Eigen::Matrix3d sqrt_information;

  template <typename T>
  bool operator()(const T* q, const T* t, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> Q(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> Tt(t);
    const Eigen::Matrix<T, 3, 1> e = Tt + Q * lever.cast<T>() - position.cast<T>();
    Eigen::Map<Eigen::Matrix<T, 3, 1>> out(residual);
    out = sqrt_information.cast<T>() * e;
    return true;
  }
};

// Absolute pose of a node: [log(R·R_measᵀ); t − t_meas] in world axes, whitened by L (LᵀL is
// the information, rows only for the directions it holds).
struct AbsolutePoseCost {
  Eigen::Quaterniond q_meas;
  Eigen::Vector3d t_meas;
  Matrix6d sqrt_information;
  bool use_z = false;   // PoseFactor::z_offset
  bool use_xy = false;  // PoseFactor::xy_offset

  // The measured position is the reference's: t_meas = t + [xy; z] (offsets it reads at).
  template <typename T>
  bool operator()(const T* q, const T* t, const T* z, const T* xy, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> Q(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> Tt(t);
    const Eigen::Quaternion<T> q_d = Q * q_meas.conjugate().cast<T>();
    const T wxyz[4] = {q_d.w(), q_d.x(), q_d.y(), q_d.z()};
    Eigen::Matrix<T, 6, 1> e;
    ceres::QuaternionToAngleAxis(wxyz, e.data());
    e.template tail<3>() = Tt - t_meas.cast<T>();
    if (use_xy) {
      e(3) += xy[0];
      e(4) += xy[1];
    }
    if (use_z) e(5) += z[0];  // the reference reads `offset` higher: t_z − (t_meas_z − offset)
    Eigen::Map<Eigen::Matrix<T, 6, 1>> out(residual);
    out = sqrt_information.cast<T>() * e;
    return true;
  }
};

// The prior of the shared horizontal offset: zero, σ per axis.
struct OffsetPriorCost {
  double inverse_sigma = 1.0;
  template <typename T>
  bool operator()(const T* xy, T* residual) const {
    residual[0] = xy[0] * inverse_sigma;
    residual[1] = xy[1] * inverse_sigma;
    return true;
  }
};

// L with LᵀL = `information` (PSD), and its rank.
Matrix6d SqrtOfInformation(const Matrix6d& information, int* rank) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(0.5 * (information + information.transpose()));
  const double largest = std::max(eig.eigenvalues().maxCoeff(), 0.0);
  Matrix6d L = Matrix6d::Zero();
  *rank = 0;
  for (int i = 0; i < 6; ++i) {
    const double lambda = eig.eigenvalues()(i);
    if (!(lambda > 1e-12 * largest)) continue;
    L.row(i) = std::sqrt(lambda) * eig.eigenvectors().col(i).transpose();
    ++*rank;
  }
  return L;
}

double PoseChi2(const PoseFactor& f, const Matrix6d& L, const Eigen::Isometry3d& T, double z_offset,
                const double* xy_offset) {
  Eigen::Matrix<double, 6, 1> e;
  const Eigen::AngleAxisd aa(T.linear() * f.T_world_body.linear().transpose());
  e << aa.angle() * aa.axis(), T.translation() - f.T_world_body.translation();
  if (f.z_offset) e(5) += z_offset;
  if (f.xy_offset) e.segment<2>(3) += Eigen::Vector2d(xy_offset[0], xy_offset[1]);
  return (L * e).squaredNorm();
}

// A loop's whitened squared residual: the left error of T_i⁻¹ T_j against the measured
// increment, as RelativeCost computes it.
double LoopChi2(const LoopFactor& f, const Matrix6d& L, const Eigen::Isometry3d& Ti,
                const Eigen::Isometry3d& Tj) {
  const Eigen::Isometry3d D = (Ti.inverse() * Tj) * f.T_from_to.inverse();
  const Eigen::AngleAxisd aa(D.linear());
  Eigen::Matrix<double, 6, 1> e;
  e << aa.angle() * aa.axis(), D.translation();
  return (L * e).squaredNorm();
}

// χ² at 99.9 % for 1..6 degrees of freedom; the gate of `dof` at the probability that
// `gate_3` (a fix's gate) has for 3.
double GateFor(int dof, double gate_3) {
  constexpr double kChi2[6] = {10.83, 13.82, 16.27, 18.47, 20.52, 22.46};
  return kChi2[std::clamp(dof, 1, 6) - 1] * gate_3 / kChi2[2];
}

double FixChi2(const PositionFactor& f, const Eigen::Matrix3d& sqrt_information,
               const Eigen::Isometry3d& T) {
  return (sqrt_information * (T * f.lever_arm_body - f.position_world)).squaredNorm();
}

// Every node's marginal covariance at the solution of `problem`; given node 0 (held constant)
// when `given_first`.
// Ceres's tangent of an EigenQuaternionManifold block is δ with q' = [cos|δ|, sin|δ| δ/|δ|] ⊗ q:
// a left (world) rotation by the rotation vector 2δ; a translation block's is the world
// translation. The chain's convention is a right perturbation in the body frame, (Exp(ξr), ξt)
// applied after T: ξr = Rᵀ·2δ, ξt = Rᵀ·δt.
void MarginalCovariances(ceres::Problem* problem, std::vector<Node>* nodes, bool given_first,
                         std::size_t first_free, PoseGraphResult* result) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t first = std::max<std::size_t>(given_first ? 1 : 0, first_free);
  if (given_first && first_free == 0) {
    problem->SetParameterBlockConstant((*nodes)[0].q);
    problem->SetParameterBlockConstant((*nodes)[0].t);
  }
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::SPARSE_QR;
  options.num_threads = 1;
  ceres::Covariance covariance(options);
  std::vector<std::pair<const double*, const double*>> blocks;
  for (std::size_t k = first; k < nodes->size(); ++k) {
    const Node& n = (*nodes)[k];
    blocks.emplace_back(n.q, n.q);
    blocks.emplace_back(n.q, n.t);
    blocks.emplace_back(n.t, n.t);
  }
  if (!covariance.Compute(blocks, problem)) {
    result->covariance_message = "the graph's covariance could not be computed (rank deficient)";
    return;
  }
  result->covariance.assign(nodes->size(), Matrix6d::Zero());
  result->covariance_given_first = given_first;
  for (std::size_t k = first; k < nodes->size(); ++k) {
    const Node& n = (*nodes)[k];
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> qq, qt, tt;
    covariance.GetCovarianceBlockInTangentSpace(n.q, n.q, qq.data());
    covariance.GetCovarianceBlockInTangentSpace(n.q, n.t, qt.data());
    covariance.GetCovarianceBlockInTangentSpace(n.t, n.t, tt.data());
    Matrix6d world;  // [2δ; δt]
    world << 4.0 * qq, 2.0 * qt, 2.0 * qt.transpose(), tt;
    const Eigen::Matrix3d Rt = FromNode(n).linear().transpose();
    Matrix6d B = Matrix6d::Zero();
    B.topLeftCorner<3, 3>() = Rt;
    B.bottomRightCorner<3, 3>() = Rt;
    const Matrix6d body = B * world * B.transpose();
    result->covariance[k] = 0.5 * (body + body.transpose());
  }
  result->covariance_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void Validate(const PoseGraphOptions& o) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("graph.") + name + " must be > 0");
  };
  positive(o.fix_huber_sigmas, "fix_huber_sigmas");
  positive(o.fix_gate_chi2, "fix_gate_chi2");
  positive(o.first_pose_sigma_deg, "first_pose_sigma_deg");
  positive(o.first_pose_sigma_m, "first_pose_sigma_m");
  positive(o.min_increment_sigma_rad, "min_increment_sigma_rad");
  positive(o.min_increment_sigma_m, "min_increment_sigma_m");
  positive(o.xy_offset_sigma_m, "xy_offset_sigma_m");
  if (o.max_gate_rounds < 1) throw std::invalid_argument("graph.max_gate_rounds must be >= 1");
  if (o.min_fixes < 1) throw std::invalid_argument("graph.min_fixes must be >= 1");
  if (o.max_iterations < 1) throw std::invalid_argument("graph.max_iterations must be >= 1");
}

PoseGraphResult SolvePoseGraph(const std::vector<Eigen::Isometry3d>& initial,
                               const std::vector<RelativeFactor>& relative,
                               const std::vector<PositionFactor>& positions,
                               const PoseGraphOptions& options) {
  return SolvePoseGraph(initial, relative, positions, {}, options);
}

PoseGraphResult SolvePoseGraph(const std::vector<Eigen::Isometry3d>& initial,
                               const std::vector<RelativeFactor>& relative,
                               const std::vector<PositionFactor>& positions,
                               const std::vector<PoseFactor>& poses,
                               const PoseGraphOptions& options,
                               const std::vector<LoopFactor>& loops) {
  Validate(options);
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = initial.size();
  for (std::size_t k = 0; k < relative.size(); ++k) {
    const RelativeFactor& f = relative[k];
    const std::string what = "relative factor " + std::to_string(k);
    if (f.from >= n || f.to >= n || f.from == f.to)
      throw std::invalid_argument(what + ": nodes " + std::to_string(f.from) + ", " +
                                  std::to_string(f.to) + " of " + std::to_string(n));
    CheckCovariance<6>(f.covariance, what);
  }
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const PositionFactor& f = positions[k];
    const std::string what = "position factor " + std::to_string(k);
    if (f.node >= n)
      throw std::invalid_argument(what + ": node " + std::to_string(f.node) + " of " +
                                  std::to_string(n));
    if (!f.position_world.allFinite() || !f.lever_arm_body.allFinite())
      throw std::invalid_argument(what + ": position is not finite");
    CheckCovariance<3>(f.covariance, what);
  }
  for (std::size_t k = 0; k < loops.size(); ++k) {
    const LoopFactor& f = loops[k];
    const std::string what = "loop factor " + std::to_string(k);
    if (f.from >= n || f.to >= n || f.from == f.to)
      throw std::invalid_argument(what + ": nodes " + std::to_string(f.from) + ", " +
                                  std::to_string(f.to) + " of " + std::to_string(n));
    if (!f.T_from_to.matrix().allFinite())
      throw std::invalid_argument(what + ": increment is not finite");
    CheckCovariance<6>(f.information, what + " information");
  }
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const PoseFactor& f = poses[k];
    const std::string what = "pose factor " + std::to_string(k);
    if (f.node >= n)
      throw std::invalid_argument(what + ": node " + std::to_string(f.node) + " of " +
                                  std::to_string(n));
    if (!f.T_world_body.matrix().allFinite())
      throw std::invalid_argument(what + ": pose is not finite");
    CheckCovariance<6>(f.information, what + " information");
  }

  PoseGraphResult result;
  result.T_world_body = initial;
  result.fix_used.assign(positions.size(), false);
  result.fix_chi2.assign(positions.size(), 0.0);
  result.pose_used.assign(poses.size(), false);
  result.pose_chi2.assign(poses.size(), 0.0);
  result.loop_used.assign(loops.size(), false);
  result.loop_chi2.assign(loops.size(), 0.0);
  const bool any_gated =
      std::any_of(poses.begin(), poses.end(), [](const PoseFactor& f) { return f.gated; });
  if (n > 0 && options.first_free_node >= n) {
    throw std::invalid_argument("graph: first_free_node " +
                                std::to_string(options.first_free_node) +
                                " holds every one of the " + std::to_string(n) + " nodes");
  }
  if ((positions.empty() && !any_gated && loops.empty()) || n == 0) {
    result.message = "no absolute factor: the chained trajectory is kept";
    return result;
  }

  Eigen::Matrix<double, 6, 1> increment_floor;
  increment_floor << Eigen::Vector3d::Constant(std::pow(options.min_increment_sigma_rad, 2)),
      Eigen::Vector3d::Constant(std::pow(options.min_increment_sigma_m, 2));
  std::vector<Matrix6d> relative_L(relative.size());
  for (std::size_t k = 0; k < relative.size(); ++k)
    relative_L[k] = SqrtInformation<6>(relative[k].covariance, increment_floor);
  std::vector<Eigen::Matrix3d> fix_L(positions.size());
  for (std::size_t k = 0; k < positions.size(); ++k)
    fix_L[k] = SqrtInformation<3>(positions[k].covariance, Eigen::Vector3d::Constant(1e-12));
  std::vector<Matrix6d> pose_L(poses.size());
  std::vector<double> pose_gate(poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    int rank = 0;
    pose_L[k] = SqrtOfInformation(poses[k].information, &rank);
    pose_gate[k] = GateFor(rank, options.fix_gate_chi2);
  }
  std::vector<Matrix6d> loop_L(loops.size());
  std::vector<double> loop_gate(loops.size());
  for (std::size_t k = 0; k < loops.size(); ++k) {
    int rank = 0;
    loop_L[k] = SqrtOfInformation(loops[k].information, &rank);
    loop_gate[k] = GateFor(rank, options.fix_gate_chi2);
  }
  Matrix6d prior_L = Matrix6d::Zero();
  prior_L.diagonal() << Eigen::Vector3d::Constant(1.0 / (options.first_pose_sigma_deg * kDegToRad)),
      Eigen::Vector3d::Constant(1.0 / options.first_pose_sigma_m);

  // The held part's prior on a window's first node: the chain's convention (a right
  // perturbation) as the left one PriorCost weighs, Ad(T) Σ Ad(T)ᵀ.
  Matrix6d held_L = Matrix6d::Zero();
  if (options.first_free_node > 0) {
    const Matrix6d A = core::Adjoint(initial[options.first_free_node]);
    held_L =
        SqrtInformation<6>(Matrix6d(A * options.held_covariance * A.transpose()), increment_floor);
  }
  std::vector<bool> use(positions.size(), true);
  std::vector<bool> use_pose(poses.size(), true);
  std::vector<bool> use_loop(loops.size(), true);
  double z_offset = 0.0;  // warm-started like the nodes
  double xy_offset[2] = {0.0, 0.0};
  std::vector<Node> nodes;
  for (int round = 0; round < options.max_gate_rounds; ++round) {
    // The first round starts from the chained trajectory, the others from the last solution
    // (the optimum without the rejected fixes is near it).
    nodes.clear();
    for (const Eigen::Isometry3d& T : result.T_world_body) nodes.push_back(ToNode(T));
    ceres::Problem problem;
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      Node& node = nodes[k];
      problem.AddParameterBlock(node.q, 4, new ceres::EigenQuaternionManifold);
      problem.AddParameterBlock(node.t, 3);
      if (k < options.first_free_node) {
        problem.SetParameterBlockConstant(node.q);
        problem.SetParameterBlockConstant(node.t);
      }
    }
    // The start: frame 0's weak prior, or in a window the held part summed up as a prior on
    // the window's first node (where the last solution put it, with its covariance), in place
    // of the increment that ties it to the held nodes.
    const std::size_t start_node = options.first_free_node;
    const Eigen::Isometry3d& start_pose = initial[start_node];
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 6, 4, 3>(new PriorCost{
                                 {Eigen::Quaterniond(start_pose.linear()).normalized(),
                                  start_pose.translation(), start_node == 0 ? prior_L : held_L}}),
                             nullptr, nodes[start_node].q, nodes[start_node].t);
    for (std::size_t k = 0; k < relative.size(); ++k) {
      const RelativeFactor& f = relative[k];
      if (start_node > 0 && f.to <= start_node && f.from <= start_node) continue;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<RelativeCost, 6, 4, 3, 4, 3>(
              new RelativeCost{{Eigen::Quaterniond(f.T_from_to.linear()).normalized(),
                                f.T_from_to.translation(), relative_L[k]}}),
          nullptr, nodes[f.from].q, nodes[f.from].t, nodes[f.to].q, nodes[f.to].t);
    }
    std::size_t used = 0;
    for (std::size_t k = 0; k < positions.size(); ++k) {
      if (!use[k]) continue;
      const PositionFactor& f = positions[k];
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PositionCost, 3, 4, 3>(
                                   new PositionCost{f.position_world, f.lever_arm_body, fix_L[k]}),
                               new ceres::HuberLoss(options.fix_huber_sigmas), nodes[f.node].q,
                               nodes[f.node].t);
      ++used;
    }
    for (std::size_t k = 0; k < poses.size(); ++k) {
      if (!use_pose[k]) continue;
      const PoseFactor& f = poses[k];
      auto* cost =
          new AbsolutePoseCost{Eigen::Quaterniond(f.T_world_body.linear()).normalized(),
                               f.T_world_body.translation(), pose_L[k], f.z_offset, f.xy_offset};
      ceres::LossFunction* loss =
          f.gated ? new ceres::HuberLoss(options.fix_huber_sigmas) : nullptr;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<AbsolutePoseCost, 6, 4, 3, 1, 2>(cost), loss,
          nodes[f.node].q, nodes[f.node].t, &z_offset, xy_offset);
      if (f.gated) ++used;
    }
    {
      // An offset no factor of this round reads is held where it is; the horizontal one has
      // its prior.
      bool z_read = false, xy_read = false;
      for (std::size_t k = 0; k < poses.size(); ++k) {
        z_read = z_read || (use_pose[k] && poses[k].z_offset);
        xy_read = xy_read || (use_pose[k] && poses[k].xy_offset);
      }
      if (problem.HasParameterBlock(&z_offset) && !z_read)
        problem.SetParameterBlockConstant(&z_offset);
      if (xy_read) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<OffsetPriorCost, 2, 2>(
                                     new OffsetPriorCost{1.0 / options.xy_offset_sigma_m}),
                                 nullptr, xy_offset);
      } else if (problem.HasParameterBlock(xy_offset)) {
        problem.SetParameterBlockConstant(xy_offset);
      }
    }
    for (std::size_t k = 0; k < loops.size(); ++k) {
      if (!use_loop[k]) continue;
      const LoopFactor& f = loops[k];
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<RelativeCost, 6, 4, 3, 4, 3>(
              new RelativeCost{{Eigen::Quaterniond(f.T_from_to.linear()).normalized(),
                                f.T_from_to.translation(), loop_L[k]}}),
          new ceres::HuberLoss(options.fix_huber_sigmas), nodes[f.from].q, nodes[f.from].t,
          nodes[f.to].q, nodes[f.to].t);
      ++used;
    }
    if (used < static_cast<std::size_t>(options.min_fixes)) {
      result.message = std::to_string(used) + " absolute factor" + (used == 1 ? "" : "s") +
                       " left after the gate, fewer than " + std::to_string(options.min_fixes) +
                       ": the chained trajectory is kept";
      result.T_world_body = initial;
      result.solved = false;
      break;
    }
    ceres::Solver::Options solver;
    solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver.max_num_iterations = options.max_iterations;
    // Tighter than Ceres's defaults (1e-6): a long chain's cost falls slowly near the optimum
    // while its far end still moves by centimetres.
    solver.function_tolerance = 1e-12;
    solver.gradient_tolerance = 1e-14;
    solver.parameter_tolerance = 1e-12;
    solver.num_threads = 1;
    solver.logging_type = ceres::SILENT;
    solver.minimizer_progress_to_stdout = false;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    ++result.solves;
    result.iterations += static_cast<int>(summary.iterations.size());
    result.final_cost = summary.final_cost;
    if (!summary.IsSolutionUsable()) {
      result.message = "the solver failed: " + summary.message;
      result.T_world_body = initial;
      result.solved = false;
      break;
    }
    for (std::size_t k = 0; k < n; ++k) result.T_world_body[k] = FromNode(nodes[k]);
    result.solved = true;
    result.message = summary.message;
    // The gate, worst first: the fixes over the bound whose residual is at least half the
    // worst one's (in σ) leave, and the rest is solved again. A gross outlier bends its
    // neighbours' residuals too; once it is gone they come back within the bound, so they
    // wait for the next round instead of leaving with it. The last round's solution is
    // final, so its fixes are the ones used.
    bool changed = false;
    const bool last_round = round + 1 == options.max_gate_rounds;
    // Fixes and pose factors in one ranking, each χ² over its own gate.
    double worst = 0.0;
    for (std::size_t k = 0; k < positions.size(); ++k) {
      result.fix_chi2[k] = FixChi2(positions[k], fix_L[k], result.T_world_body[positions[k].node]);
      if (use[k]) worst = std::max(worst, result.fix_chi2[k] / options.fix_gate_chi2);
    }
    for (std::size_t k = 0; k < poses.size(); ++k) {
      result.pose_chi2[k] =
          PoseChi2(poses[k], pose_L[k], result.T_world_body[poses[k].node], z_offset, xy_offset);
      if (use_pose[k] && poses[k].gated)
        worst = std::max(worst, result.pose_chi2[k] / pose_gate[k]);
    }
    for (std::size_t k = 0; k < loops.size(); ++k) {
      result.loop_chi2[k] = LoopChi2(loops[k], loop_L[k], result.T_world_body[loops[k].from],
                                     result.T_world_body[loops[k].to]);
      if (use_loop[k]) worst = std::max(worst, result.loop_chi2[k] / loop_gate[k]);
    }
    for (std::size_t k = 0; k < loops.size(); ++k) {
      const double ratio = result.loop_chi2[k] / loop_gate[k];
      if (!last_round && use_loop[k] && ratio > 1.0 && ratio >= 0.25 * worst) {
        use_loop[k] = false;
        changed = true;
      }
    }
    for (std::size_t k = 0; k < positions.size(); ++k) {
      const double ratio = result.fix_chi2[k] / options.fix_gate_chi2;
      if (!last_round && use[k] && ratio > 1.0 && ratio >= 0.25 * worst) {
        use[k] = false;
        changed = true;
      }
    }
    for (std::size_t k = 0; k < poses.size(); ++k) {
      const double ratio = result.pose_chi2[k] / pose_gate[k];
      if (!last_round && poses[k].gated && use_pose[k] && ratio > 1.0 && ratio >= 0.25 * worst) {
        use_pose[k] = false;
        changed = true;
      }
    }
    if (!changed) {
      // Absolute: with a fix or a reference match in the solution, against the world; with
      // loops alone, given node 0 (the start as the chain takes it, exact).
      bool absolute = false;
      for (std::size_t k = 0; k < positions.size(); ++k) absolute = absolute || use[k];
      for (std::size_t k = 0; k < poses.size(); ++k)
        absolute = absolute || (use_pose[k] && poses[k].gated);
      if (options.covariance) {
        MarginalCovariances(&problem, &nodes, !absolute, options.first_free_node, &result);
      }
      break;
    }
  }
  result.first_solved_frame = options.first_free_node;
  if (!options.covariance) result.covariance_message = "not asked for";
  if (!result.solved) result.covariance_message = "the graph was not solved";
  result.fixes_used = 0;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    result.fix_used[k] = result.solved && use[k];
    if (result.fix_used[k]) ++result.fixes_used;
  }
  result.fixes_rejected = positions.size() - result.fixes_used;
  result.z_offset_m = result.solved ? z_offset : 0.0;
  result.xy_offset_m =
      result.solved ? Eigen::Vector2d(xy_offset[0], xy_offset[1]) : Eigen::Vector2d::Zero();
  result.loops_used = 0;
  for (std::size_t k = 0; k < loops.size(); ++k) {
    result.loop_used[k] = result.solved && use_loop[k];
    if (result.loop_used[k]) ++result.loops_used;
  }
  result.loops_rejected = loops.size() - result.loops_used;
  result.poses_used = 0;
  result.poses_rejected = 0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    result.pose_used[k] = result.solved && use_pose[k];
    if (!poses[k].gated) continue;
    if (result.pose_used[k]) {
      ++result.poses_used;
    } else {
      ++result.poses_rejected;
    }
  }
  result.solve_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace rovermap::graph
