// Acceptance of a registration: status, inlier ratio, RMS, and a correction within k sigma of
// the odometry error model; each rejection says why.
#include <gtest/gtest.h>

#include <cmath>

#include "mapper/FrameJudge.hpp"

using namespace rovermap::mapper;
using rovermap::registration::RegistrationResult;
using rovermap::registration::RegistrationStatus;

namespace {

RegistrationResult Good() {
  RegistrationResult r;
  r.status = RegistrationStatus::kConverged;
  r.converged = true;
  r.inlier_ratio = 0.8;
  r.rms_m = 0.01;
  return r;
}

Eigen::Isometry3d Step(double forward_m, double yaw_deg) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(forward_m, 0, 0);
  return T;
}

}  // namespace

TEST(FrameJudge, AcceptsAGoodRegistration) {
  const Judgement j = JudgeRegistration(Good(), MapperOptions{});
  EXPECT_TRUE(j.accepted);
  EXPECT_EQ(j.reason, FallbackReason::kNone);
}

TEST(FrameJudge, RejectsEachFailureWithItsReason) {
  const MapperOptions options;
  RegistrationResult r = Good();
  r.status = RegistrationStatus::kTooFewPairs;
  r.message = "5 pairs";
  Judgement j = JudgeRegistration(r, options);
  EXPECT_FALSE(j.accepted);
  EXPECT_EQ(j.reason, FallbackReason::kRegistrationFailed);
  EXPECT_NE(j.detail.find("too_few_pairs"), std::string::npos) << j.detail;

  r = Good();
  r.status = RegistrationStatus::kMaxIterations;  // still usable
  EXPECT_TRUE(JudgeRegistration(r, options).accepted);

  r = Good();
  r.inlier_ratio = 0.1;
  j = JudgeRegistration(r, options);
  EXPECT_EQ(j.reason, FallbackReason::kLowInlierRatio);
  EXPECT_NE(j.detail.find("0.1"), std::string::npos) << j.detail;

  r = Good();
  r.rms_m = 1.0;
  EXPECT_EQ(JudgeRegistration(r, options).reason, FallbackReason::kHighRms);

  r = Good();
  r.rms_m = std::nan("");
  EXPECT_EQ(JudgeRegistration(r, options).reason, FallbackReason::kHighRms);
}

TEST(FrameJudge, CorrectionGateFollowsTheOdometryModel) {
  MapperOptions o;
  o.odometry_sigma_translation_ratio = 0.05;
  o.odometry_sigma_translation_m = 0.01;
  o.odometry_sigma_rotation_deg_per_m = 2.0;
  o.odometry_sigma_rotation_deg = 0.5;
  o.correction_gate_sigma = 3.0;
  // A 1 m step: σt = 0.06 m (gate 0.18 m), σr = 2.5° (gate 7.5°).
  const OdometrySigma sigma = OdometryStepSigma(1.0, o);
  EXPECT_NEAR(sigma.translation_m, 0.06, 1e-12);
  EXPECT_NEAR(sigma.rotation_rad, 2.5 * M_PI / 180.0, 1e-12);
  const Eigen::Isometry3d predicted = Step(1.0, 0.0);
  EXPECT_TRUE(JudgeCorrection(predicted, Step(1.17, 0.0), o).accepted);
  const Judgement far = JudgeCorrection(predicted, Step(1.19, 0.0), o);
  EXPECT_FALSE(far.accepted);
  EXPECT_EQ(far.reason, FallbackReason::kImplausibleCorrection);
  EXPECT_NE(far.detail.find("translation"), std::string::npos) << far.detail;
  EXPECT_TRUE(JudgeCorrection(predicted, Step(1.0, 7.4), o).accepted);
  const Judgement turned = JudgeCorrection(predicted, Step(1.0, 7.6), o);
  EXPECT_FALSE(turned.accepted);
  EXPECT_NE(turned.detail.find("rotation"), std::string::npos) << turned.detail;
}

TEST(FrameJudge, ReasonsHaveTheirCsvSpelling) {
  EXPECT_STREQ(ToString(FallbackReason::kNone), "none");
  EXPECT_STREQ(ToString(FallbackReason::kBadFrame), "bad_frame");
  EXPECT_STREQ(ToString(FallbackReason::kImplausibleCorrection), "implausible_correction");
}
