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
///
/// PCA normals are estimated on demand (RequireOrientations): registration samples the
/// source and matches only part of the target, so most normals would never be read.
class IndexedCloud {
 public:
  /// Tangents (curves) are computed here; normals come from the cloud when it has them,
  /// otherwise on demand, when `options` use orientations (orientation test, point-to-plane
  /// residual). The tree is built on first use.
  IndexedCloud(PointCloud cloud, const RegistrationOptions& options);
  /// The same with the points' spacing known [m] (> 0): a cloud merged from a denser one keeps
  /// the denser one's, so that Zhang's D (reference_distance_m 0) follows the sensor's sampling,
  /// not the merge (mapper::Mapper::Prepare, MapperOptions::registration_cell_px).
  IndexedCloud(PointCloud cloud, const RegistrationOptions& options, double spacing_m);
  IndexedCloud(const IndexedCloud&) = delete;
  IndexedCloud& operator=(const IndexedCloud&) = delete;

  const PointCloud& cloud() const { return cloud_; }
  /// The k-d tree, built on first use (a source that needs no normals never needs one).
  /// Safe to call from several threads.
  const KdTree& tree() const;
  /// Whether this cloud carries orientations (given, tangents or on-demand normals).
  bool HasOrientations() const { return !orientations_.empty(); }
  /// Whether its orientations are PCA normals estimated on demand (they cost a k-NN each).
  bool EstimatesOrientations() const { return !known_.empty(); }
  /// Makes the orientations of `indices` available (estimates the missing normals in
  /// parallel). Safe to call from several threads; each index is estimated once.
  void RequireOrientations(const std::vector<std::size_t>& indices) const;
  /// Unit orientation of point i (zero vector = unknown). Valid once i has been required.
  const Eigen::Vector3d& orientation(std::size_t i) const { return orientations_[i]; }
  /// Expected angular error of orientation(i) [rad] from the scatter of the neighbours it was
  /// fitted to; 0 for given normals (trusted). Valid once i has been required.
  double orientation_spread(std::size_t i) const { return spreads_.empty() ? 0.0 : spreads_[i]; }
  /// Median nearest-neighbour spacing [m], as given, or computed on first use (only needed for
  /// D = 0).
  double spacing() const;

 private:
  PointCloud cloud_;
  mutable std::unique_ptr<KdTree> tree_;
  mutable std::once_flag tree_once_;
  int normal_neighbors_ = 0;
  // Entries are written once, under the mutex, before `known_` says so; a thread reads only
  // entries it has required, so reads never race with the writes.
  mutable std::vector<Eigen::Vector3d> orientations_;
  mutable std::vector<double> spreads_;       // empty: all 0 (given normals)
  mutable std::vector<unsigned char> known_;  // empty: all known
  mutable std::mutex orientation_mutex_;
  mutable std::once_flag spacing_once_;
  mutable double spacing_ = 0.0;
  double given_spacing_ = 0.0;
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
  std::size_t queries = 0;  ///< closest-point queries (sampled points used, both ways)
  /// k-d tree searches those queries ran: a query point that moved less than half the gap to
  /// its second closest point since its last search keeps its closest point without one
  std::size_t searches = 0;
  std::size_t pairs_found = 0;  ///< pairs within the previous Dmax (and orientation test)
  std::size_t pairs_kept = 0;   ///< pairs after the new Dmax or the Mahalanobis gate
  std::size_t pairs_rejected_by_orientation = 0;  ///< within Dmax, failed the orientation test
  double mean_m = 0.0;                            ///< μ of the found pairs' distances
  double stddev_m = 0.0;                          ///< σ
  double dmax_m = 0.0;                            ///< Dmax after the update
  DmaxBranch branch = DmaxBranch::kNoPairs;
  double rms_m = 0.0;  ///< RMS distance of the kept pairs before the motion update
  double step_translation_m = 0.0;
  double step_rotation_deg = 0.0;
  bool accelerated = false;             ///< matched at an (accepted) Anderson extrapolation
  bool extrapolation_rejected = false;  ///< the extrapolation raised the energy: plain step used
};

struct RegistrationResult {
  RegistrationStatus status = RegistrationStatus::kTooFewPoints;
  bool converged = false;
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  int iterations = 0;
  std::size_t sample_points = 0;      ///< source points matched at the end (see Options)
  std::size_t inliers = 0;            ///< sampled points paired within the final Dmax / gate
  double inlier_ratio = 0.0;          ///< inliers / sample_points: low means little overlap found
  double rms_m = 0.0;                 ///< RMS distance of those pairs [m]
  double dmax_m = 0.0;                ///< final Dmax [m]
  double reference_distance_m = 0.0;  ///< D as used (given or derived) [m]
  /// Information and covariance of the estimate for a left perturbation
  /// T = Exp([δr, δt]) T̂ in the target frame, order [rx ry rz (rad), tx ty tz (m)].
  /// From the final pairs assuming independent residuals (optimistic for dense clouds).
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  /// The part of `information` the errors of the target's normals alone would give on
  /// featureless ground (point-to-plane; same parameterisation): a direction whose information
  /// is not well above it is constrained by noise and artefacts, not by the ground's shape.
  /// Zero where the normals carry no expected error (given normals, point-to-point).
  Eigen::Matrix<double, 6, 6> noise_information = Eigen::Matrix<double, 6, 6>::Zero();
  /// Smallest / largest eigenvalue of the information scaled to unit metres and radians:
  /// near 0 means a direction the data do not constrain (a plane, a corridor).
  double conditioning = 0.0;
  /// Largest distance of a matched source point from the source origin, in the target frame
  /// [m]: the scale of rotations in `conditioning` (a rotation δr moves points by up to
  /// δr · extent_m).
  double extent_m = 0.0;
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
