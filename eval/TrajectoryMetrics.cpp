#include "core/Units.hpp"
#include "eval/TrajectoryMetrics.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace rovermap::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using core::kRadToDeg;

std::vector<Eigen::Vector3d> Positions(const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<Eigen::Vector3d> positions;
  positions.reserve(poses.size());
  for (const auto& T : poses) positions.push_back(T.translation());
  return positions;
}

std::string Seconds(double t) {
  std::ostringstream s;
  s << t;
  return s.str();
}

nlohmann::json Number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json MatrixJson(const Eigen::Matrix4d& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

// "ate" -> ate_rmse_m, ate_mean_m, ... (suffix: the unit).
void AddStats(nlohmann::json& out, const std::string& name, const std::string& rmse_key,
              const std::string& unit, const ErrorStats& stats) {
  out[rmse_key] = Number(stats.rmse);
  out[name + "_mean_" + unit] = Number(stats.mean);
  out[name + "_median_" + unit] = Number(stats.median);
  out[name + "_max_" + unit] = Number(stats.max);
}

}  // namespace

ErrorStats ComputeStats(std::vector<double> values) {
  ErrorStats stats;
  stats.count = values.size();
  if (values.empty()) {
    stats.rmse = stats.mean = stats.median = stats.max = kNaN;
    return stats;
  }
  double sum = 0.0, sum_squares = 0.0;
  for (double v : values) {
    sum += v;
    sum_squares += v * v;
  }
  const double n = static_cast<double>(values.size());
  stats.rmse = std::sqrt(sum_squares / n);
  stats.mean = sum / n;
  std::sort(values.begin(), values.end());
  const std::size_t half = values.size() / 2;
  stats.median = values.size() % 2 == 1 ? values[half] : 0.5 * (values[half - 1] + values[half]);
  stats.max = values.back();
  return stats;
}

Eigen::Isometry3d AlignUmeyama(const std::vector<Eigen::Vector3d>& source,
                               const std::vector<Eigen::Vector3d>& target) {
  if (source.size() != target.size() || source.size() < 2)
    throw std::invalid_argument("AlignUmeyama: need two or more point pairs of equal count");
  const double n = static_cast<double>(source.size());
  Eigen::Vector3d mean_source = Eigen::Vector3d::Zero(), mean_target = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < source.size(); ++i) {
    mean_source += source[i];
    mean_target += target[i];
  }
  mean_source /= n;
  mean_target /= n;
  // Umeyama 1991, eq. 38: the cross-covariance Σ_xy of target (y) and source (x).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < source.size(); ++i)
    covariance += (target[i] - mean_target) * (source[i] - mean_source).transpose();
  covariance /= n;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  // Eq. 43: S = diag(1, 1, −1) when det(U)·det(V) < 0, so that R is a rotation, not a reflection.
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * S * svd.matrixV().transpose();  // eq. 40
  T.translation() = mean_target - T.linear() * mean_source;    // eq. 41 (scale 1)
  return T;
}

double RotationAngle(const Eigen::Isometry3d& T) {
  // cos θ = (tr R − 1) / 2 as the KITTI devkit, sin θ = ‖vee(R − Rᵀ)‖ / 2: atan2 keeps small
  // angles exact where acos near 1 loses half the digits.
  const Eigen::Matrix3d& R = T.linear();
  const double c = 0.5 * (R.trace() - 1.0);
  const double s =
      0.5 * Eigen::Vector3d(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1)).norm();
  return std::atan2(s, c);
}

std::vector<double> PathDistances(const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<double> distances(poses.size(), 0.0);
  for (std::size_t k = 1; k < poses.size(); ++k)
    distances[k] = distances[k - 1] + (poses[k].translation() - poses[k - 1].translation()).norm();
  return distances;
}

Association Associate(const Trajectory& estimate, const Trajectory& groundtruth,
                      const EvalOptions& options) {
  Association a;
  a.by_timestamp = estimate.has_timestamps() && groundtruth.has_timestamps();
  if (!a.by_timestamp) {
    if (estimate.size() != groundtruth.size()) {
      a.message =
          "association by index (a file without timestamps) needs equal lengths: " + estimate.file +
          " has " + std::to_string(estimate.size()) + " poses, " + groundtruth.file + " has " +
          std::to_string(groundtruth.size());
      return a;
    }
    for (std::size_t i = 0; i < estimate.size(); ++i) {
      a.estimate_index.push_back(i);
      a.groundtruth_index.push_back(i);
    }
    return a;
  }
  // Every candidate within the tolerance, then closest first, each pose used once.
  const double tolerance = options.association_tolerance_s;
  const std::vector<double>& gt = groundtruth.timestamps_s;
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate.timestamps_s[i];
    for (auto it = std::lower_bound(gt.begin(), gt.end(), t - tolerance);
         it != gt.end() && *it <= t + tolerance; ++it)
      candidates.emplace_back(std::abs(*it - t), i, static_cast<std::size_t>(it - gt.begin()));
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> estimate_used(estimate.size(), false), gt_used(gt.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (const auto& [dt, i, j] : candidates) {
    if (estimate_used[i] || gt_used[j]) continue;
    estimate_used[i] = gt_used[j] = true;
    pairs.emplace_back(i, j);
    a.max_time_difference_s = std::max(a.max_time_difference_s, dt);
  }
  std::sort(pairs.begin(), pairs.end());
  for (const auto& [i, j] : pairs) {
    a.estimate_index.push_back(i);
    a.groundtruth_index.push_back(j);
  }
  if (pairs.empty()) {
    a.message = "no timestamp of " + estimate.file + " (" + Seconds(estimate.timestamps_s.front()) +
                " to " + Seconds(estimate.timestamps_s.back()) + " s) within " +
                Seconds(tolerance) + " s of one of " + groundtruth.file + " (" +
                Seconds(gt.front()) + " to " + Seconds(gt.back()) +
                " s); see eval.association_tolerance_s";
  }
  return a;
}

std::string ToString(MetricStatus status) {
  switch (status) {
    case MetricStatus::kOk:
      return "ok";
    case MetricStatus::kNoPairs:
      return "no_pairs";
    case MetricStatus::kTooFewPairs:
      return "too_few_pairs";
  }
  return "ok";
}

TrajectoryMetrics EvaluateAssociated(const std::vector<Eigen::Isometry3d>& estimate,
                                     const std::vector<Eigen::Isometry3d>& groundtruth,
                                     const EvalOptions& options) {
  TrajectoryMetrics m;
  m.rpe_delta_m = options.rpe_delta_m;
  m.pairs = std::min(estimate.size(), groundtruth.size());
  if (estimate.size() != groundtruth.size() || m.pairs < 2) {
    m.status = MetricStatus::kTooFewPairs;
    m.message = "need two or more associated poses, have " + std::to_string(m.pairs);
    m.ate_m = m.ate_origin_m = m.rpe_trans_m = m.rpe_rot_deg = ComputeStats({});
    m.kitti_trans_percent = m.kitti_rot_deg_per_m = kNaN;
    return m;
  }
  const std::size_t n = m.pairs;
  m.groundtruth_positions = Positions(groundtruth);
  m.distance_m = PathDistances(groundtruth);
  m.length_m = m.distance_m.back();

  // ATE: positions after the best rigid alignment (Umeyama 1991; Sturm et al. 2012, eq. 2).
  const std::vector<Eigen::Vector3d> estimate_positions = Positions(estimate);
  m.T_groundtruth_estimate = AlignUmeyama(estimate_positions, m.groundtruth_positions);
  // ATE at the origin: the first estimate pose moved onto the first ground-truth pose.
  const Eigen::Isometry3d T_origin = groundtruth.front() * estimate.front().inverse();
  for (std::size_t k = 0; k < n; ++k) {
    m.aligned_positions.push_back(m.T_groundtruth_estimate * estimate_positions[k]);
    m.origin_aligned_positions.push_back(T_origin * estimate_positions[k]);
    m.ate_error_m.push_back((m.aligned_positions[k] - m.groundtruth_positions[k]).norm());
    m.ate_origin_error_m.push_back(
        (m.origin_aligned_positions[k] - m.groundtruth_positions[k]).norm());
  }
  m.ate_m = ComputeStats(m.ate_error_m);
  m.ate_origin_m = ComputeStats(m.ate_origin_error_m);

  // RPE (Sturm et al. 2012, eq. 3): E = (Q_i⁻¹ Q_j)⁻¹ (P_i⁻¹ P_j), j the first pose at least
  // rpe_delta_m of ground-truth travel after i.
  std::vector<double> rpe_trans, rpe_rot;
  for (std::size_t i = 0; i < n; ++i) {
    const auto j = std::lower_bound(m.distance_m.begin() + static_cast<std::ptrdiff_t>(i) + 1,
                                    m.distance_m.end(), m.distance_m[i] + options.rpe_delta_m);
    if (j == m.distance_m.end()) break;
    const std::size_t jj = static_cast<std::size_t>(j - m.distance_m.begin());
    const Eigen::Isometry3d E = (groundtruth[i].inverse() * groundtruth[jj]).inverse() *
                                (estimate[i].inverse() * estimate[jj]);
    rpe_trans.push_back(E.translation().norm());
    rpe_rot.push_back(RotationAngle(E) * kRadToDeg);
  }
  m.rpe_trans_m = ComputeStats(rpe_trans);
  m.rpe_rot_deg = ComputeStats(rpe_rot);

  // KITTI devkit (Geiger et al. 2012, evaluate_odometry.cpp, calcSequenceErrors): for each start
  // pose and length L, the first pose more than L further along the ground truth; errors of
  // (P_i⁻¹ P_j)⁻¹ (Q_i⁻¹ Q_j) divided by L. Every pose starts segments (the devkit: every 10th).
  double trans_sum = 0.0, rot_sum = 0.0;
  std::size_t segment_count = 0;
  for (double length : options.segment_lengths_m) {
    SegmentError segment;
    segment.length_m = length;
    double segment_trans = 0.0, segment_rot = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const auto j = std::upper_bound(m.distance_m.begin() + static_cast<std::ptrdiff_t>(i),
                                      m.distance_m.end(), m.distance_m[i] + length);
      if (j == m.distance_m.end()) break;
      const std::size_t jj = static_cast<std::size_t>(j - m.distance_m.begin());
      const Eigen::Isometry3d E = (estimate[i].inverse() * estimate[jj]).inverse() *
                                  (groundtruth[i].inverse() * groundtruth[jj]);
      segment_trans += E.translation().norm() / length;
      segment_rot += RotationAngle(E) / length;
      ++segment.count;
    }
    const double count = static_cast<double>(segment.count);
    segment.trans_percent = segment.count > 0 ? 100.0 * segment_trans / count : kNaN;
    segment.rot_deg_per_m = segment.count > 0 ? kRadToDeg * segment_rot / count : kNaN;
    m.segments.push_back(segment);
    trans_sum += segment_trans;
    rot_sum += segment_rot;
    segment_count += segment.count;
  }
  const double total = static_cast<double>(segment_count);
  m.kitti_trans_percent = segment_count > 0 ? 100.0 * trans_sum / total : kNaN;
  m.kitti_rot_deg_per_m = segment_count > 0 ? kRadToDeg * rot_sum / total : kNaN;
  return m;
}

TrajectoryMetrics EvaluateTrajectory(const Trajectory& estimate, const Trajectory& groundtruth,
                                     const EvalOptions& options) {
  const Association a = Associate(estimate, groundtruth, options);
  std::vector<Eigen::Isometry3d> estimate_poses, groundtruth_poses;
  for (std::size_t k = 0; k < a.estimate_index.size(); ++k) {
    estimate_poses.push_back(estimate.poses[a.estimate_index[k]]);
    groundtruth_poses.push_back(groundtruth.poses[a.groundtruth_index[k]]);
  }
  TrajectoryMetrics m = EvaluateAssociated(estimate_poses, groundtruth_poses, options);
  if (a.estimate_index.empty()) {
    m.status = MetricStatus::kNoPairs;
    m.message = a.message;
  }
  return m;
}

nlohmann::json ToJson(const TrajectoryMetrics& m) {
  nlohmann::json out;
  out["status"] = ToString(m.status);
  if (!m.message.empty()) out["message"] = m.message;
  out["pairs"] = m.pairs;
  out["length_m"] = m.length_m;
  AddStats(out, "ate", "ate_rmse_m", "m", m.ate_m);
  AddStats(out, "ate_origin", "ate_rmse_origin_m", "m", m.ate_origin_m);
  out["rpe_delta_m"] = m.rpe_delta_m;
  out["rpe_pairs"] = m.rpe_trans_m.count;
  AddStats(out, "rpe_trans", "rpe_trans_rmse_m", "m", m.rpe_trans_m);
  AddStats(out, "rpe_rot", "rpe_rot_rmse_deg", "deg", m.rpe_rot_deg);
  out["kitti_trans_percent"] = Number(m.kitti_trans_percent);
  out["kitti_rot_deg_per_m"] = Number(m.kitti_rot_deg_per_m);
  nlohmann::json segments = nlohmann::json::array();
  for (const SegmentError& s : m.segments)
    segments.push_back({{"length_m", s.length_m},
                        {"count", s.count},
                        {"trans_percent", Number(s.trans_percent)},
                        {"rot_deg_per_m", Number(s.rot_deg_per_m)}});
  out["kitti_segments"] = segments;
  const Eigen::Isometry3d& T = m.T_groundtruth_estimate;
  out["alignment"] = {{"T_groundtruth_estimate", MatrixJson(T.matrix())},
                      {"rotation_deg", RotationAngle(T) * kRadToDeg},
                      {"translation_m", T.translation().norm()}};
  return out;
}

}  // namespace rovermap::eval
