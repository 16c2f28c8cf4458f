// bench_stereo: correlation stereo (stereo frame -> body-frame points with covariances and
// normals) at 640x480 and at the simulator's default size, for SGBM_3WAY and BM, and the
// simulator's own speed. Prints median wall-clock times.
//
//   bench_stereo [--runs N]
//
// The pairs are rendered by the simulator (seed 1), so no data files are needed.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "sim/Simulator.hpp"
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
  int runs = 7;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: bench_stereo [--runs N]\n");
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
  return 0;
}
