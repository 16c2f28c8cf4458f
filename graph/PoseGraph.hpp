#pragma once
// A pose graph over the frames (docs/graph.md): the chained frame-to-frame increments as
// relative factors weighted by their covariances, absolute position fixes (GNSS) as robust
// factors gated against the solution, solved with Ceres. Ceres stays inside PoseGraph.cpp.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

namespace rovermap::graph {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Options of SolvePoseGraph; plain values, in-class defaults.
struct PoseGraphOptions {
  /// [σ] a position fix's whitened residual beyond this is weighed linearly (Huber), so that a
  /// fix far from the others pulls with a bounded force while the gate decides on it. About
  /// √fix_gate_chi2: a fix within the gate weighs fully; > 0.
  double fix_huber_sigmas = 4.0;
  /// [χ², 3 dof] a fix whose whitened squared residual at the solution exceeds this is rejected
  /// and the graph solved again without it (16.27: 99.9 % of good fixes pass); > 0.
  double fix_gate_chi2 = 16.27;
  /// [count] fewer fixes left after the gate: the graph keeps the initial trajectory. Fixes
  /// that all disagree are rejected until one or two are left, which agree with the chain
  /// whatever they say; >= 1.
  int min_fixes = 3;
  /// [count] solve–gate rounds at most (each round rejects the worst fixes); >= 1.
  int max_gate_rounds = 20;
  /// [count] Levenberg–Marquardt iterations per solve; >= 1.
  int max_iterations = 100;
  /// [deg] σ of the weak prior that holds frame 0's attitude where it was (removes the gauge
  /// freedom a few collinear fixes leave); > 0.
  double first_pose_sigma_deg = 5.0;
  /// [m] σ of that prior on frame 0's position; > 0.
  double first_pose_sigma_m = 100.0;
  /// [rad], [m] floor of a relative factor's σ: a zero covariance (frame 0, a step given as
  /// exact) would be a hard constraint the solver cannot weigh; > 0.
  double min_increment_sigma_rad = 1e-6;
  double min_increment_sigma_m = 1e-6;
  /// [m] σ per axis of the shared horizontal offset of the PoseFactor::xy_offset factors (a
  /// reference DEM's georeferencing); > 0.
  double xy_offset_sigma_m = 1.0;
  /// Compute every node's marginal covariance at the solution (PoseGraphResult::covariance).
  bool covariance = true;
  /// Nodes before this one are held where `initial` puts them (a daemon's earlier solution):
  /// the solve's cost stays with the window from it on. The window's first node gets a prior
  /// at its `initial` pose with `held_covariance` in place of its increment from the held
  /// nodes (the held part summed up, as a marginalised past) and of frame 0's prior; factors
  /// from held nodes into the window (a revisit of old ground) tie it to them as they are.
  /// 0: every node is free.
  std::size_t first_free_node = 0;
  /// That prior's covariance (the chain's convention: the last solution's marginal of the
  /// window's first node).
  Matrix6d held_covariance = Matrix6d::Zero();
};

/// @throw std::invalid_argument naming the field if a value is out of range.
void Validate(const PoseGraphOptions& options);

/// T_from_to measured, with the covariance of a left perturbation in frame `from`
/// ([rx ry rz (rad) tx ty tz (m)], RegistrationResult's and PoseChain's convention:
/// T_true = (Exp(δr), δt) ∘ T_from_to).
struct RelativeFactor {
  std::size_t from = 0;
  std::size_t to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Identity();
};

/// An absolute position of the point `lever_arm_body` of node `node` (a GNSS antenna), in the
/// world frame [m], with its covariance [m²].
struct PositionFactor {
  std::size_t node = 0;
  Eigen::Vector3d position_world = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  Eigen::Vector3d lever_arm_body = Eigen::Vector3d::Zero();
};

/// An absolute pose of node `node` (a match against a reference DEM): the residual
/// [log(R·R_measᵀ); t − t_meas] (world axes; rad, m) weighed by `information`, positive
/// semi-definite: zero in the directions the measurement does not hold (roll, pitch, often z).
/// Robust and gated as the position fixes are.
struct PoseFactor {
  std::size_t node = 0;
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  Matrix6d information = Matrix6d::Zero();
  /// false: a prior (least squares, never gated, not counted among the absolute factors), such
  /// as the chain's own roll and pitch.
  bool gated = true;
  /// The measured z is on another vertical datum, `offset` above the nodes': the residual is
  /// t_z − (t_meas_z − offset), one offset shared by every such factor and solved for
  /// (PoseGraphResult::z_offset_m).
  bool z_offset = false;
  /// The measured x, y are the reference's, misplaced by one shared horizontal offset (its
  /// georeferencing error), solved for with the prior PoseGraphOptions::xy_offset_sigma_m
  /// (PoseGraphResult::xy_offset_m): what places the reference in the world enters every
  /// match's absolute uncertainty, not each match's own σ.
  bool xy_offset = false;
};

/// A revisit (loop closure): T_from_to measured by matching the ground of `to` onto the ground
/// `from` mapped earlier, weighed by `information` (positive semi-definite, a left perturbation
/// in frame `from` as RelativeFactor's covariance; zero in the directions the match does not
/// hold). Robust and gated as the absolute factors are.
struct LoopFactor {
  std::size_t from = 0;
  std::size_t to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  Matrix6d information = Matrix6d::Zero();
};

/// What SolvePoseGraph did.
struct PoseGraphResult {
  /// The graph was solved: there was at least one position factor and Ceres returned a usable
  /// solution. false: `T_world_body` is the initial trajectory, `message` says why.
  bool solved = false;
  std::vector<Eigen::Isometry3d> T_world_body;  ///< one per node
  /// Per position factor: used in the final solve, and its whitened squared residual there.
  std::vector<bool> fix_used;
  std::vector<double> fix_chi2;
  std::size_t fixes_used = 0;
  std::size_t fixes_rejected = 0;
  /// The same per pose factor (a prior, PoseFactor::gated false, is always used).
  std::vector<bool> pose_used;
  std::vector<double> pose_chi2;
  std::size_t poses_used = 0;
  std::size_t poses_rejected = 0;
  /// The same per loop factor.
  std::vector<bool> loop_used;
  std::vector<double> loop_chi2;
  std::size_t loops_used = 0;
  std::size_t loops_rejected = 0;
  /// [m] how far above the nodes' vertical datum the PoseFactor::z_offset factors' is (0
  /// without them).
  double z_offset_m = 0.0;
  /// [m] the PoseFactor::xy_offset factors' horizontal offset (east, north; 0 without them).
  Eigen::Vector2d xy_offset_m = Eigen::Vector2d::Zero();
  int solves = 0;      ///< gate rounds run
  int iterations = 0;  ///< Levenberg–Marquardt iterations, all solves
  double final_cost = 0.0;
  double solve_ms = 0.0;
  std::string message;
  /// Per node, when solved and PoseGraphOptions::covariance: the marginal covariance of its
  /// pose (ChainStep::covariance's convention: a right perturbation in the body frame,
  /// [rx ry rz tx ty tz]), robust losses applied as at the solution. Against the world when a
  /// position or gated pose factor is used; with loop factors alone given node 0 (zero there,
  /// as the chain's: nothing absolute places the start). Empty when not computed;
  /// covariance_message then says why. With PoseGraphOptions::first_free_node, zero for the
  /// held nodes (the caller has theirs).
  std::vector<Matrix6d> covariance;
  bool covariance_given_first = false;
  /// PoseGraphOptions::first_free_node: the nodes before it were held.
  std::size_t first_solved_frame = 0;
  std::string covariance_message;
  double covariance_ms = 0.0;
};

/// Solves for every node's T_world_body from `initial` (one per node, the chained trajectory):
/// relative factors as least squares in their covariance, position and pose factors (the
/// absolute ones) with a Huber loss, then rounds of gating (an absolute factor over the gate at
/// the solution is left out and the rest solved again, until none is left out or the rounds
/// end). The gate is PoseGraphOptions::fix_gate_chi2 for a fix's 3 degrees of freedom and the
/// χ² at the same probability for a pose or loop factor's (the rank of its information). Fewer
/// than PoseGraphOptions::min_fixes absolute and loop factors left, or none given: nothing is
/// solved and the initial trajectory is returned as it is.
/// @throw std::invalid_argument if a factor names a node that does not exist, a covariance or
///        information is not finite or not symmetric positive semi-definite, or the options are
///        invalid.
PoseGraphResult SolvePoseGraph(const std::vector<Eigen::Isometry3d>& initial,
                               const std::vector<RelativeFactor>& relative,
                               const std::vector<PositionFactor>& positions,
                               const std::vector<PoseFactor>& poses,
                               const PoseGraphOptions& options = {},
                               const std::vector<LoopFactor>& loops = {});

/// The same without pose factors.
PoseGraphResult SolvePoseGraph(const std::vector<Eigen::Isometry3d>& initial,
                               const std::vector<RelativeFactor>& relative,
                               const std::vector<PositionFactor>& positions,
                               const PoseGraphOptions& options = {});

}  // namespace rovermap::graph
