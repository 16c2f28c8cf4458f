// Honest uncertainty: the chained covariance must say how far the chained pose is from the truth.
// Two parts. The maths: errors that repeat from step to step (PoseChain's SystematicError) add up
// linearly, and the chain's covariance must follow them as a Monte Carlo of perturbed SE(3) chains
// does. The data: on KITTI and the simulator, the true pose lies within the stated 2σ (6-D NEES <=
// 12.85) about as often as it should.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "config/Config.hpp"
#include "mapper/PoseChain.hpp"
#include "mapper/PoseUncertainty.hpp"
#include "mapper/SeedStudy.hpp"
#include "mapper/SystematicRates.hpp"
#include "sim/Simulator.hpp"
#include "tests/support/PipelineDefaults.hpp"
#include "tests/support/Sanitizers.hpp"
#include "tests/support/ScratchDir.hpp"

using namespace rovermap;
using mapper::Matrix6d;
using Vector6d = Eigen::Matrix<double, 6, 1>;

namespace {

// (Exp(δr), δt) ∘ T: the left perturbation of RegistrationResult and PoseChain.
Eigen::Isometry3d PerturbLeft(const Vector6d& delta, const Eigen::Isometry3d& T) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  const double angle = delta.head<3>().norm();
  if (angle > 0) D.linear() = Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
  D.translation() = delta.tail<3>();
  return D * T;
}

// ξ with T_true = T ∘ (Exp(ξr), ξt).
Vector6d RightError(const Eigen::Isometry3d& T, const Eigen::Isometry3d& T_true) {
  const Eigen::Isometry3d E = T.inverse() * T_true;
  const Eigen::AngleAxisd aa(E.linear());
  Vector6d xi;
  xi << aa.angle() * aa.axis(), E.translation();
  return xi;
}

struct MonteCarlo {
  double nees_mean = 0.0;        // of the final pose against its chained covariance
  double nees_mean_white = 0.0;  // against the covariance chained without the systematic part
};

// `runs` chains of `steps` increments (0.5 m ahead, 2° left) perturbed by a Gauss-Markov
// systematic error L·b (persistence φ) plus white noise of covariance Q.
MonteCarlo SimulateChains(int steps, int runs, const Vector6d& white_sigma,
                          const Vector6d& systematic_sigma, double persistence) {
  Eigen::Isometry3d increment = Eigen::Isometry3d::Identity();
  increment.linear() = Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).matrix();
  increment.translation() = Eigen::Vector3d(0.5, 0.0, 0.0);
  const Matrix6d Q = white_sigma.cwiseAbs2().asDiagonal();
  mapper::SystematicError systematic{systematic_sigma, persistence};
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  auto draw = [&] {
    Vector6d v;
    for (int i = 0; i < 6; ++i) v(i) = normal(rng);
    return v;
  };
  MonteCarlo out;
  for (int run = 0; run < runs; ++run) {
    mapper::PoseChain chain(Eigen::Isometry3d::Identity());
    mapper::PoseChain white(Eigen::Isometry3d::Identity());
    Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
    Vector6d b = draw();
    for (int k = 1; k <= steps; ++k) {
      if (k > 1) b = persistence * b + std::sqrt(1.0 - persistence * persistence) * draw();
      const Vector6d delta = systematic_sigma.cwiseProduct(b) + white_sigma.cwiseProduct(draw());
      const Eigen::Isometry3d measured = PerturbLeft(delta, increment);
      truth = truth * increment;
      chain.Add(Eigen::Isometry3d::Identity() * truth, measured, Q, systematic);
      white.Add(Eigen::Isometry3d::Identity() * truth, measured,
                Q + Matrix6d(systematic_sigma.cwiseAbs2().asDiagonal()));
    }
    const Vector6d xi = RightError(chain.back().T_world_body, truth);
    out.nees_mean += xi.dot(chain.back().covariance.ldlt().solve(xi)) / runs;
    out.nees_mean_white += xi.dot(white.back().covariance.ldlt().solve(xi)) / runs;
  }
  return out;
}

using rovermap::testing::PipelineDefaultsWithoutOctoMap;

mapper::CalibrationCheck Calibration(const mapper::PreloadedSequence& seq, const char* what,
                                     bool image_check = true) {
  mapper::PipelineOptions options = PipelineDefaultsWithoutOctoMap();
  options.mapper.image_check = image_check;
  const auto check =
      mapper::CheckCalibration(mapper::RunWithOdometry(seq, mapper::OdometryOf(seq), options));
  EXPECT_TRUE(check.has_value());
  if (!check) return {};
  std::printf("%s: %zu frames, within 2 sigma %.3f, NEES mean %.2f, median %.2f\n", what,
              check->frames, check->within_2sigma, check->nees_mean, check->nees_median);
  return *check;
}

// Calibrated: about 0.954 of the frames within 2σ and a NEES about 6, not merely cautious.
void ExpectCalibrated(const mapper::CalibrationCheck& c) {
  EXPECT_GE(c.within_2sigma, 0.85);
  EXPECT_LE(c.within_2sigma, 0.99);
  EXPECT_GE(c.nees_mean, 2.0);
  EXPECT_LE(c.nees_mean, 12.0);
}

}  // namespace

// ---- the maths ------------------------------------------------------------------------------

TEST(SystematicError, ChainedCovarianceMatchesMonteCarlo) {
  Vector6d white, systematic;
  white << 0.02, 0.02, 0.05, 2.0, 2.0, 1.0;  // mrad, mm (scaled below)
  systematic << 0.01, 0.01, 0.05, 3.0, 1.0, 1.0;
  white.head<3>() *= 1e-3, white.tail<3>() *= 1e-3;
  systematic.head<3>() *= 1e-3, systematic.tail<3>() *= 1e-3;
  for (const double persistence : {0.0, 0.9, 0.999}) {
    const MonteCarlo mc = SimulateChains(30, 3000, white, systematic, persistence);
    EXPECT_NEAR(mc.nees_mean, 6.0, 0.45) << "persistence " << persistence;
    if (persistence > 0.5) {
      // Chained as white noise, the same errors are far outside their covariance.
      EXPECT_GT(mc.nees_mean_white, 15.0) << "persistence " << persistence;
    }
  }
}

TEST(SystematicError, NoneLeavesTheChainAsItWas) {
  mapper::PoseChain a(Eigen::Isometry3d::Identity()), b(Eigen::Isometry3d::Identity());
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translation().x() = 1.0;
  Matrix6d q = Matrix6d::Identity() * 1e-4;
  for (int k = 1; k <= 5; ++k) {
    Eigen::Isometry3d odo = Eigen::Isometry3d::Identity();
    odo.translation().x() = k;
    a.Add(odo, step, q);
    b.Add(odo, step, q, mapper::SystematicError{});
  }
  EXPECT_TRUE(a.back().covariance.isApprox(b.back().covariance, 1e-15));
  EXPECT_TRUE(b.back().systematic_cross.isZero(0.0));
}

// ---- the data -------------------------------------------------------------------------------

// What repeats from step to step: the rig's stated calibration (its mounting's rotation in
// radians, its scale), and for stereo at least mapper.stereo_systematic_* besides.
TEST(SystematicError, RatesFollowTheRigAndStereosOwnBias) {
  const mapper::MapperOptions o;
  const io::RigCalibrationSigma exact{0.0, 0.0}, field{0.4, 0.007}, poor{2.0, 0.01};
  const mapper::SystematicRates cloud_exact =
      mapper::SystematicRatesOf(io::SensorType::kCloud, exact, o);
  EXPECT_EQ(cloud_exact.translation_ratio, 0.0);
  EXPECT_EQ(cloud_exact.rotation_rad_per_m, 0.0);
  // The larger of the two: 0.4° is 0.00698 rad, the scale 0.007.
  EXPECT_EQ(mapper::SystematicRatesOf(io::SensorType::kCloud, field, o).translation_ratio, 0.007);
  EXPECT_NEAR(mapper::SystematicRatesOf(io::SensorType::kCloud, {0.5, 0.001}, o).translation_ratio,
              0.5 * M_PI / 180.0, 1e-15);
  const mapper::SystematicRates stereo_exact =
      mapper::SystematicRatesOf(io::SensorType::kStereo, exact, o);
  EXPECT_EQ(stereo_exact.translation_ratio, o.stereo_systematic_ratio);
  EXPECT_NEAR(stereo_exact.rotation_rad_per_m, o.stereo_systematic_deg_per_m * M_PI / 180.0, 1e-15);
  EXPECT_NEAR(mapper::SystematicRatesOf(io::SensorType::kStereo, poor, o).translation_ratio,
              2.0 * M_PI / 180.0, 1e-15);
}

// Real stereo: the bundled KITTI excerpt, its own odometry, its 51 frames. Before (no stereo
// covariance scale, no systematic part): within 2σ 0.00, NEES mean 4487 (the stereo scale
// alone: 139). With the defaults: 0.94, NEES 8.0 (its first 20 frames alone: 0.842 at the
// scales 2 to 25, 0.895 at 50: one frame's difference).
TEST(PoseCalibration, KittiStereo) {
  if (rovermap::testing::kSanitizedBuild)
    GTEST_SKIP() << "statistics only: the Release suite checks them";
  const mapper::PreloadedSequence seq =
      mapper::Preload(std::filesystem::path(ROVERMAP_DATASETS_DIR) / "kitti_stereo51",
                      PipelineDefaultsWithoutOctoMap());
  ExpectCalibrated(Calibration(seq, "kitti_stereo51"));
}

namespace {

// Seeds 1…`seeds` of the simulator's 20-frame traverse with `sensor`, pooled: one traverse's
// frames share their errors (each pose is the last one's plus a step), so one traverse's
// fraction within 2σ is a noisy sample of the calibration.
// `rig`: the simulator's rig calibration error (sim.baseline_error, sim.mount_error_deg), drawn
// per traverse; none by default.
struct RigError {
  double baseline = 0.0;   // σ [ratio]
  double mount_deg = 0.0;  // σ per axis [deg]
};

mapper::CalibrationCheck PooledSimulated(sim::SensorKind sensor, int seeds, const char* name,
                                         bool image_check = true, RigError rig = {},
                                         int frames = 20) {
  mapper::CalibrationCheck pooled;
  double within = 0.0, nees = 0.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const std::filesystem::path dir =
        rovermap::testing::ScratchDir() / (std::string("sim_") + name + "_" + std::to_string(seed));
    config::Config cfg;
    cfg.sim.sensor = sensor;
    cfg.sim.frames = frames;
    cfg.sim.seed = seed;
    cfg.sim.baseline_error = rig.baseline;
    cfg.sim.mount_error_deg = rig.mount_deg;
    sim::Simulator(cfg.sim).WriteSequence(dir, {});
    const std::string what = std::string("sim ") + name + ", seed " + std::to_string(seed);
    const mapper::CalibrationCheck c = Calibration(
        mapper::Preload(dir, PipelineDefaultsWithoutOctoMap()), what.c_str(), image_check);
    pooled.frames += c.frames;
    within += c.within_2sigma * static_cast<double>(c.frames);
    nees += c.nees_mean * static_cast<double>(c.frames);
  }
  EXPECT_GT(pooled.frames, 0u);
  if (pooled.frames == 0) return pooled;
  pooled.within_2sigma = within / static_cast<double>(pooled.frames);
  pooled.nees_mean = nees / static_cast<double>(pooled.frames);
  std::printf("sim %s, %d traverses: %zu frames, within 2 sigma %.3f, NEES mean %.2f\n", name,
              seeds, pooled.frames, pooled.within_2sigma, pooled.nees_mean);
  return pooled;
}

}  // namespace

// The simulator's stereo: 0.32 to 1.00 within 2σ over seeds 1–8 with
// mapper.stereo_covariance_scale at 2, every one 1.00 at 50. Pooled over those eight traverses
// of 20 frames: 0.954, NEES 4.2 with the default 10 (0.757 at 2, 1.000 at 50; docs/replay.md,
// "Known limits"). Seeds 1–4 here (a traverse takes 8 s to render): 0.974, NEES 4.1 (0.71 at 2,
// 1.00 at 50). That is the registration's own covariance, which every frame without an image
// estimate chains: the image check is off here. With it on, the images hold the simulator's
// clean renderings so well that its steps are far inside the chain's calibration terms, which
// were fitted to KITTI's rig (1.000 within 2σ; ImageCheck.SimulatedStereoTraverse).
// Under the sanitizers PoseCalibration.SimulatedCloudTraverses runs the check's code and
// Mapper.SimulatedStereoTraverse the stereo frames'.
TEST(PoseCalibration, SimulatedStereoTraverses) {
  if (rovermap::testing::kSanitizedBuild)
    GTEST_SKIP() << "statistics only: the Release suite checks them";
  ExpectCalibrated(PooledSimulated(sim::SensorKind::kStereo, 4, "stereo", /*image_check=*/false));
}

// A real rig's calibration is never exact, and the chain's systematic part
// (mapper.stereo_systematic_*, fitted on KITTI) stands for that error. The simulator's rig is
// exact unless told otherwise, so with the image check, which holds its clean renderings to
// 0.01° a step, every frame of eight traverses lies within 2σ (NEES 0.5): cautious, as it
// should be for a rig that has no such error. Given one as a field calibration leaves it, drawn
// per traverse (sim.baseline_error 0.7 %, sim.mount_error_deg 0.4° about each axis: the
// systematic part's 0.7 % a metre along and across the step), the defaults are calibrated:
// seeds 1–8 pooled 0.987 within 2σ, NEES 3.6 (error²/σ² x 0.62, y 0.67, z 0.88, roll 0.23,
// pitch 0.28, yaw 0.63); seeds 1–4 here 0.974, NEES 3.7.
TEST(PoseCalibration, SimulatedStereoTraversesOnAFieldCalibratedRig) {
  if (rovermap::testing::kSanitizedBuild)
    GTEST_SKIP() << "statistics only: the Release suite checks them";
  ExpectCalibrated(PooledSimulated(sim::SensorKind::kStereo, 4, "stereo_rig",
                                   /*image_check=*/true, RigError{0.007, 0.4}));
}

// The simulator's cloud traverses keep yaw from dead reckoning on 11–19 of their 19 frames. With
// those directions chained at the gates' bound (mapper.odometry_sigma_*: 0.8° a 0.15 m step,
// where the simulated odometry errs by 0.04–0.05°), every frame of seeds 1–8 was within 2σ
// (NEES 1.1–6.0; yaw's error²/σ² 0.01). Chained at what odometry is typically wrong by
// (mapper.odometry_noise_*): seeds 1–8 pooled 0.993, NEES 5.1, yaw's error²/σ² 0.97; seeds 1–4
// here 0.987. What is left of the caution is roll's (error²/σ² 0.05: the chained attitude floor,
// mapper.registration_attitude_sigma_deg).
TEST(PoseCalibration, SimulatedCloudTraverses) {
  const int seeds = rovermap::testing::kSanitizedBuild ? 1 : 4;
  const mapper::CalibrationCheck c = PooledSimulated(sim::SensorKind::kCloud, seeds, "cloud");
  if (!rovermap::testing::kSanitizedBuild) ExpectCalibrated(c);
}

// A cloud rig mis-calibrated as a field calibration leaves it (0.4° mounting, 0.7 % range scale,
// drawn per traverse and stated in sequence.yaml): the chain's systematic part follows the
// stated calibration (mapper::SystematicRatesOf) for clouds as for stereo. One traverse is one
// draw of the rig, so 40 short ones (12 frames) are pooled. Measured: 0.927 within 2σ (0.298
// while the cloud chain had no systematic part).
TEST(PoseCalibration, SimulatedCloudTraversesOnAFieldCalibratedRig) {
  if (rovermap::testing::kSanitizedBuild)
    GTEST_SKIP() << "statistics only: the Release suite checks them";
  const mapper::CalibrationCheck c = PooledSimulated(sim::SensorKind::kCloud, 40, "cloud_rig",
                                                     /*image_check=*/true, RigError{0.007, 0.4},
                                                     /*frames=*/12);
  EXPECT_GE(c.within_2sigma, 0.85);
  EXPECT_LE(c.within_2sigma, 0.99);
}
