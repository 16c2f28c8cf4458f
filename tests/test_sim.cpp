// The simulator: determinism, its rendered stereo against the true terrain, and dead-reckoning
// statistics against the configured error model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/FileUtil.hpp"
#include "io/GeoTiff.hpp"
#include "io/Sequence.hpp"
#include "sim/Simulator.hpp"
#include "sim/TerrainGeoTiff.hpp"
#include "stereo/Stereo.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::sim {
namespace {

namespace fs = std::filesystem;

// A tiny configuration: small terrain and images, a few frames.
SimOptions Tiny() {
  SimOptions o;
  o.frames = 3;
  o.terrain_size_m = 16.0;
  o.terrain_cell_m = 0.04;
  o.image_width = 160;
  o.image_height = 120;
  o.focal_px = 100.0;
  o.max_range_m = 7.0;
  o.rocks = 30;
  o.craters = 2;
  return o;
}

// Tiny, with a 240×180 stereo camera (f = 150 px).
SimOptions SmallStereo() {
  SimOptions o = Tiny();
  o.image_width = 240;
  o.image_height = 180;
  o.focal_px = 150.0;
  return o;
}

double Median(std::vector<double> x) {
  std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
  return x[x.size() / 2];
}
double Quantile(std::vector<double> x, double q) {
  const std::size_t k = static_cast<std::size_t>(q * (x.size() - 1));
  std::nth_element(x.begin(), x.begin() + k, x.end());
  return x[k];
}

TEST(Simulator, SameSeedSameSequenceOtherSeedDifferent) {
  const fs::path a = rovermap::testing::ScratchDir() / "a";
  const fs::path b = rovermap::testing::ScratchDir() / "b";
  const fs::path c = rovermap::testing::ScratchDir() / "c";
  for (const auto& d : {a, b, c}) fs::remove_all(d);
  SimOptions o = Tiny();
  o.frames = 2;
  Simulator(o).WriteSequence(a, {});
  Simulator(o).WriteSequence(b, {});
  o.seed = 2;
  Simulator(o).WriteSequence(c, {});
  for (const char* file : {"sequence.yaml", "odometry.tum", "groundtruth.tum",
                           "frames/000000.left.png", "frames/000001.right.png"}) {
    EXPECT_EQ(io::ReadWholeFile(a / file), io::ReadWholeFile(b / file)) << file;
  }
  EXPECT_NE(io::ReadWholeFile(a / "frames/000001.left.png"),
            io::ReadWholeFile(c / "frames/000001.left.png"));
  EXPECT_NE(io::ReadWholeFile(a / "odometry.tum"), io::ReadWholeFile(c / "odometry.tum"));
}

TEST(Simulator, WritesAValidSequenceInBothModes) {
  for (SensorKind kind : {SensorKind::kStereo, SensorKind::kCloud}) {
    const fs::path dir = rovermap::testing::ScratchDir() / "valid";
    fs::remove_all(dir);
    SimOptions o = Tiny();
    o.sensor = kind;
    std::size_t calls = 0;
    const SimulateResult r =
        Simulator(o).WriteSequence(dir, [&](std::size_t done, std::size_t total) {
          ++calls;
          EXPECT_EQ(done, calls);
          EXPECT_EQ(total, 3u);
        });
    EXPECT_EQ(r.frames, 3u);
    EXPECT_EQ(calls, 3u);
    io::SequenceReader reader(dir);  // validates everything (docs/design.md §4)
    EXPECT_EQ(reader.frame_count(), 3u);
    EXPECT_TRUE(reader.has_groundtruth());
    io::Frame frame;
    ASSERT_TRUE(reader.Next(&frame));
    if (kind == SensorKind::kCloud) {
      EXPECT_GT(frame.cloud.size(), 300u);
      EXPECT_TRUE(frame.cloud.HasNormals());
    } else {
      EXPECT_EQ(frame.left.cols, 160);
    }
  }
}

// Stereo on the simulator's own rendered images, points compared with the true terrain.
TEST(Simulator, RenderedStereoMatchesTrueTerrainHeight) {
  const Simulator sim(SmallStereo());
  cv::Mat left, right;
  sim.RenderStereo(1, &left, &right);
  const io::CameraModel c = sim.camera();
  stereo::StereoOptions so;
  so.num_disparities = 32;
  so.max_range_m = 6.0;
  const stereo::StereoPointsResult r = stereo::ComputePoints(
      left, right, {c.fx, c.fy, c.cx, c.cy, c.baseline_m, 0.0}, sim.T_body_sensor(), so);
  ASSERT_EQ(r.status, stereo::StereoStatus::kOk);
  const Eigen::Isometry3d T_world_body = sim.truth()[1].T_world_body;
  std::vector<double> dz;
  for (const Eigen::Vector3d& p_body : r.cloud.points) {
    const Eigen::Vector3d p = T_world_body * p_body;
    dz.push_back(std::abs(p.z() - sim.terrain().Height(p.x(), p.y())));
  }
  std::printf("sim stereo: %zu points of %zu pixels; |dz| median %.4f m, p90 %.4f m, p99 %.4f m\n",
              r.cloud.size(), r.pixels, Median(dz), Quantile(dz, 0.9), Quantile(dz, 0.99));
  // Measured (seed 1, SGBM_3WAY defaults): 29554 of 43200 pixels, median 8.2 mm, p90 35 mm,
  // p99 0.51 m (occlusion edges and the horizon); without the sub-pixel refinement 29734,
  // 9.7 mm, 40 mm, 0.54 m.
  EXPECT_GT(r.cloud.size(), r.pixels / 2);
  EXPECT_LT(Median(dz), 0.02);
  EXPECT_LT(Quantile(dz, 0.9), 0.06);
}

// The matcher's disparity against the ray-cast truth, per disparity band: OpenCV's sub-pixel
// parabola reads it short by an amount that varies with the disparity (a non-affine error that
// bends the ground differently in successive frames); the Lucas–Kanade refinement
// (stereo.subpixel_window_px) flattens that.
TEST(Simulator, SubpixelRefinementFlattensTheDisparityBias) {
  SimOptions o = SmallStereo();
  o.max_range_m = 12.0;
  const Simulator sim(o);
  cv::Mat left, right;
  sim.RenderStereo(1, &left, &right);
  const io::CameraModel c = sim.camera();
  const Eigen::Isometry3d T_world_camera = sim.truth()[1].T_world_body * sim.T_body_sensor();
  cv::Mat truth(left.size(), CV_32F, cv::Scalar(std::nanf("")));
  for (int v = 0; v < truth.rows; ++v) {
    for (int u = 0; u < truth.cols; ++u) {
      const Eigen::Vector3d ray((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
      double t = 0.0;
      if (sim.terrain().Raycast(T_world_camera.translation(),
                                (T_world_camera.linear() * ray).normalized(), o.max_range_m, &t)) {
        const double z = ray.z() * t / ray.norm();
        truth.at<float>(v, u) = static_cast<float>(c.fx * c.baseline_m / z);
      }
    }
  }
  // Mean error [px] in the bands d < 5, 5–10, 10–20, >= 20 px (gross errors > 2 px left out).
  auto band_means = [&](int window) {
    stereo::StereoOptions so;
    so.num_disparities = 48;
    so.subpixel_window_px = window;
    const stereo::DisparityResult d = stereo::ComputeDisparity(left, right, so);
    std::vector<double> sum(4, 0.0), count(4, 0.0);
    for (int v = 0; v < truth.rows; ++v) {
      for (int u = 0; u < truth.cols; ++u) {
        const float t = truth.at<float>(v, u), m = d.disparity.at<float>(v, u);
        if (!std::isfinite(t) || !std::isfinite(m) || std::abs(m - t) > 2.0f) continue;
        const int band = t < 5 ? 0 : t < 10 ? 1 : t < 20 ? 2 : 3;
        sum[band] += m - t;
        ++count[band];
      }
    }
    for (int b = 0; b < 4; ++b) sum[b] /= std::max(count[b], 1.0);
    return sum;
  };
  const std::vector<double> plain = band_means(0), refined = band_means(9);
  std::printf(
      "disparity bias per band [px]: parabola %+.3f %+.3f %+.3f %+.3f; refined %+.3f %+.3f %+.3f "
      "%+.3f\n",
      plain[0], plain[1], plain[2], plain[3], refined[0], refined[1], refined[2], refined[3]);
  auto spread = [](const std::vector<double>& x) {
    return *std::max_element(x.begin(), x.end()) - *std::min_element(x.begin(), x.end());
  };
  // Measured (seed 1): parabola +0.047 −0.067 −0.126 −0.105 px (spread 0.17 px); refined
  // −0.020 +0.023 +0.013 +0.005 px (spread 0.043 px).
  EXPECT_GT(spread(plain), 0.12);
  EXPECT_LT(spread(refined), 0.08);
  for (const double b : refined) EXPECT_LT(std::abs(b), 0.05);
}

// Per-step dead-reckoning errors against the model: the travel ratio has mean
// (1 + scale)(1 + slip_mean) and σ (1 + scale)·slip_sigma; the heading error grows by
// bias·dt per step with σ random_walk·√dt.
TEST(Simulator, OdometryErrorsFollowTheModel) {
  SimOptions o = Tiny();
  o.frames = 400;
  o.terrain_size_m = 60;
  o.terrain_cell_m = 0.1;
  o.path = PathShape::kLoop;
  o.turn_radius_m = 8;
  o.odom_scale_error = 0.03;
  o.odom_slip_mean = 0.02;
  o.odom_slip_sigma = 0.05;
  o.heading_bias_deg_s = 0.1;
  o.heading_random_walk_deg_rt_s = 0.2;
  const Simulator sim(o);
  const double dt = 1.0 / o.frame_rate_hz;
  std::vector<double> ratio, dyaw;
  for (std::size_t k = 1; k < sim.truth().size(); ++k) {
    const Eigen::Isometry3d true_step =
        sim.truth()[k - 1].T_world_body.inverse() * sim.truth()[k].T_world_body;
    const Eigen::Isometry3d odom_step =
        sim.odometry()[k - 1].T_world_body.inverse() * sim.odometry()[k].T_world_body;
    ratio.push_back(odom_step.translation().norm() / true_step.translation().norm());
    auto yaw = [](const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); };
    const double e = yaw(sim.odometry()[k].T_world_body.linear()) -
                     yaw(sim.truth()[k].T_world_body.linear()) -
                     (yaw(sim.odometry()[k - 1].T_world_body.linear()) -
                      yaw(sim.truth()[k - 1].T_world_body.linear()));
    dyaw.push_back(std::atan2(std::sin(e), std::cos(e)) * 180 / M_PI);
  }
  auto mean = [](const std::vector<double>& x) {
    return std::accumulate(x.begin(), x.end(), 0.0) / x.size();
  };
  auto stddev = [&](const std::vector<double>& x) {
    const double m = mean(x);
    double s = 0;
    for (double v : x) s += (v - m) * (v - m);
    return std::sqrt(s / (x.size() - 1));
  };
  std::printf(
      "odometry: ratio mean %.4f sd %.4f (model %.4f, %.4f); dyaw mean %.4f sd %.4f deg (model "
      "%.4f, %.4f)\n",
      mean(ratio), stddev(ratio), 1.03 * 1.02, 1.03 * 0.05, mean(dyaw), stddev(dyaw), 0.1 * dt,
      0.2 * std::sqrt(dt));
  // Measured (seed 1): ratio 1.0470 ± 0.0491 (model 1.0506 ± 0.0515), heading step
  // 0.0566 ± 0.1354 deg (model 0.0500 ± 0.1414). Bounds: 4 standard errors on the mean,
  // 15 % on the spread (399 steps).
  const double n = static_cast<double>(ratio.size());
  EXPECT_NEAR(mean(ratio), 1.03 * 1.02, 4 * 1.03 * 0.05 / std::sqrt(n));
  EXPECT_NEAR(stddev(ratio), 1.03 * 0.05, 0.15 * 1.03 * 0.05);
  EXPECT_NEAR(mean(dyaw), 0.1 * dt, 4 * 0.2 * std::sqrt(dt) / std::sqrt(n));
  EXPECT_NEAR(stddev(dyaw), 0.2 * std::sqrt(dt), 0.15 * 0.2 * std::sqrt(dt));
}

TEST(Simulator, ErrorFreeOdometryIsTheTruthAndScaleErrorScalesTheDistance) {
  SimOptions o = Tiny();
  o.frames = 20;
  o.odom_scale_error = 0;
  o.odom_slip_mean = 0;
  o.odom_slip_sigma = 0;
  o.heading_bias_deg_s = 0;
  o.heading_random_walk_deg_rt_s = 0;
  const Simulator exact(o);
  for (std::size_t k = 0; k < exact.truth().size(); ++k) {
    EXPECT_TRUE(exact.odometry()[k].T_world_body.isApprox(exact.truth()[k].T_world_body, 1e-9));
  }
  o.odom_scale_error = 0.05;
  o.path = PathShape::kStraight;
  const Simulator scaled(o);
  const double true_length = (scaled.truth().back().T_world_body.translation() -
                              scaled.truth().front().T_world_body.translation())
                                 .norm();
  const double odom_length = (scaled.odometry().back().T_world_body.translation() -
                              scaled.odometry().front().T_world_body.translation())
                                 .norm();
  EXPECT_NEAR(odom_length / true_length, 1.05, 0.002);
}

TEST(Simulator, StartPoseMovesThePathOverTheSameTerrain) {
  SimOptions o = Tiny();
  o.frames = 10;
  const Simulator origin(o);
  o.start_x_m = 2.0;
  o.start_y_m = -1.5;
  o.start_yaw_deg = 120.0;
  const Simulator moved(o);
  // The same ground, sample for sample.
  ASSERT_EQ(moved.terrain().samples(), origin.terrain().samples());
  for (int j = 0; j < origin.terrain().samples(); j += 7) {
    for (int i = 0; i < origin.terrain().samples(); i += 7) {
      ASSERT_EQ(moved.terrain().Sample(i, j), origin.terrain().Sample(i, j)) << i << " " << j;
    }
  }
  // The path is the default one turned by the start yaw and moved to the start position; the
  // height, roll and pitch follow the terrain there.
  const Eigen::Rotation2Dd R(120.0 * M_PI / 180.0);
  for (std::size_t k = 0; k < origin.truth().size(); ++k) {
    const Eigen::Vector3d& p0 = origin.truth()[k].T_world_body.translation();
    const Eigen::Vector3d& p = moved.truth()[k].T_world_body.translation();
    const Eigen::Vector2d expected = Eigen::Vector2d(2.0, -1.5) + R * p0.head<2>();
    EXPECT_NEAR((p.head<2>() - expected).norm(), 0.0, 1e-9) << k;
    const Eigen::Matrix3d& R0 = origin.truth()[k].T_world_body.linear();
    const Eigen::Matrix3d& R1 = moved.truth()[k].T_world_body.linear();
    const double yaw0 = std::atan2(R0(1, 0), R0(0, 0));
    const double yaw1 = std::atan2(R1(1, 0), R1(0, 0));
    EXPECT_NEAR(std::remainder(yaw1 - yaw0 - 120.0 * M_PI / 180.0, 2 * M_PI), 0.0, 1e-9) << k;
  }
  EXPECT_TRUE(moved.odometry()[0].T_world_body.isApprox(moved.truth()[0].T_world_body, 1e-12));

  // The odometry seed changes the drift alone.
  o.odometry_seed = 7;
  const Simulator reseeded(o);
  for (std::size_t k = 0; k < moved.truth().size(); ++k) {
    EXPECT_TRUE(reseeded.truth()[k].T_world_body.isApprox(moved.truth()[k].T_world_body, 0.0));
  }
  EXPECT_FALSE(
      reseeded.odometry().back().T_world_body.isApprox(moved.odometry().back().T_world_body, 1e-9));
  // odometry_seed equal to seed is the default.
  o.odometry_seed = o.seed;
  const Simulator same(o);
  EXPECT_TRUE(
      same.odometry().back().T_world_body.isApprox(moved.odometry().back().T_world_body, 0.0));

  // A start at the edge of the square, heading out of it: refused, naming the keys.
  o.start_x_m = 7.9;
  o.start_yaw_deg = 0.0;
  try {
    Simulator outside(o);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sim.start_x_m"), std::string::npos) << e.what();
  }
}

TEST(Simulator, CloudModeFollowsTheStereoErrorModel) {
  SimOptions o = Tiny();
  o.outlier_fraction = 0.0;
  const Simulator sim(o);
  const SimCloud cloud = sim.RenderCloud(0);
  ASSERT_GT(cloud.cloud.size(), 500u);
  EXPECT_EQ(cloud.outliers, 0u);
  // Height error normalised by the model's vertical σ: about unit spread.
  const Eigen::Isometry3d T = sim.truth()[0].T_world_body * sim.T_body_sensor();
  std::vector<double> normalised;
  for (std::size_t i = 0; i < cloud.cloud.size(); ++i) {
    const Eigen::Vector3d p = T * cloud.cloud.points[i];
    const Eigen::Matrix3d cov = T.linear() * cloud.cloud.covariances[i] * T.linear().transpose();
    normalised.push_back(std::abs(p.z() - sim.terrain().Height(p.x(), p.y())) /
                         std::sqrt(cov(2, 2)));
  }
  // |N(0,1)| has median 0.674; the terrain slope under the lateral error adds a little.
  const double median = Median(normalised);
  std::printf("cloud mode: %zu points, median |dz|/sigma_z %.3f\n", cloud.cloud.size(), median);
  EXPECT_GT(median, 0.4);
  EXPECT_LT(median, 1.0);
  o.outlier_fraction = 0.1;
  const SimCloud noisy = Simulator(o).RenderCloud(0);
  EXPECT_NEAR(static_cast<double>(noisy.outliers) / noisy.cloud.size(), 0.1, 0.03);
}

// The rig's calibration error (sim.baseline_error, sim.mount_error_deg): one draw per traverse,
// from the seed. The sequence states the nominal rig; the points come from the drawn one, so
// they fit the terrain through the true mounting and baseline and miss it through the stated.
TEST(Simulator, RigCalibrationErrorIsDrawnPerTraverseAndNotStated) {
  SimOptions o = Tiny();
  o.outlier_fraction = 0.0;
  o.disparity_sigma_px = 0.0;
  o.pixel_sigma_px = 0.0;
  const Simulator exact(o);
  EXPECT_TRUE(exact.T_body_sensor_true().isApprox(exact.T_body_sensor(), 0.0));
  EXPECT_EQ(exact.baseline_true_m(), o.baseline_m);

  o.baseline_error = 0.01;
  o.mount_error_deg = 0.5;
  const Simulator rig(o);
  EXPECT_TRUE(rig.T_body_sensor().isApprox(exact.T_body_sensor(), 0.0));  // stated: nominal
  EXPECT_EQ(rig.camera().baseline_m, o.baseline_m);
  const double mount_deg = Eigen::AngleAxisd(rig.T_body_sensor().linear().transpose() *
                                             rig.T_body_sensor_true().linear())
                               .angle() *
                           180.0 / M_PI;
  const double baseline_ratio = rig.baseline_true_m() / o.baseline_m - 1.0;
  std::printf("rig error, seed 1: mounting %.3f deg, baseline %+.4f\n", mount_deg, baseline_ratio);
  EXPECT_GT(mount_deg, 0.0);
  EXPECT_LT(mount_deg, 5.0 * 0.5 * std::sqrt(3.0));
  EXPECT_NE(baseline_ratio, 0.0);
  EXPECT_LT(std::abs(baseline_ratio), 5.0 * 0.01);
  o.seed = 2;
  EXPECT_NE(Simulator(o).baseline_true_m(),
            rig.baseline_true_m());  // another traverse, another rig

  // Noise-free points: on the terrain through the true rig, off it through the stated one.
  const SimCloud cloud = rig.RenderCloud(0);
  ASSERT_GT(cloud.cloud.size(), 500u);
  const Eigen::Isometry3d& T_world_body = rig.truth()[0].T_world_body;
  const double scale = rig.baseline_true_m() / o.baseline_m;  // the depth the true rig measures
  std::vector<double> through_true, through_stated;
  for (const Eigen::Vector3d& p : cloud.cloud.points) {
    const Eigen::Vector3d t = T_world_body * rig.T_body_sensor_true() * (scale * p);
    const Eigen::Vector3d s = T_world_body * rig.T_body_sensor() * p;
    through_true.push_back(std::abs(t.z() - rig.terrain().Height(t.x(), t.y())));
    through_stated.push_back(std::abs(s.z() - rig.terrain().Height(s.x(), s.y())));
  }
  std::printf(
      "noise-free points off the terrain (median): %.2f mm through the true rig, %.2f mm "
      "through the stated one\n",
      1e3 * Median(through_true), 1e3 * Median(through_stated));
  EXPECT_LT(Median(through_true), 1e-3);
  EXPECT_GT(Median(through_stated), 5.0 * Median(through_true));
}

TEST(Simulator, TerrainGeoTiffHoldsTheTrueHeights) {
  SimOptions o = Tiny();
  o.frames = 1;
  const Simulator sim(o);
  const fs::path file = rovermap::testing::ScratchDir() / "rovermap_test_sim_terrain.tif";
  dem::ElevationMapOptions grid;
  grid.cell_size_m = 0.2;
  const io::GeoTiffInfo info = WriteTerrainGeoTiff(file, sim, grid);
  // 16 m square, 0.2 m cells: about 80 × 80 cells (the grid is turned by the convergence).
  EXPECT_NEAR(static_cast<double>(info.valid_cells), 80.0 * 80.0, 200.0);
  const io::DemRaster raster = io::ReadDemGeoTiff(file);
  EXPECT_EQ(raster.epsg, 32632);  // UTM 32N at the default origin (Lausanne)
  std::vector<double> tif, truth;
  for (float z : raster.elevation_m) {
    if (std::isfinite(z)) tif.push_back(z);
  }
  for (int j = 0; j < sim.terrain().samples(); j += 5)
    for (int i = 0; i < sim.terrain().samples(); i += 5)
      truth.push_back(sim.terrain().Sample(i, j));
  EXPECT_EQ(tif.size(), info.valid_cells);
  EXPECT_NEAR(Median(tif), Median(truth), 0.02);
  EXPECT_NEAR(*std::max_element(tif.begin(), tif.end()),
              *std::max_element(truth.begin(), truth.end()), 0.1);
}

}  // namespace
}  // namespace rovermap::sim
