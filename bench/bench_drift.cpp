// bench_drift: the drift anchor of docs/design.md §10. Frame to frame over simulated cloud
// sequences, every method seeded by the same dead-reckoning increments and chained from odometry
// pose 0: rovermap's pipeline (mapper::Mapper, defaults; and mapper.reference = local_map)
// against Open3D's point-to-plane ICP and Generalized-ICP. Built only with
// -DROVERMAP_BENCH_PEERS=ON.
//
//   bench_drift [--frames N] [--long N] [--gate-factor F | --gate-m M] [--max-iterations N]
//               [--repeats N] [--dump DIR]
//
// One table per sequence: ATE aligned at the first pose, ATE (SE(3)-aligned), final position
// error in % of the true path length, median time per frame, and how often a method's
// increment came out worse than dead reckoning's; then the ratios the target asks for. Each
// method runs --repeats times (default 3): the run with the median ATE is reported, with the
// range over the runs.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "bench/Peers.hpp"
#include "config/Config.hpp"
#include "core/Stopwatch.hpp"
#include "eval/TrajectoryMetrics.hpp"
#include "io/Sequence.hpp"
#include "io/Tum.hpp"
#include "mapper/Degeneracy.hpp"
#include "mapper/Mapper.hpp"
#include "sim/Simulator.hpp"

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

using Clock = std::chrono::steady_clock;
using core::MsSince;
using Poses = std::vector<Eigen::Isometry3d>;

// One method's chained trajectory and per-frame times (frame 0 registers nothing: no time).
struct Run {
  std::string name;
  Poses poses;
  std::vector<double> register_ms;  // the registration as compared (rovermap: prepare+register)
  std::vector<double> frame_ms;     // rovermap only: LoadFrame + ProcessLoaded
  std::vector<double> fitness;      // Open3D only
  int yaw_from_odometry = -1;       // rovermap only: increments whose yaw is dead reckoning's
};

struct Sequence {
  std::string name;
  fs::path dir;
  std::vector<double> stamps;
  Poses odometry, truth;
};


Sequence Simulate(const std::string& name, const fs::path& dir, const sim::SimOptions& o) {
  sim::Simulator(o).WriteSequence(dir, {});
  const io::SequenceReader reader(dir);
  std::vector<double> stamps;
  for (const auto& p : reader.odometry()) stamps.push_back(p.timestamp);
  return {name, dir, stamps, io::PosesOf(reader.odometry()), io::PosesOf(reader.groundtruth())};
}

// --dump DIR: DIR/<sequence>/<method>.tum (and groundtruth.tum), for `rovermap eval`.
std::string FileName(std::string name) {
  for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name;
}
void Dump(const fs::path& dir, const Sequence& seq, const std::string& name, const Poses& poses) {
  if (dir.empty()) return;
  std::vector<io::StampedPose> stamped;
  for (std::size_t k = 0; k < poses.size(); ++k)
    stamped.push_back({seq.stamps[k], poses[k], 0, {}});
  fs::create_directories(dir / FileName(seq.name));
  io::WriteTum(dir / FileName(seq.name) / (FileName(name) + ".tum"), stamped);
}

// rovermap's pipeline on every frame. `own_normals`: the simulator's true normals are dropped
// from the loaded clouds, so the matcher estimates its own (PCA), as the peers must.
Run RunRovermap(const Sequence& seq, mapper::Reference reference, bool own_normals) {
  const config::Config defaults;
  mapper::PipelineOptions options{defaults.mapper, defaults.registration, defaults.stereo,
                                  defaults.dem, defaults.octomap, defaults.terrain};
  options.mapper.reference = reference;
  io::SequenceReader reader(seq.dir);
  mapper::Mapper mapper(reader.info(), options);
  Run run;
  run.name = std::string("rovermap ") +
             (reference == mapper::Reference::kPrevious ? "previous" : "local_map") +
             (own_normals ? ", PCA normals" : "");
  run.yaw_from_odometry = 0;
  io::Frame frame;
  while (reader.Next(&frame)) {
    const auto t0 = Clock::now();
    const auto min_points = static_cast<std::size_t>(options.mapper.min_points);
    mapper::LoadedFrame loaded = mapper::LoadFrame(frame, mapper.sensor(), min_points);
    if (own_normals) loaded.cloud.normals.clear();
    const mapper::FrameResult r = mapper.ProcessLoaded(frame, std::move(loaded));
    const double whole_ms = MsSince(t0);
    run.poses.push_back(r.step.T_world_body);
    if (frame.index == 0) continue;
    const bool partial_yaw =
        r.status == mapper::FrameStatus::kPartial && (r.odometry_directions & mapper::kYaw) != 0;
    if (partial_yaw || r.status == mapper::FrameStatus::kFallback ||
        r.status == mapper::FrameStatus::kBadFrame) {
      ++run.yaw_from_odometry;
    }
    run.register_ms.push_back(r.time.prepare_ms + r.time.register_ms);
    run.frame_ms.push_back(whole_ms);
  }
  return run;
}

using PeerFactory = std::unique_ptr<bench::PeerMethod> (*)(const bench::Points&,
                                                           const bench::Points&);

// A peer frame to frame: frame k (source) onto frame k-1 (target), from the dead-reckoning
// increment, chained from odometry pose 0. Clouds are loaded as the Mapper loads them.
Run RunPeer(const Sequence& seq, PeerFactory make, const bench::PeerParams& params) {
  io::SequenceReader reader(seq.dir);
  const config::Config defaults;
  mapper::SensorSetup sensor;
  sensor.type = reader.info().sensor_type;
  sensor.camera = reader.info().camera;
  sensor.T_body_sensor = reader.info().T_body_sensor;
  sensor.stereo = defaults.stereo;
  Run run;
  io::Frame frame;
  bench::Points previous;
  while (reader.Next(&frame)) {
    mapper::LoadedFrame loaded = mapper::LoadFrame(frame, sensor, 1);
    if (frame.index == 0) {
      run.poses.push_back(seq.odometry[0]);
    } else {
      const Eigen::Isometry3d increment =
          seq.odometry[frame.index - 1].inverse() * seq.odometry[frame.index];
      const auto peer = make(loaded.cloud.points, previous);
      run.name = peer->Name();
      const bench::PeerResult r = peer->Run(increment, params);
      run.poses.push_back(run.poses.back() * r.T_target_source);
      run.register_ms.push_back(r.time_ms);
      run.fitness.push_back(r.fitness);
    }
    previous = std::move(loaded.cloud.points);
  }
  return run;
}

// Each step's increment against the true one: est_inc⁻¹ · true_inc, its translation [m] and
// rotation angle [deg].
struct StepErrors {
  std::vector<double> m, deg;
};
StepErrors IncrementErrors(const Poses& est, const Poses& truth) {
  StepErrors out;
  for (std::size_t k = 1; k < est.size(); ++k) {
    const Eigen::Isometry3d e =
        (est[k - 1].inverse() * est[k]).inverse() * (truth[k - 1].inverse() * truth[k]);
    out.m.push_back(e.translation().norm());
    out.deg.push_back(eval::RotationAngle(e) * 180.0 / M_PI);
  }
  return out;
}

struct Row {
  std::string name;
  double ate_origin_m = 0, ate_m = 0, final_percent = 0, register_ms = NAN, frame_ms = NAN;
  double ate_origin_min_m = 0, ate_origin_max_m = 0;  // over the repeated runs
  int worse_steps = 0;        // increments further from the truth than dead reckoning's
  double worst_step_m = 0;    // largest increment error, translation
  double worst_step_deg = 0;  // and rotation
  double min_fitness = NAN;
  int yaw_from_odometry = -1;
};

Row Evaluate(const Run& run, const Sequence& seq) {
  const eval::TrajectoryMetrics m = eval::EvaluateAssociated(run.poses, seq.truth, {});
  Row row;
  row.name = run.name;
  row.yaw_from_odometry = run.yaw_from_odometry;
  row.ate_origin_m = row.ate_origin_min_m = row.ate_origin_max_m = m.ate_origin_m.rmse;
  row.ate_m = m.ate_m.rmse;
  row.final_percent =
      100.0 * (run.poses.back().translation() - seq.truth.back().translation()).norm() / m.length_m;
  if (!run.register_ms.empty()) row.register_ms = bench::Median(run.register_ms);
  if (!run.frame_ms.empty()) row.frame_ms = bench::Median(run.frame_ms);
  const StepErrors errors = IncrementErrors(run.poses, seq.truth);
  const StepErrors odometry = IncrementErrors(seq.odometry, seq.truth);
  for (std::size_t k = 0; k < errors.m.size(); ++k) {
    if (errors.m[k] > odometry.m[k]) ++row.worse_steps;
    row.worst_step_m = std::max(row.worst_step_m, errors.m[k]);
    row.worst_step_deg = std::max(row.worst_step_deg, errors.deg[k]);
  }
  for (const double f : run.fitness)
    row.min_fitness = std::isnan(row.min_fitness) ? f : std::min(row.min_fitness, f);
  return row;
}

// `repeats` runs of one method (should a parallel reduction ever make runs differ, chaining
// would amplify it): the row of the run with the median ATE origin, the range of ATE origin
// over the runs, and the median time per frame over every run's frames.
Row Measure(const std::function<Run()>& run_once, const Sequence& seq, int repeats,
            const fs::path& dump) {
  std::vector<Run> runs;
  std::vector<Row> rows;
  Run pooled;
  for (int i = 0; i < repeats; ++i) {
    runs.push_back(run_once());
    rows.push_back(Evaluate(runs.back(), seq));
    for (const double t : runs.back().register_ms) pooled.register_ms.push_back(t);
    for (const double t : runs.back().frame_ms) pooled.frame_ms.push_back(t);
  }
  std::vector<std::size_t> order(rows.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&rows](std::size_t a, std::size_t b) {
    return rows[a].ate_origin_m < rows[b].ate_origin_m;
  });
  const std::size_t median = order[order.size() / 2];
  Row out = rows[median];
  out.ate_origin_min_m = rows[order.front()].ate_origin_m;
  out.ate_origin_max_m = rows[order.back()].ate_origin_m;
  if (!pooled.register_ms.empty()) out.register_ms = bench::Median(pooled.register_ms);
  if (!pooled.frame_ms.empty()) out.frame_ms = bench::Median(pooled.frame_ms);
  Dump(dump, seq, runs[median].name, runs[median].poses);
  return out;
}

void PrintRatio(const char* what, double value, double limit) {
  std::printf("  %-44s %7.3f  (target <= %.2f: %s)\n", what, value, limit,
              value <= limit ? "met" : "MISSED");
}

void Report(const Sequence& seq, const std::vector<Row>& rows, std::size_t steps) {
  std::printf("\n## %s: %zu frames, true path %.2f m\n", seq.name.c_str(), seq.truth.size(),
              eval::PathDistances(seq.truth).back());
  std::printf("%-32s %8s %11s %7s %8s %8s %9s %7s %7s %8s %7s %6s\n", "method", "ATEo[cm]",
              "ATEo range", "ATE[cm]", "final[%]", "reg[ms]", "frame[ms]", "worse", "max[cm]",
              "max[deg]", "min fit", "yaw DR");
  for (const Row& r : rows) {
    const std::string yaw = r.yaw_from_odometry < 0 ? "-" : std::to_string(r.yaw_from_odometry);
    std::printf(
        "%-32s %8.2f %5.2f-%-5.2f %7.2f %8.3f %8.1f %9.1f %3d/%-3zu %7.2f %8.3f %7.3f "
        "%6s\n",
        r.name.c_str(), 100 * r.ate_origin_m, 100 * r.ate_origin_min_m, 100 * r.ate_origin_max_m,
        100 * r.ate_m, r.final_percent, r.register_ms, r.frame_ms, r.worse_steps, steps,
        100 * r.worst_step_m, r.worst_step_deg, r.min_fitness, yaw.c_str());
  }
  const Row& odometry = rows[0];
  const Row& gicp = rows[2];
  for (std::size_t i = 3; i < rows.size(); ++i) {
    std::printf("%s against %s:\n", rows[i].name.c_str(), gicp.name.c_str());
    PrintRatio("ATE origin / GICP's", rows[i].ate_origin_m / gicp.ate_origin_m, 1.0);
    PrintRatio("time per frame (prepare+register) / GICP's", rows[i].register_ms / gicp.register_ms,
               0.5);
    PrintRatio("ATE origin / dead reckoning's", rows[i].ate_origin_m / odometry.ate_origin_m, 0.1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  bench::WaitPassivelyUnlessTold(argv);
  int frames = 30, long_frames = 150, repeats = 3;
  double gate_factor = 5.0;
  std::optional<double> gate_m;
  fs::path dump;
  bench::PeerParams params;
  params.max_iterations = 50;
  params.normals_knn = 20;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--frames")
        frames = std::stoi(bench::OptionValue(argc, argv, &i));
      else if (arg == "--long")
        long_frames = std::stoi(bench::OptionValue(argc, argv, &i));
      else if (arg == "--gate-factor")
        gate_factor = std::stod(bench::OptionValue(argc, argv, &i));
      else if (arg == "--gate-m")
        gate_m = std::stod(bench::OptionValue(argc, argv, &i));
      else if (arg == "--repeats")
        repeats = std::max(1, std::stoi(bench::OptionValue(argc, argv, &i)));
      else if (arg == "--dump")
        dump = bench::OptionValue(argc, argv, &i);
      else if (arg == "--max-iterations")
        params.max_iterations = std::stoi(bench::OptionValue(argc, argv, &i));
      else
        throw std::invalid_argument("unknown option " + arg);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr,
                 "bench_drift: %s\nusage: bench_drift [--frames N] [--long N] "
                 "[--gate-factor F | --gate-m M] [--max-iterations N] [--repeats N] "
                 "[--dump DIR]\n",
                 e.what());
    return 2;
  }
  const fs::path scratch =
      fs::temp_directory_path() / ("rovermap_bench_drift." + std::to_string(getpid()));
  fs::create_directories(scratch);
  std::printf("# bench_drift: Open3D %s; load average %s\n", bench::Open3dVersion().c_str(),
              bench::LoadAverage().c_str());
  std::printf(
      "# ATEo: ATE aligned at the first pose; final: |t_last - t_true,last| / true path "
      "length; reg: median per frame of rovermap's prepare+register stages or the peer's "
      "call (normals/covariances, tree, ICP); frame: LoadFrame + ProcessLoaded; worse: "
      "increments (translation) further from the truth than dead reckoning's; max: "
      "largest increment error; min fit: Open3D's smallest fitness; yaw DR: rovermap's "
      "increments whose yaw is dead reckoning's (degenerate direction or fallback)\n");

  sim::SimOptions traverse;
  traverse.sensor = sim::SensorKind::kCloud;
  traverse.frames = frames;
  sim::SimOptions loop = traverse;
  loop.frames = long_frames;
  loop.path = sim::PathShape::kLoop;
  loop.terrain_size_m = 60.0;
  const std::vector<Sequence> sequences = {
      Simulate("sim cloud traverse (curves)", scratch / "traverse", traverse),
      Simulate("sim cloud loop", scratch / "loop", loop)};

  for (const Sequence& seq : sequences) {
    // The peers' correspondence gate: gate_factor × the median nearest-neighbour spacing of
    // frame 0 (the spacing rovermap derives its D from), unless fixed.
    io::SequenceReader reader(seq.dir);
    io::Frame first;
    reader.Next(&first);
    const config::Config defaults;
    const registration::IndexedCloud cloud0(first.cloud, defaults.registration);
    params.max_correspondence_m = gate_m ? *gate_m : gate_factor * cloud0.spacing();
    std::printf(
        "\n# %s: %zu points in frame 0, median spacing %.3f m; peers: gate %.3f m, at "
        "most %d iterations, point-to-plane normals from %d neighbours\n",
        seq.name.c_str(), first.cloud.size(), cloud0.spacing(), params.max_correspondence_m,
        params.max_iterations, params.normals_knn);
    std::fflush(stdout);

    Run odometry;
    odometry.name = "dead reckoning";
    odometry.poses = seq.odometry;
    Dump(dump, seq, "groundtruth", seq.truth);
    std::vector<Row> rows = {Measure([&] { return odometry; }, seq, 1, dump)};
    for (const PeerFactory make :
         {&bench::MakeOpen3dPointToPlane, &bench::MakeOpen3dGeneralizedIcp}) {
      rows.push_back(Measure([&] { return RunPeer(seq, make, params); }, seq, repeats, dump));
    }
    for (const auto reference : {mapper::Reference::kPrevious, mapper::Reference::kLocalMap}) {
      for (const bool own_normals : {false, true}) {
        rows.push_back(
            Measure([&] { return RunRovermap(seq, reference, own_normals); }, seq, repeats, dump));
      }
    }
    Report(seq, rows, seq.truth.size() - 1);
    std::fflush(stdout);
  }
  std::printf("\n# load average after: %s\n", bench::LoadAverage().c_str());
  fs::remove_all(scratch);
  return 0;
}
