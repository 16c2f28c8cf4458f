// What a biased dead reckoning leaves in the registered trajectory (docs/design.md §10). A
// wheeled or skid-steer rover's heading drifts by tenths of a degree per metre; seeds made from
// the ground truth with such a drift (sim::DeadReckoningFromTruth) must register to the same
// increments as the ground truth itself: per-frame heading error within 0.02° of the
// truth-seeded replay's mean, ATE (aligned at the first pose) within 1.2× of it.
//
// The frames are loaded once (mapper::Preload) and replayed from each seed with the defaults.
// bench_seed prints the same comparison as a table (bench/README.md).
#include <gtest/gtest.h>

#include <cstdio>

#include "config/Config.hpp"
#include "eval/HeadingError.hpp"
#include "eval/TrajectoryMetrics.hpp"
#include "mapper/SeedStudy.hpp"
#include "sim/DeadReckoning.hpp"
#include "sim/Simulator.hpp"
#include "tests/support/PipelineDefaults.hpp"
#include "tests/support/Sanitizers.hpp"
#include "tests/support/ScratchDir.hpp"

using namespace rovermap;

namespace {

using Poses = std::vector<Eigen::Isometry3d>;

mapper::PipelineOptions Defaults() { return rovermap::testing::PipelineDefaultsWithoutOctoMap(); }

using io::PosesOf;

struct Replayed {
  eval::HeadingErrors heading;
  double ate_origin_m = 0.0;
  int yaw_from_odometry = 0;  ///< increments whose yaw was dead reckoning's
  int fell_back = 0;          ///< frames that took dead reckoning's whole increment
};

Replayed Replay(const mapper::PreloadedSequence& seq, const Poses& odometry) {
  const mapper::ChainedRun run =
      mapper::Chained(mapper::RunWithOdometry(seq, odometry, Defaults()));
  const Poses truth = PosesOf(seq.truth);
  return {eval::CompareHeadings(run.poses, truth),
          eval::EvaluateAssociated(run.poses, truth, eval::EvalOptions()).ate_origin_m.rmse,
          run.yaw_from_odometry, run.fell_back};
}

// Each seed model against the truth-seeded replay of the same frames.
void ExpectSeedIndependent(const mapper::PreloadedSequence& seq,
                           const std::vector<sim::DeadReckoningModel>& models) {
  ASSERT_EQ(seq.truth.size(), seq.frames.size());
  const Replayed reference = Replay(seq, PosesOf(seq.truth));
  EXPECT_EQ(reference.yaw_from_odometry, 0) << "yaw kept from the seed: the test would not see "
                                               "what registration leaves of it";
  // A rejected registration takes the truth's increment whole: the reference would look better
  // than registration is, and a biased seed would be held to it unfairly.
  EXPECT_EQ(reference.fell_back, 0) << "frames fell back to the truth seed";
  std::printf(
      "truth-seeded: heading error %+.4f deg/frame (RMS %.4f), final %+.3f deg, ATE %.4f m\n",
      reference.heading.mean_deg, reference.heading.rms_deg, reference.heading.final_deg,
      reference.ate_origin_m);
  for (const sim::DeadReckoningModel& m : models) {
    const Poses seed = PosesOf(sim::DeadReckoningFromTruth(seq.truth, m));
    const Replayed r = Replay(seq, seed);
    const eval::HeadingErrors seed_heading = eval::CompareHeadings(seed, PosesOf(seq.truth));
    std::printf(
        "%.1f deg/m, %+.0f %%: seed %+.3f deg/frame; registered %+.4f deg/frame (RMS "
        "%.4f), final %+.3f deg, ATE %.4f m (%.2fx)\n",
        m.heading_bias_deg_per_m, 100.0 * m.scale_error, seed_heading.mean_deg, r.heading.mean_deg,
        r.heading.rms_deg, r.heading.final_deg, r.ate_origin_m,
        r.ate_origin_m / reference.ate_origin_m);
    const std::string what =
        std::to_string(m.heading_bias_deg_per_m) + " deg/m, scale " + std::to_string(m.scale_error);
    EXPECT_NEAR(r.heading.mean_deg, reference.heading.mean_deg, 0.02) << what;
    EXPECT_LE(r.ate_origin_m, 1.2 * reference.ate_origin_m) << what;
  }
}

// The sanitizer build replays only the largest bias from each sequence (support/Sanitizers.hpp).
using rovermap::testing::kSanitizedBuild;

sim::DeadReckoningModel Model(double deg_per_m, double scale, std::uint64_t seed) {
  sim::DeadReckoningModel m;
  m.heading_bias_deg_per_m = deg_per_m;
  m.heading_noise_deg = 0.05;
  m.scale_error = scale;
  m.translation_noise_m = 0.01;
  m.seed = seed;
  return m;
}

}  // namespace

TEST(DeadReckoningFromTruth, ChainsTheModelledErrors) {
  std::vector<io::StampedPose> truth(11);
  for (std::size_t k = 0; k < truth.size(); ++k) {
    truth[k].timestamp = 0.5 * static_cast<double>(k);
    truth[k].T_world_body.translation() = Eigen::Vector3d(0.5 * static_cast<double>(k), 0, 0);
  }
  sim::DeadReckoningModel m;
  m.heading_bias_deg_per_m = 0.4;
  m.scale_error = 0.03;
  const Poses dr = PosesOf(sim::DeadReckoningFromTruth(truth, m));
  ASSERT_EQ(dr.size(), truth.size());
  EXPECT_TRUE(dr[0].isApprox(truth[0].T_world_body));
  // 5 m driven: 2° of heading, each 0.5 m step 3 % long.
  const eval::HeadingErrors h = eval::CompareHeadings(dr, PosesOf(truth));
  EXPECT_NEAR(h.final_deg, 2.0, 1e-9);
  EXPECT_NEAR(h.mean_deg, 0.2, 1e-9);
  EXPECT_NEAR((dr[1].translation() - dr[0].translation()).norm(), 0.515, 1e-12);
  // The same seed gives the same poses; noise moves them.
  m.heading_noise_deg = 0.05;
  const Poses a = PosesOf(sim::DeadReckoningFromTruth(truth, m));
  EXPECT_TRUE(a.back().isApprox(PosesOf(sim::DeadReckoningFromTruth(truth, m)).back()));
  EXPECT_FALSE(a.back().isApprox(dr.back()));
}

// The simulator's cloud traverse (30 frames, 0.15 m a frame) over ground with relief enough for
// every direction to be registered, from every heading bias (0.2, 0.4, 0.8°/m) and scale error (3
// and 10 %) below. (Over the default, gentler relief the relative degeneracy test,
// mapper.min_information, hands yaw to dead reckoning on 16 of 29 frames, and the seed's error
// comes back through that door: the biased seeds' ATE 1.2-1.7x the truth-seeded one's. That is the
// degeneracy test's to fix.)
TEST(SeedRobustness, SimulatedTraverse) {
  const std::filesystem::path dir = rovermap::testing::ScratchDir() / "sim";
  config::Config cfg;
  cfg.sim.sensor = sim::SensorKind::kCloud;
  cfg.sim.relief_m = 1.2;
  cfg.sim.relief_wavelength_m = 5.0;
  sim::Simulator(cfg.sim).WriteSequence(dir, {});
  const mapper::PreloadedSequence seq = mapper::Preload(dir, Defaults());
  std::vector<sim::DeadReckoningModel> models;
  std::uint64_t seed = 1;
  for (const double bias : {0.2, 0.4, 0.8})
    for (const double scale : {0.03, 0.10}) {
      const sim::DeadReckoningModel m = Model(bias, scale, seed++);
      if (!kSanitizedBuild || bias == 0.8) models.push_back(m);
    }
  ExpectSeedIndependent(seq, models);
}

// Real stereo: the bundled KITTI excerpt's first 20 frames (24 m at 1.2 m a frame, so 0.8°/m
// is a degree of heading error in every seed), each bias once, both scale errors.
// Under the sanitizers Mapper.KittiRealStereoBeatsDeadReckoningAndKeepsTheRoadFlat runs the same
// frames through the same code, and SeedRobustness.SimulatedTraverse the study's own.
TEST(SeedRobustness, KittiStereo) {
  if (kSanitizedBuild) GTEST_SKIP() << "statistics only: the Release suite checks them";
  const mapper::PreloadedSequence seq = mapper::Preload(
      std::filesystem::path(ROVERMAP_DATASETS_DIR) / "kitti_stereo51", Defaults(), 20);
  ExpectSeedIndependent(seq, {Model(0.2, 0.03, 1), Model(0.4, 0.10, 2), Model(0.8, 0.03, 3)});
}
