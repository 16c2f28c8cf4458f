// bench_stereo: correlation stereo (stereo frame -> body-frame points with covariances and
// normals) at 640x480 and at the simulator's default size, for SGBM_3WAY and BM, and the
// simulator's own speed; then, for each stereo sequence given, its first pair with the
// defaults, step by step (disparity, points, corners). Prints median wall-clock times.
//
//   bench_stereo [--runs N] [SEQUENCE_DIR ...]
//
// The pairs of the first table are rendered by the simulator (seed 1): no data files needed.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "core/Heap.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "sim/Simulator.hpp"
#include "stereo/ImageMotion.hpp"
#include "stereo/Stereo.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double MedianMs(int runs, const std::function<void()>& work) {
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto start = Clock::now();
    work();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  std::nth_element(ms.begin(), ms.begin() + ms.size() / 2, ms.end());
  return ms[ms.size() / 2];
}

rovermap::sim::SimOptions SimAt(int width, int height) {
  rovermap::sim::SimOptions o;
  o.focal_px = o.focal_px * width / o.image_width;  // same field of view
  o.image_width = width;
  o.image_height = height;
  o.frames = 3;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  // The heap as `rovermap replay` keeps it: a KITTI frame's points and covariances reuse freed
  // pages instead of faulting new ones in every run.
  rovermap::core::KeepFreedMemoryInHeap();
  int runs = 7;
  std::vector<std::string> sequences;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++i]));
    } else if (argv[i][0] != '-') {
      sequences.emplace_back(argv[i]);
    } else {
      std::fprintf(stderr, "usage: bench_stereo [--runs N] [SEQUENCE_DIR ...]\n");
      return 2;
    }
  }
  using rovermap::stereo::Algorithm;
  const rovermap::sim::SimOptions defaults;
  std::printf("# bench_stereo: median of %d runs [ms]; pairs rendered by the simulator\n", runs);
  std::printf("%-10s %-10s %12s %12s %10s\n", "size", "matcher", "disparity", "frame->pts",
              "points");
  for (const auto& [width, height] : std::vector<std::pair<int, int>>{
           {640, 480}, {defaults.image_width, defaults.image_height}}) {
    const rovermap::sim::Simulator sim(SimAt(width, height));
    cv::Mat left, right;
    sim.RenderStereo(1, &left, &right);
    const rovermap::io::CameraModel c = sim.camera();
    const rovermap::stereo::StereoCamera camera{c.fx, c.fy, c.cx, c.cy, c.baseline_m, 0.0};
    for (Algorithm algorithm : {Algorithm::kSgbm3Way, Algorithm::kBm}) {
      rovermap::stereo::StereoOptions o;
      o.algorithm = algorithm;
      if (algorithm == Algorithm::kBm) o.block_size = 11;
      o = rovermap::stereo::ResolveDisparities(o, camera, width, height, sim.T_body_sensor());
      const double disparity_ms =
          MedianMs(runs, [&] { rovermap::stereo::ComputeDisparity(left, right, o); });
      std::size_t points = 0;
      const double frame_ms = MedianMs(runs, [&] {
        points = rovermap::stereo::ComputePoints(left, right, camera, sim.T_body_sensor(), o)
                     .cloud.size();
      });
      std::printf("%4dx%-5d %-10s %12.1f %12.1f %10zu\n", width, height,
                  rovermap::stereo::ToString(algorithm), disparity_ms, frame_ms, points);
    }
  }

  // Simulator: frames per second at its default size (stereo rendering and cloud mode), and
  // the set-up (terrain, path, odometry).
  rovermap::sim::SimOptions o = defaults;
  const double setup_ms = MedianMs(std::max(1, runs / 3), [&] { rovermap::sim::Simulator s(o); });
  const rovermap::sim::Simulator sim(o);
  int frame = 0;
  const double stereo_ms = MedianMs(runs, [&] {
    cv::Mat left, right;
    sim.RenderStereo(frame++ % o.frames, &left, &right);
  });
  const double cloud_ms = MedianMs(runs, [&] { sim.RenderCloud(frame++ % o.frames); });
  std::printf(
      "\nsimulator (%dx%d, terrain %.0f m / %.2f m cells): set-up %.0f ms; stereo pair "
      "%.1f ms (%.2f frames/s); cloud %.1f ms (%.1f frames/s)\n",
      o.image_width, o.image_height, o.terrain_size_m, o.terrain_cell_m, setup_ms, stereo_ms,
      1000.0 / stereo_ms, cloud_ms, 1000.0 / cloud_ms);

  // Real pairs: the first frame of each sequence, the defaults (num_disparities from the rig).
  if (!sequences.empty()) {
    std::printf("\n%-28s %10s %10s %10s %10s %10s %8s\n", "sequence (frame 0, defaults)", "size",
                "disparity", "points", "corners", "points", "fill");
  }
  for (const std::string& dir : sequences) {
    try {
      rovermap::io::SequenceReader reader(dir);
      rovermap::io::Frame frame;
      const rovermap::io::SequenceInfo& info = reader.info();
      if (!info.camera || !reader.Next(&frame) || frame.left.empty()) {
        std::fprintf(stderr, "bench_stereo: %s: not a stereo sequence\n", dir.c_str());
        return 1;
      }
      const rovermap::io::CameraModel& c = *info.camera;
      const rovermap::stereo::StereoCamera camera{c.fx, c.fy, c.cx, c.cy, c.baseline_m, 0.0};
      // As the pipeline resolves them: the disparity range, the fill limited to what the DEM
      // fuses.
      const rovermap::stereo::StereoOptions o =
          rovermap::mapper::ResolveSensor(info, rovermap::stereo::StereoOptions{},
                                          rovermap::dem::ElevationMapOptions{})
              .stereo;
      cv::Mat disparity;
      const double disparity_ms = MedianMs(runs, [&] {
        disparity = rovermap::stereo::ComputeDisparity(frame.left, frame.right, o).disparity;
      });
      rovermap::stereo::StereoPointsResult points;
      const double points_ms = MedianMs(runs, [&] {
        points = rovermap::stereo::DisparityToPoints(disparity, camera, info.T_body_sensor, o);
      });
      const double corners_ms = MedianMs(runs, [&] {
        rovermap::stereo::DetectLandmarks(frame.left, frame.right, camera,
                                          rovermap::stereo::ImageMotionOptions{});
      });
      std::printf("%-28.28s %4dx%-5d %10.1f %10.1f %10.1f %10zu %8zu\n",
                  std::filesystem::path(dir).filename().c_str(), c.width, c.height, disparity_ms,
                  points_ms, corners_ms, points.cloud.size(), points.fill.size());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_stereo: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}
