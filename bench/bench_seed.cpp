// bench_seed: what a biased dead reckoning leaves in the registered trajectory (docs/design.md
// §10: a seed biased in heading or scale changes the result by no more than the registration's
// own noise). Each sequence's frames are loaded once; the pipeline (defaults, or --config / --set)
// then runs from seeds made from the ground truth by a wheeled rover's error model
// (sim::DeadReckoningFromTruth: heading bias per metre, scale error, noise), from the truth
// itself and from the sequence's own odometry.
//
//   bench_seed [--frames N] [--quick | --truth-only] [--write-tum DIR] [--config FILE] [--set key=value ...]
//              SEQUENCE_DIR ...
//
// --quick: the ground truth, the bundled odometry, 0.4 and 0.8°/m with 3 % only.
// --truth-only: the ground-truth seed alone (and the peer), to compare settings quickly.
// --write-tum DIR: each row's trajectory as DIR/<sequence>_<row>.tum, for a per-frame look.
//
// Per seed: the per-frame heading error (mean, RMS) and the final heading error [deg], the ATE
// aligned at the first pose and SE(3)-aligned [m], the ATE's ratio to the ground-truth-seeded
// replay's, the frames whose yaw came from dead reckoning and those that fell back to it whole,
// and the seed's own figures.
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "bench/StereoVo.hpp"
#include "config/Config.hpp"
#include "eval/HeadingError.hpp"
#include "eval/TrajectoryMetrics.hpp"
#include "io/Tum.hpp"
#include "mapper/SeedStudy.hpp"
#include "sim/DeadReckoning.hpp"

using namespace rovermap;

namespace {

using Poses = std::vector<Eigen::Isometry3d>;

struct Seed {
  std::string name;
  Poses odometry;
};

void PrintRow(const std::string& name, const Poses& estimate, const Poses& truth,
              double reference_ate_m, const std::string& yaw_from_odometry = "") {
  const eval::HeadingErrors h = eval::CompareHeadings(estimate, truth);
  const eval::TrajectoryMetrics m = eval::EvaluateAssociated(estimate, truth, eval::EvalOptions());
  std::printf(
      "| %s | %+.3f | %.3f | %+.2f | %.3f | %.3f | %s | %s |\n", name.c_str(), h.mean_deg,
      h.rms_deg, h.final_deg, m.ate_origin_m.rmse, m.ate_m.rmse,
      reference_ate_m > 0.0
          ? (std::to_string(m.ate_origin_m.rmse / reference_ate_m).substr(0, 4) + "×").c_str()
          : "",
      yaw_from_odometry.c_str());
}

// Writes `poses`, stamped like the sequence's frames, as DIR/<sequence>_<row>.tum (row: the
// seed's name with everything but letters and digits turned into '_').
void WriteRow(const std::string& dir, const std::string& sequence, const std::string& row,
              const mapper::PreloadedSequence& seq, const Poses& poses) {
  if (dir.empty()) return;
  std::string name = std::filesystem::path(sequence).filename().string() + "_" + row;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  std::vector<io::StampedPose> stamped(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    stamped[i].timestamp = seq.frames[i].timestamp;
    stamped[i].T_world_body = poses[i];
  }
  std::filesystem::create_directories(dir);
  io::WriteTum(std::filesystem::path(dir) / (name + ".tum"), stamped);
}

}  // namespace

int main(int argc, char** argv) {
  bench::WaitPassivelyUnlessTold(argv);
  std::size_t frames = 0;
  bool quick = false, truth_only = false;
  std::string config_file, tum_dir;
  std::vector<std::string> overrides, sequences;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--frames") {
        frames = static_cast<std::size_t>(std::stoul(bench::OptionValue(argc, argv, &i)));
      } else if (arg == "--quick") {
        quick = true;
      } else if (arg == "--truth-only") {
        truth_only = true;
      } else if (arg == "--write-tum") {
        tum_dir = bench::OptionValue(argc, argv, &i);
      } else if (arg == "--config") {
        config_file = bench::OptionValue(argc, argv, &i);
      } else if (arg == "--set") {
        overrides.push_back(bench::OptionValue(argc, argv, &i));
      } else if (!arg.empty() && arg[0] == '-') {
        throw std::invalid_argument("unknown option " + arg);
      } else {
        sequences.push_back(arg);
      }
    }
    if (sequences.empty()) throw std::invalid_argument("give at least one SEQUENCE_DIR");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_seed: %s\n", e.what());
    return 2;
  }
  const config::Config cfg = config::LoadConfig(
      config_file.empty() ? std::nullopt : std::optional<std::filesystem::path>(config_file),
      overrides);
  mapper::PipelineOptions options{cfg.mapper, cfg.registration, cfg.stereo, cfg.dem, cfg.octomap, cfg.terrain};
  options.octomap.enabled = false;  // not compared; it only costs time here

  struct Model {
    const char* name;
    sim::DeadReckoningModel model;
  };
  const std::vector<Model> models = {
      {"noise only, a", {0.0, 0.05, 0.0, 0.01, 3}},    {"noise only, b", {0.0, 0.05, 0.0, 0.01, 4}},
      {"0.2°/m, 3 %", {0.2, 0.05, 0.03, 0.01, 1}},     {"0.4°/m, 3 %", {0.4, 0.05, 0.03, 0.01, 1}},
      {"0.8°/m, 3 %", {0.8, 0.05, 0.03, 0.01, 1}},     {"0.4°/m, 10 %", {0.4, 0.05, 0.10, 0.01, 1}},
      {"-0.4°/m, -3 %", {-0.4, 0.05, -0.03, 0.01, 2}},
  };
  std::printf("load average: %s\n", bench::LoadAverage().c_str());
  for (const std::string& dir : sequences) {
    const mapper::PreloadedSequence seq = mapper::Preload(dir, options, frames);
    if (seq.truth.size() != seq.frames.size()) {
      std::fprintf(stderr, "bench_seed: %s has no groundtruth.tum; skipped\n", dir.c_str());
      continue;
    }
    const Poses truth = io::PosesOf(seq.truth);
    std::vector<Seed> seeds = {{"ground truth", truth}};
    if (!truth_only) {
      seeds.push_back({"bundled odometry", mapper::OdometryOf(seq)});
      for (const Model& m : models) {
        const std::string name = m.name;
        if (quick && name != "0.4°/m, 3 %" && name != "0.8°/m, 3 %") continue;
        seeds.push_back({m.name, io::PosesOf(sim::DeadReckoningFromTruth(seq.truth, m.model))});
      }
    }

    std::printf("\n%s, %zu frames\n\n", dir.c_str(), seq.frames.size());
    std::optional<Poses> vo;
    if (seq.info.sensor_type == io::SensorType::kStereo)
      vo = bench::StereoVisualOdometry(dir, truth.front(), seq.frames.size());
    std::printf(
        "| seed | heading err/frame mean [deg] | RMS [deg] | final [deg] | ATE origin "
        "[m] | ATE [m] | ATE / GT-seeded | yaw from DR / fell back |\n|---|---|---|---|---|---|---|---|\n");
    double reference_ate = 0.0;
    for (const Seed& s : seeds) {
      const std::vector<mapper::FrameResult> results =
          mapper::RunWithOdometry(seq, s.odometry, options);
      const mapper::ChainedRun run = mapper::Chained(results);
      const Poses& estimate = run.poses;
      if (reference_ate == 0.0) {
        reference_ate =
            eval::EvaluateAssociated(estimate, truth, eval::EvalOptions()).ate_origin_m.rmse;
      }
      PrintRow("registered, seed " + s.name, estimate, truth, reference_ate,
               std::to_string(run.yaw_from_odometry) + " / " + std::to_string(run.fell_back));
      WriteRow(tum_dir, dir, "registered " + s.name, seq, estimate);
      if (s.name != "ground truth") PrintRow("  the seed itself", s.odometry, truth, 0.0);
      std::fflush(stdout);
    }
    if (vo) {
      PrintRow("peer: stereo visual odometry (GFTT, KLT, PnP RANSAC)", *vo, truth, reference_ate);
      WriteRow(tum_dir, dir, "peer vo", seq, *vo);
    }
  }
  return 0;
}
