#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "registration/DmaxSchedule.hpp"
#include "registration/KdTree.hpp"
#include "registration/Options.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::registration {

/// A cloud with its k-d tree and the orientations the options need (normals for surfaces,
/// tangents for curves). Built once per cloud: in a sequence, frame k's source index is
/// frame k+1's target index.
class IndexedCloud {
 public:
  /// Builds the tree; estimates orientations when `options` use them (orientation test,
  /// point-to-plane residual) and the cloud has none.
  IndexedCloud(PointCloud cloud, const RegistrationOptions& options);
  IndexedCloud(const IndexedCloud&) = delete;
  IndexedCloud& operator=(const IndexedCloud&) = delete;

  const PointCloud& cloud() const { return cloud_; }
  const KdTree& tree() const { return *tree_; }
  /// Unit orientations (zero vector = unknown); empty when not needed.
  const std::vector<Eigen::Vector3d>& orientations() const { return orientations_; }
  /// Median nearest-neighbour spacing [m], computed on first use (only needed for D = 0).
  double spacing() const;

 private:
  PointCloud cloud_;
  std::unique_ptr<KdTree> tree_;
  std::vector<Eigen::Vector3d> orientations_;
  mutable std::once_flag spacing_once_;
  mutable double spacing_ = 0.0;
};

enum class RegistrationStatus {
  kConverged,      ///< stopping test met
  kMaxIterations,  ///< max_iterations reached first; the estimate is still usable
  kTooFewPoints,   ///< a cloud has fewer than 3 points; T is the initial estimate
  kTooFewPairs,    ///< fewer than min_pairs pairs survived; T is the last good estimate
  kSolverFailed,   ///< the closed-form / linear solve failed (degenerate pairs)
  kInvalidInput,   ///< options and data disagree (e.g. use_uncertainty without covariances)
};

const char* ToString(RegistrationStatus status);

/// One iteration of the loop (Zhang 1994, §4.3 step 3).
struct IterationTrace {
  int iteration = 0;
  std::size_t queries = 0;       ///< closest-point queries (source points used, both ways)
  std::size_t pairs_found = 0;   ///< pairs within the previous Dmax (and orientation test)
  std::size_t pairs_kept = 0;    ///< pairs after the new Dmax or the Mahalanobis gate
  double mean_m = 0.0;           ///< μ of the found pairs' distances
  double stddev_m = 0.0;         ///< σ
  double dmax_m = 0.0;           ///< Dmax after the update
  DmaxBranch branch = DmaxBranch::kNoPairs;
  double rms_m = 0.0;            ///< RMS distance of the kept pairs before the motion update
  double step_translation_m = 0.0;
  double step_rotation_deg = 0.0;
};

struct RegistrationResult {
  RegistrationStatus status = RegistrationStatus::kTooFewPoints;
  bool converged = false;
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  int iterations = 0;
  std::size_t inliers = 0;          ///< pairs within the final Dmax / gate at the final T
  double inlier_ratio = 0.0;        ///< inliers / source points: low means little overlap found
  double rms_m = 0.0;               ///< RMS distance of those pairs [m]
  double dmax_m = 0.0;              ///< final Dmax [m]
  double reference_distance_m = 0.0;  ///< D as used (given or derived) [m]
  /// Information and covariance of the estimate for a left perturbation
  /// T = Exp([δr, δt]) T̂ in the target frame, order [rx ry rz (rad), tx ty tz (m)].
  /// From the final pairs assuming independent residuals (optimistic for dense clouds).
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  /// Smallest / largest eigenvalue of the information scaled to unit metres and radians:
  /// near 0 means a direction the data do not constrain (a plane, a corridor).
  double conditioning = 0.0;
  std::vector<IterationTrace> trace;
  std::string message;  ///< why it failed, empty on success
};

/// Zhang's iterative point matching of `source` onto `target` from `T_init`:
/// returns T_target_source with target ≈ R·source + t. Never throws on data; the
/// status says what happened.
RegistrationResult Register(const IndexedCloud& source, const IndexedCloud& target,
                            const Eigen::Isometry3d& T_init, const RegistrationOptions& options);

/// Convenience overload that indexes both clouds.
RegistrationResult Register(const PointCloud& source, const PointCloud& target,
                            const Eigen::Isometry3d& T_init, const RegistrationOptions& options);

}  // namespace rovermap::registration
