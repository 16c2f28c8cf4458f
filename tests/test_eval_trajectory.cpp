// Trajectory metrics (docs/design.md §8) against hand-computed values: pure translation drift, pure
// yaw drift, a known SE(3) offset; association; TUM/KITTI parsing; KITTI 00's ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/Units.hpp"
#include "tests/support/ScratchDir.hpp"
#include "eval/TrajectoryIo.hpp"
#include "eval/TrajectoryMetrics.hpp"
#include "io/IoError.hpp"

namespace rovermap::eval {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = rovermap::core::kPi;

Eigen::Isometry3d Pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Isometry3d Translation(double x, double y, double z) {
  return Pose(Eigen::Matrix3d::Identity(), {x, y, z});
}

Eigen::Matrix3d Rz(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

fs::path TempFile(const std::string& name, const std::string& text) {
  const fs::path dir = rovermap::testing::ScratchDir();
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

std::string ReadError(const fs::path& path, TrajectoryFormat format = TrajectoryFormat::kAuto) {
  try {
    ReadTrajectory(path, format);
  } catch (const io::IoError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an IoError for " << path;
  return "";
}

Trajectory Timed(const std::vector<double>& times, const std::string& file) {
  Trajectory t;
  t.file = file;
  t.timestamps_s = times;
  for (double s : times) t.poses.push_back(Translation(s, 0, 0));
  return t;
}

// ---- statistics and alignment --------------------------------------------------------------

TEST(ErrorStats, HandComputed) {
  const ErrorStats s = ComputeStats({3.0, 4.0, 0.0, 5.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(50.0 / 4.0));  // (9 + 16 + 0 + 25) / 4
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.median, 3.5);  // between 3 and 4
  EXPECT_DOUBLE_EQ(s.max, 5.0);
  EXPECT_DOUBLE_EQ(ComputeStats({2.0, 7.0, 1.0}).median, 2.0);
  EXPECT_TRUE(std::isnan(ComputeStats({}).rmse));
}

TEST(AlignUmeyama, RecoversAKnownTransformWithoutReflection) {
  const Eigen::Isometry3d T = Pose(
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(), {5, -2, 1});
  std::vector<Eigen::Vector3d> source, target;
  for (int k = 0; k < 20; ++k) {
    // Planar points (z = 0): the case where a careless SVD returns a reflection.
    source.emplace_back(std::cos(0.4 * k) * (1 + 0.1 * k), std::sin(0.3 * k), 0.0);
    target.push_back(T * source.back());
  }
  const Eigen::Isometry3d found = AlignUmeyama(source, target);
  EXPECT_LT((found.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(found.linear().determinant(), 1.0, 1e-12);
  EXPECT_THROW(AlignUmeyama({source[0]}, {target[0]}), std::invalid_argument);
}

TEST(RotationAngle, SmallAndLargeAngles) {
  EXPECT_EQ(RotationAngle(Eigen::Isometry3d::Identity()), 0.0);
  EXPECT_NEAR(RotationAngle(Pose(Rz(1e-9), {0, 0, 0})), 1e-9, 1e-18);
  EXPECT_NEAR(RotationAngle(Pose(Rz(kPi / 2), {0, 0, 0})), kPi / 2, 1e-15);
  EXPECT_NEAR(RotationAngle(Pose(Rz(kPi), {0, 0, 0})), kPi, 1e-15);
}

// ---- the three synthetic cases -----------------------------------------------------------------

// Ground truth drives 10 m along x in 1 m steps; the estimate drifts 0.1 m sideways per metre.
TEST(Metrics, PureTranslationDrift) {
  std::vector<Eigen::Isometry3d> gt, est;
  for (int k = 0; k <= 10; ++k) {
    gt.push_back(Translation(k, 0, 0));
    est.push_back(Translation(k, 0.1 * k, 0));
  }
  EvalOptions options;
  options.rpe_delta_m = 1.0;
  options.segment_lengths_m = {2.0, 5.0};
  const TrajectoryMetrics m = EvaluateAssociated(est, gt, options);
  ASSERT_EQ(m.status, MetricStatus::kOk);
  EXPECT_EQ(m.pairs, 11u);
  EXPECT_DOUBLE_EQ(m.length_m, 10.0);
  // Origin-aligned errors 0.1 k: RMSE 0.1 sqrt(Σk² / 11) = 0.1 sqrt(385 / 11) = 0.1 sqrt(35).
  EXPECT_NEAR(m.ate_origin_m.rmse, 0.1 * std::sqrt(35.0), 1e-12);
  EXPECT_NEAR(m.ate_origin_m.mean, 0.5, 1e-12);
  EXPECT_NEAR(m.ate_origin_m.median, 0.5, 1e-12);
  EXPECT_NEAR(m.ate_origin_m.max, 1.0, 1e-12);
  // SE(3) alignment lays the estimate's line (steps of sqrt(1.01) m) onto the ground truth's,
  // centroids together: errors (sqrt(1.01) − 1)(k − 5), RMSE (sqrt(1.01) − 1) sqrt(110 / 11).
  EXPECT_NEAR(m.ate_m.rmse, (std::sqrt(1.01) - 1.0) * std::sqrt(10.0), 1e-9);
  // RPE over 1 m: each step's error is the 0.1 m sideways drift, no rotation.
  EXPECT_EQ(m.rpe_trans_m.count, 10u);
  EXPECT_NEAR(m.rpe_trans_m.rmse, 0.1, 1e-12);
  EXPECT_NEAR(m.rpe_trans_m.max, 0.1, 1e-12);
  EXPECT_NEAR(m.rpe_rot_deg.rmse, 0.0, 1e-12);
  // KITTI: a segment of L ends at the first pose more than L further (devkit), i.e. L + 1 steps,
  // error 0.1 (L + 1) / L: L = 2 → 15 % (8 segments), L = 5 → 12 % (5 segments).
  ASSERT_EQ(m.segments.size(), 2u);
  EXPECT_EQ(m.segments[0].count, 8u);
  EXPECT_NEAR(m.segments[0].trans_percent, 15.0, 1e-9);
  EXPECT_EQ(m.segments[1].count, 5u);
  EXPECT_NEAR(m.segments[1].trans_percent, 12.0, 1e-9);
  EXPECT_NEAR(m.kitti_trans_percent, 100.0 * (8 * 0.15 + 5 * 0.12) / 13.0, 1e-9);
  EXPECT_NEAR(m.kitti_rot_deg_per_m, 0.0, 1e-12);
}

// The estimate turns 90° left at every 1 m step (a square) while the truth goes straight.
TEST(Metrics, PureYawDrift) {
  std::vector<Eigen::Isometry3d> gt, est = {Eigen::Isometry3d::Identity()};
  for (int k = 0; k <= 3; ++k) gt.push_back(Translation(k, 0, 0));
  for (int k = 1; k <= 3; ++k) est.push_back(est.back() * Pose(Rz(kPi / 2), {1, 0, 0}));
  // est positions: (0,0) (1,0) (1,1) (0,1).
  EvalOptions options;
  options.rpe_delta_m = 1.0;
  options.segment_lengths_m = {1.0};
  const TrajectoryMetrics m = EvaluateAssociated(est, gt, options);
  ASSERT_EQ(m.status, MetricStatus::kOk);
  // Errors 0, 0, |(1,1) − (2,0)| = sqrt 2, |(0,1) − (3,0)| = sqrt 10.
  EXPECT_NEAR(m.ate_origin_m.rmse, std::sqrt(3.0), 1e-12);  // sqrt((2 + 10) / 4)
  EXPECT_NEAR(m.ate_origin_m.mean, (std::sqrt(2.0) + std::sqrt(10.0)) / 4.0, 1e-12);
  EXPECT_NEAR(m.ate_origin_m.median, std::sqrt(2.0) / 2.0, 1e-12);
  EXPECT_NEAR(m.ate_origin_m.max, std::sqrt(10.0), 1e-12);
  // RPE over 1 m: E = T(−1,0,0)·[Rz(90°) | (1,0,0)] = [Rz(90°) | 0] for each of the 3 steps.
  EXPECT_EQ(m.rpe_rot_deg.count, 3u);
  EXPECT_NEAR(m.rpe_rot_deg.rmse, 90.0, 1e-9);
  EXPECT_NEAR(m.rpe_trans_m.rmse, 0.0, 1e-12);
  // KITTI, L = 1 m: segments 0→2 and 1→3 (first pose more than 1 m on). Both: estimate
  // [Rz(180°) | (1,1,0)] in the start frame, truth T(2,0,0); error [Rz(180°) | (−1,1,0)]:
  // sqrt 2 m and 180° per 1 m.
  EXPECT_EQ(m.segments[0].count, 2u);
  EXPECT_NEAR(m.kitti_trans_percent, 100.0 * std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(m.kitti_rot_deg_per_m, 180.0, 1e-6);
}

// The estimate is the truth seen from another world frame: alignment must remove it exactly.
TEST(Metrics, KnownSe3OffsetIsRemovedExactly) {
  const Eigen::Isometry3d T_offset = Pose(
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(), {5, -2, 1});
  std::vector<Eigen::Isometry3d> gt, est;
  for (int k = 0; k < 60; ++k) {
    const double a = 0.1 * k;
    gt.push_back(
        Pose(Rz(a) * Eigen::AngleAxisd(0.02 * k, Eigen::Vector3d::UnitX()).toRotationMatrix(),
             {3 * std::cos(a), 3 * std::sin(a), 0.05 * k}));
    est.push_back(T_offset * gt.back());
  }
  EvalOptions options;
  options.segment_lengths_m = {1.0, 5.0};
  const TrajectoryMetrics m = EvaluateAssociated(est, gt, options);
  ASSERT_EQ(m.status, MetricStatus::kOk);
  EXPECT_LT(m.ate_m.max, 1e-12);
  EXPECT_LT(m.ate_origin_m.max, 1e-12);
  EXPECT_LT(m.rpe_trans_m.max, 1e-12);
  EXPECT_LT(m.rpe_rot_deg.max, 1e-9);
  EXPECT_LT(m.kitti_trans_percent, 1e-10);
  EXPECT_LT(m.kitti_rot_deg_per_m, 1e-9);
  EXPECT_LT((m.T_groundtruth_estimate.matrix() - T_offset.inverse().matrix()).cwiseAbs().maxCoeff(),
            1e-12);
  // The same offset is a visible error before alignment, and the JSON carries every §8 key.
  const nlohmann::json j = ToJson(m);
  for (const char* key : {"ate_rmse_m", "ate_rmse_origin_m", "rpe_trans_rmse_m", "rpe_rot_rmse_deg",
                          "kitti_trans_percent", "kitti_rot_deg_per_m", "pairs", "length_m"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["pairs"], 60);
  EXPECT_NEAR(j["alignment"]["rotation_deg"].get<double>(), 0.7 * 180.0 / kPi, 1e-9);
}

TEST(Metrics, TooShortForTheDeltaGivesNullNotZero) {
  const std::vector<Eigen::Isometry3d> gt = {Translation(0, 0, 0), Translation(1, 0, 0)};
  EvalOptions options;
  options.rpe_delta_m = 5.0;
  const TrajectoryMetrics m = EvaluateAssociated(gt, gt, options);
  EXPECT_EQ(m.status, MetricStatus::kOk);
  EXPECT_EQ(m.rpe_trans_m.count, 0u);
  const nlohmann::json j = ToJson(m);
  EXPECT_TRUE(j["rpe_trans_rmse_m"].is_null());
  EXPECT_TRUE(j["kitti_trans_percent"].is_null());
  EXPECT_EQ(EvaluateAssociated({gt[0]}, {gt[0]}, options).status, MetricStatus::kTooFewPairs);
}

// ---- association -----------------------------------------------------------------------------

TEST(Associate, ByTimestampClosestFirstEachPoseOnce) {
  const Trajectory gt = Timed({0.0, 0.1, 0.2, 0.3, 0.4}, "gt.tum");
  // 0.29 and 0.305 both lie within 0.02 s of 0.3: the closer one (0.305) takes it; 5.0 matches
  // nothing.
  const Trajectory est = Timed({0.005, 0.115, 0.29, 0.305, 5.0}, "est.tum");
  const Association a = Associate(est, gt, EvalOptions{});
  ASSERT_TRUE(a.by_timestamp);
  EXPECT_EQ(a.estimate_index, (std::vector<std::size_t>{0, 1, 3}));
  EXPECT_EQ(a.groundtruth_index, (std::vector<std::size_t>{0, 1, 3}));
  EXPECT_NEAR(a.max_time_difference_s, 0.015, 1e-12);
}

TEST(Associate, MismatchedTimestampsAreNamed) {
  const Trajectory gt = Timed({0.0, 0.1, 0.2, 0.3}, "gt.tum");
  const Trajectory est = Timed({100.0, 100.1, 100.2, 100.3}, "est.tum");
  const TrajectoryMetrics m = EvaluateTrajectory(est, gt, EvalOptions{});
  EXPECT_EQ(m.status, MetricStatus::kNoPairs);
  EXPECT_NE(m.message.find("est.tum"), std::string::npos) << m.message;
  EXPECT_NE(m.message.find("gt.tum"), std::string::npos) << m.message;
  EXPECT_NE(m.message.find("eval.association_tolerance_s"), std::string::npos) << m.message;
  // A clock offset of 0.03 s needs a tolerance above the default 0.02 s.
  const Trajectory late = Timed({0.03, 0.13, 0.23, 0.33}, "late.tum");
  EXPECT_EQ(EvaluateTrajectory(late, gt, EvalOptions{}).status, MetricStatus::kNoPairs);
  EvalOptions loose;
  loose.association_tolerance_s = 0.04;
  const Association a = Associate(late, gt, loose);
  EXPECT_EQ(a.estimate_index, (std::vector<std::size_t>{0, 1, 2, 3}));
  EXPECT_EQ(a.groundtruth_index, (std::vector<std::size_t>{0, 1, 2, 3}));
}

TEST(Associate, ByIndexNeedsEqualLengths) {
  Trajectory gt = Timed({0, 1, 2}, "gt.txt"), est = Timed({0, 1}, "est.txt");
  gt.timestamps_s.clear();
  est.timestamps_s.clear();
  const Association a = Associate(est, gt, EvalOptions{});
  EXPECT_FALSE(a.by_timestamp);
  EXPECT_TRUE(a.estimate_index.empty());
  EXPECT_NE(a.message.find("2 poses"), std::string::npos) << a.message;
  est.poses.push_back(Translation(2, 0, 0));
  EXPECT_EQ(Associate(est, gt, EvalOptions{}).estimate_index.size(), 3u);
}

// ---- reading -----------------------------------------------------------------------------------

TEST(ReadTrajectory, TumAndKittiWithCommentsAndCrlf) {
  const Trajectory tum =
      ReadTrajectory(TempFile("a.tum",
                              "# timestamp tx ty tz qx qy qz qw\r\n0.0 1 2 3 0 0 0 1\r\n\r\n"
                              "0.1 1 2 3 0 0 0.7071068 0.7071068  # a quarter turn\r\n"));
  EXPECT_EQ(tum.format, TrajectoryFormat::kTum);
  ASSERT_EQ(tum.size(), 2u);
  EXPECT_EQ(tum.timestamps_s, (std::vector<double>{0.0, 0.1}));
  EXPECT_EQ(tum.poses[0].translation(), Eigen::Vector3d(1, 2, 3));
  EXPECT_NEAR(RotationAngle(tum.poses[1]), kPi / 2, 1e-6);
  EXPECT_NEAR(tum.poses[1].linear()(1, 0), 1.0, 1e-6);  // Rz(90°): x → y

  const Trajectory kitti = ReadTrajectory(
      TempFile("a.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n0 -1 0 4 1 0 0 5 0 0 0.9999999 6\n"));
  EXPECT_EQ(kitti.format, TrajectoryFormat::kKitti);
  EXPECT_FALSE(kitti.has_timestamps());
  ASSERT_EQ(kitti.size(), 2u);
  EXPECT_EQ(kitti.poses[1].translation(), Eigen::Vector3d(4, 5, 6));
  // The 7-digit matrix is projected onto a rotation.
  EXPECT_NEAR(
      (kitti.poses[1].linear().transpose() * kitti.poses[1].linear() - Eigen::Matrix3d::Identity())
          .norm(),
      0.0, 1e-15);
}

TEST(ReadTrajectory, ParseErrorsNameFileAndLine) {
  struct Case {
    std::string name, text, expect;
    TrajectoryFormat format = TrajectoryFormat::kAuto;
  };
  const std::string ok = "0 0 0 0 0 0 0 1\n";
  const std::vector<Case> cases = {
      {"text.tum", ok + "1 0 0 abc 0 0 0 1\n", "text.tum:2: not a finite number 'abc'"},
      {"nan.tum", ok + "# c\n1 0 0 nan 0 0 0 1\n", "nan.tum:3: not a finite number 'nan'"},
      {"seven.tum", ok + "1 0 0 0 0 0 1\n", "seven.tum:2: 7 columns, expected 8"},
      {"nine.tum", "0 0 0 0 0 0 0 1 5\n", "nine.tum:1: 9 numbers"},
      {"quat.tum", ok + "1 0 0 0 0 0 0 2\n", "quat.tum:2: quaternion"},
      {"order.tum", ok + "1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", "order.tum:3: timestamp"},
      {"forced.tum", ok, "forced.tum:1: 8 numbers", TrajectoryFormat::kKitti},
      {"mixed.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n" + ok, "mixed.txt:2: 8 numbers"},
      {"scaled.txt", "2 0 0 0 0 2 0 0 0 0 2 0\n", "scaled.txt:1: the 3x3 part is not a rotation"},
      {"mirror.txt", "-1 0 0 0 0 1 0 0 0 0 1 0\n", "mirror.txt:1: the 3x3 part is not a rotation"},
      {"empty.tum", "# nothing\n\n", "empty.tum: no poses"},
  };
  for (const Case& c : cases) {
    const std::string message = ReadError(TempFile(c.name, c.text), c.format);
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.name << ": " << message;
  }
  EXPECT_NE(ReadError(TempFile("x", "") / ".." / "missing.tum").find("missing.tum"),
            std::string::npos);
  EXPECT_EQ(ParseTrajectoryFormat("kitti"), TrajectoryFormat::kKitti);
  EXPECT_THROW(ParseTrajectoryFormat("euroc"), std::invalid_argument);
}

// ---- KITTI odometry 00 (datasets/kitti_odometry_00) -------------------------------------------

const fs::path kKitti00 = fs::path(ROVERMAP_DATASETS_DIR) / "kitti_odometry_00" / "KITTI_00_gt.txt";

TEST(Kitti00, AgainstItselfEveryErrorIsZero) {
  const Trajectory gt = ReadTrajectory(kKitti00);
  EXPECT_EQ(gt.format, TrajectoryFormat::kKitti);
  ASSERT_EQ(gt.size(), 4541u);
  const TrajectoryMetrics m = EvaluateTrajectory(gt, gt, EvalOptions{});
  ASSERT_EQ(m.status, MetricStatus::kOk);
  EXPECT_EQ(m.pairs, 4541u);
  // Summing the translation column differences with awk gives 3724.187 m.
  EXPECT_NEAR(m.length_m, 3724.187, 1e-3);
  EXPECT_LT(m.ate_m.max, 1e-9);
  EXPECT_LT(m.ate_origin_m.max, 1e-9);
  EXPECT_LT(m.rpe_trans_m.max, 1e-9);
  EXPECT_LT(m.rpe_rot_deg.max, 1e-9);
  EXPECT_LT(m.kitti_trans_percent, 1e-9);
  EXPECT_LT(m.kitti_rot_deg_per_m, 1e-9);
  for (const SegmentError& s : m.segments) EXPECT_GT(s.count, 4000u) << s.length_m;
}

// Every position scaled by 1.01 (a 1 % odometry scale error), rotations untouched: each relative
// translation c becomes 1.01 c, so a segment's or an RPE pair's error is exactly 0.01 ‖c‖ and
// there is no rotation error; the origin-aligned error of pose k is 0.01 ‖t_k − t_0‖.
TEST(Kitti00, OnePercentScaleErrorIsMeasuredExactly) {
  const Trajectory gt = ReadTrajectory(kKitti00);
  Trajectory est = gt;
  for (auto& T : est.poses) T.translation() *= 1.01;
  EvalOptions options;
  options.rpe_delta_m = 10.0;
  const TrajectoryMetrics m = EvaluateTrajectory(est, gt, options);
  ASSERT_EQ(m.status, MetricStatus::kOk);

  // Oracles straight from the definitions.
  const std::vector<double> dist = PathDistances(gt.poses);
  auto chord = [&](std::size_t i, std::size_t j) {
    return (gt.poses[i].linear().transpose() *
            (gt.poses[j].translation() - gt.poses[i].translation()))
        .norm();
  };
  double sum_squares = 0.0;
  for (const auto& T : gt.poses)
    sum_squares += std::pow(0.01 * (T.translation() - gt.poses[0].translation()).norm(), 2);
  EXPECT_NEAR(m.ate_origin_m.rmse, std::sqrt(sum_squares / 4541.0), 1e-9);

  double segment_sum = 0.0;
  std::size_t segments = 0;
  for (double length : options.segment_lengths_m)
    for (std::size_t i = 0; i < gt.size(); ++i) {
      std::size_t j = i;
      while (j < gt.size() && dist[j] <= dist[i] + length) ++j;
      if (j == gt.size()) break;
      segment_sum += 0.01 * chord(i, j) / length;
      ++segments;
    }
  EXPECT_NEAR(m.kitti_trans_percent, 100.0 * segment_sum / static_cast<double>(segments), 1e-9);
  EXPECT_NEAR(m.kitti_trans_percent, 1.0, 0.02);  // chords are about as long as the segments
  EXPECT_LT(m.kitti_rot_deg_per_m, 1e-9);

  double rpe_squares = 0.0;
  std::size_t rpe_pairs = 0;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    std::size_t j = i + 1;
    while (j < gt.size() && dist[j] < dist[i] + 10.0) ++j;
    if (j == gt.size()) break;
    rpe_squares += std::pow(0.01 * chord(i, j), 2);
    ++rpe_pairs;
  }
  EXPECT_EQ(m.rpe_trans_m.count, rpe_pairs);
  EXPECT_NEAR(m.rpe_trans_m.rmse, std::sqrt(rpe_squares / static_cast<double>(rpe_pairs)), 1e-9);
  EXPECT_LT(m.rpe_rot_deg.max, 1e-9);
  // Alignment can only reduce the error, and cannot remove a scale error.
  EXPECT_LT(m.ate_m.rmse, m.ate_origin_m.rmse);
  EXPECT_GT(m.ate_m.rmse, 0.1);
}

// With the real frame times (about 10 Hz): every second pose, stamped 5 ms late and seen from
// another world frame, associates by timestamp to exactly those poses and aligns to zero error.
TEST(Kitti00, AssociatesByTheRealTimestamps) {
  Trajectory gt = ReadTrajectory(kKitti00);
  std::ifstream times(kKitti00.parent_path() / "KITTI_00_gt_times.txt");
  for (double t; times >> t;) gt.timestamps_s.push_back(t);
  ASSERT_EQ(gt.timestamps_s.size(), gt.size());
  const Eigen::Isometry3d T_offset = Pose(Rz(1.0), {100, -50, 3});
  Trajectory est;
  est.file = "every_second.tum";
  for (std::size_t k = 0; k < gt.size(); k += 2) {
    est.timestamps_s.push_back(gt.timestamps_s[k] + 0.005);
    est.poses.push_back(T_offset * gt.poses[k]);
  }
  const Association a = Associate(est, gt, EvalOptions{});
  ASSERT_TRUE(a.by_timestamp);
  ASSERT_EQ(a.estimate_index.size(), 2271u);  // poses 0, 2, ..., 4540
  for (std::size_t k = 0; k < a.estimate_index.size(); ++k)
    ASSERT_EQ(a.groundtruth_index[k], 2 * a.estimate_index[k]);
  EXPECT_NEAR(a.max_time_difference_s, 0.005, 1e-9);
  const TrajectoryMetrics m = EvaluateTrajectory(est, gt, EvalOptions{});
  ASSERT_EQ(m.status, MetricStatus::kOk);
  EXPECT_LT(m.ate_m.max, 1e-8);
  EXPECT_LT(m.ate_origin_m.max, 1e-8);
  EXPECT_LT(m.kitti_trans_percent, 1e-8);
}

}  // namespace
}  // namespace rovermap::eval
