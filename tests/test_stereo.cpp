// Correlation stereo against real ground truth (Middlebury 2014 Motorcycle, quarter size, and
// the OpenCV/Middlebury 2006 Aloe pair, both in datasets/), and the error model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "stereo/Stereo.hpp"

namespace rovermap::stereo {
namespace {

namespace fs = std::filesystem;
const fs::path kMotorcycle = fs::path(ROVERMAP_DATASETS_DIR) / "middlebury2014_motorcycle_quarter";
const fs::path kAloe = fs::path(ROVERMAP_DATASETS_DIR) / "middlebury2006_aloe_opencv";

// Motorcycle calib.txt: cam0 f, cx, cy; doffs; baseline (mm).
constexpr double kF = 999.421, kCx = 294.182, kCy = 252.932, kDoffs = 32.778;
constexpr double kBaselineM = 0.193001;

struct Scores {
  double coverage = 0;     // estimated / evaluated pixels
  double bad2 = 0;         // |d − gt| > 2 px among estimated evaluated pixels
  double bad2_holes = 0;   // same, missing estimates counted as bad
  double mean_abs_px = 0;  // among estimated
  std::size_t evaluated = 0;
};

// `mask`: pixels to evaluate (non-occluded with ground truth).
Scores Score(const cv::Mat& disparity, const cv::Mat& gt, const cv::Mat& mask) {
  Scores s;
  std::size_t estimated = 0, bad = 0;
  double sum = 0;
  for (int v = 0; v < gt.rows; ++v) {
    for (int u = 0; u < gt.cols; ++u) {
      if (!mask.at<unsigned char>(v, u)) continue;
      ++s.evaluated;
      const float d = disparity.at<float>(v, u);
      if (std::isnan(d)) continue;
      ++estimated;
      const double e = std::abs(d - gt.at<float>(v, u));
      sum += e;
      if (e > 2.0) ++bad;
    }
  }
  s.coverage = static_cast<double>(estimated) / s.evaluated;
  s.bad2 = static_cast<double>(bad) / estimated;
  s.bad2_holes = static_cast<double>(bad + s.evaluated - estimated) / s.evaluated;
  s.mean_abs_px = sum / estimated;
  return s;
}

// PFM ("Pf": one channel), rows stored bottom to top; negative scale = little endian. Values as
// stored (Middlebury: disparity in px, inf = unknown). Empty on any problem.
cv::Mat ReadPfm(const fs::path& path) {
  std::FILE* file = std::fopen(path.string().c_str(), "rb");
  if (file == nullptr) return {};
  char magic[3] = {};
  int width = 0, height = 0;
  double scale = 0;
  cv::Mat out;
  if (std::fscanf(file, "%2s %d %d %lf", magic, &width, &height, &scale) == 4 &&
      std::string(magic) == "Pf" && scale < 0 && width > 0 && height > 0 &&
      std::fgetc(file) != EOF) {  // the single whitespace after the scale
    out.create(height, width, CV_32F);
    for (int v = height - 1; v >= 0; --v) {
      if (std::fread(out.ptr<float>(v), sizeof(float), width, file) != std::size_t(width)) {
        out.release();
        break;
      }
    }
  }
  std::fclose(file);
  return out;
}

struct Motorcycle {
  cv::Mat left, right, gt, mask;  // gt CV_32F, mask 255 = non-occluded with ground truth
};

Motorcycle LoadMotorcycle() {
  Motorcycle m;
  m.left = cv::imread((kMotorcycle / "im0.png").string(), cv::IMREAD_GRAYSCALE);
  m.right = cv::imread((kMotorcycle / "im1.png").string(), cv::IMREAD_GRAYSCALE);
  m.gt = ReadPfm(kMotorcycle / "disp0GT.pfm");
  const cv::Mat nocc = cv::imread((kMotorcycle / "mask0nocc.png").string(), cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(m.left.empty() || m.right.empty() || m.gt.empty() || nocc.empty());
  m.mask = (nocc == 255) & (m.gt == m.gt) & (m.gt < 1e6);  // finite ground truth only
  return m;
}

StereoOptions MotorcycleOptions(Algorithm algorithm) {
  StereoOptions o;
  o.algorithm = algorithm;
  o.num_disparities = 64;  // ground truth 9.2 .. 62.9 px
  if (algorithm == Algorithm::kBm) o.block_size = 11;
  return o;
}

TEST(StereoMiddlebury, PfmGroundTruthReadsTheRightWayUp) {
  const Motorcycle m = LoadMotorcycle();
  ASSERT_EQ(m.gt.type(), CV_32F);
  ASSERT_EQ(m.gt.size(), m.left.size());
  // The dataset README's range; a flipped or mis-scaled read would break the bad-pixel rate anyway.
  double lo = 1e9, hi = 0;
  for (int v = 0; v < m.gt.rows; ++v)
    for (int u = 0; u < m.gt.cols; ++u)
      if (m.mask.at<unsigned char>(v, u)) {
        lo = std::min(lo, double(m.gt.at<float>(v, u)));
        hi = std::max(hi, double(m.gt.at<float>(v, u)));
      }
  EXPECT_GT(lo, 9.0);
  EXPECT_LT(hi, 63.0);
}

TEST(StereoMiddlebury, MotorcycleSgbm3WayBadPixelRate) {
  const Motorcycle m = LoadMotorcycle();
  const DisparityResult r =
      ComputeDisparity(m.left, m.right, MotorcycleOptions(Algorithm::kSgbm3Way));
  ASSERT_EQ(r.status, StereoStatus::kOk) << r.message;
  const Scores s = Score(r.disparity, m.gt, m.mask);
  std::printf(
      "Motorcycle SGBM_3WAY: coverage %.3f bad2 %.4f bad2(holes bad) %.4f mean |e| %.3f px\n",
      s.coverage, s.bad2, s.bad2_holes, s.mean_abs_px);
  // Measured: coverage 0.926, bad2 0.0371 (0.109 with holes counted bad), mean 0.72 px
  // (without the sub-pixel refinement 0.0363, mean 0.64 px).
  EXPECT_GT(s.coverage, 0.90);
  EXPECT_LT(s.bad2, 0.05);
  EXPECT_LT(s.bad2_holes, 0.13);
}

TEST(StereoMiddlebury, DefaultFiltersRemoveWrongMatches) {
  const Motorcycle m = LoadMotorcycle();
  StereoOptions unfiltered = MotorcycleOptions(Algorithm::kSgbm3Way);
  unfiltered.disp12_max_diff = -1;
  unfiltered.uniqueness_ratio = 0;
  unfiltered.speckle_window_size = 0;
  const Scores off = Score(ComputeDisparity(m.left, m.right, unfiltered).disparity, m.gt, m.mask);
  const Scores on =
      Score(ComputeDisparity(m.left, m.right, MotorcycleOptions(Algorithm::kSgbm3Way)).disparity,
            m.gt, m.mask);
  std::printf("Motorcycle SGBM_3WAY unfiltered: coverage %.3f bad2 %.4f\n", off.coverage, off.bad2);
  EXPECT_GT(off.coverage, on.coverage);
  // Measured: unfiltered coverage 0.936, bad2 0.0448; filtered 0.926, 0.0371.
  EXPECT_GT(off.bad2, 1.1 * on.bad2);
}

TEST(StereoMiddlebury, MotorcycleBmBadPixelRate) {
  const Motorcycle m = LoadMotorcycle();
  const DisparityResult r = ComputeDisparity(m.left, m.right, MotorcycleOptions(Algorithm::kBm));
  ASSERT_EQ(r.status, StereoStatus::kOk) << r.message;
  const Scores s = Score(r.disparity, m.gt, m.mask);
  std::printf("Motorcycle BM: coverage %.3f bad2 %.4f bad2(holes bad) %.4f mean |e| %.3f px\n",
              s.coverage, s.bad2, s.bad2_holes, s.mean_abs_px);
  // Measured (block 11): coverage 0.843, bad2 0.0359 (0.187 with holes), mean 0.71 px.
  EXPECT_GT(s.coverage, 0.80);
  EXPECT_LT(s.bad2, 0.05);
}

TEST(StereoMiddlebury, MotorcycleMetricDepth) {
  const Motorcycle m = LoadMotorcycle();
  const StereoOptions o = MotorcycleOptions(Algorithm::kSgbm3Way);
  const DisparityResult r = ComputeDisparity(m.left, m.right, o);
  std::vector<double> abs_error, rel_error;
  for (int v = 0; v < m.gt.rows; ++v) {
    for (int u = 0; u < m.gt.cols; ++u) {
      const float d = r.disparity.at<float>(v, u);
      if (!m.mask.at<unsigned char>(v, u) || std::isnan(d)) continue;
      const double z = kF * kBaselineM / (d + kDoffs);
      const double z_gt = kF * kBaselineM / (m.gt.at<float>(v, u) + kDoffs);
      abs_error.push_back(std::abs(z - z_gt));
      rel_error.push_back(std::abs(z - z_gt) / z_gt);
    }
  }
  auto median = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    return x[x.size() / 2];
  };
  auto p90 = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + x.size() * 9 / 10, x.end());
    return x[x.size() * 9 / 10];
  };
  std::printf("Motorcycle depth: median |dz| %.4f m, p90 %.4f m, median rel %.4f\n",
              median(abs_error), p90(abs_error), median(rel_error));
  // Measured: median 9.4 mm, p90 35.8 mm, median relative 0.34 % (depths 2.0 .. 4.6 m);
  // without the sub-pixel refinement 6.8 mm, 28.6 mm, 0.26 %.
  EXPECT_LT(median(abs_error), 0.010);
  EXPECT_LT(p90(abs_error), 0.040);

  // The point path gives the same depths (doffs handled), in the range the dataset README gives.
  StereoCamera camera{kF, kF, kCx, kCy, kBaselineM, kDoffs};
  StereoOptions po = o;
  po.compute_normals = false;
  const StereoPointsResult points =
      DisparityToPoints(m.gt, camera, Eigen::Isometry3d::Identity(), po);
  ASSERT_EQ(points.status, StereoStatus::kOk);
  double zmin = 1e9, zmax = 0;
  for (const auto& p : points.cloud.points) {
    zmin = std::min(zmin, p.z());
    zmax = std::max(zmax, p.z());
  }
  std::printf("Motorcycle GT depth range %.3f .. %.3f m, %zu points\n", zmin, zmax,
              points.cloud.size());
  EXPECT_GT(zmin, 1.9);
  EXPECT_LT(zmax, 4.7);
}

TEST(StereoMiddlebury, AloeHalfSizeBadPixelRate) {
  cv::Mat left = cv::imread((kAloe / "aloeL.jpg").string(), cv::IMREAD_GRAYSCALE);
  cv::Mat right = cv::imread((kAloe / "aloeR.jpg").string(), cv::IMREAD_GRAYSCALE);
  cv::Mat gt8 = cv::imread((kAloe / "aloeGT.png").string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(left.empty() || right.empty() || gt8.empty());
  // Half size keeps the test quick: disparities 43..211 px become 21.5..105.5 px.
  cv::resize(left, left, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::resize(right, right, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::Mat gt_full;
  gt8.convertTo(gt_full, CV_32F);
  cv::Mat gt(left.size(), CV_32F), mask(left.size(), CV_8U);
  for (int v = 0; v < gt.rows; ++v) {
    for (int u = 0; u < gt.cols; ++u) {
      // Nearest full-size sample; unknown (0) anywhere in the 2×2 block = not evaluated.
      float lo = 1e9f;
      for (int dv = 0; dv < 2; ++dv)
        for (int du = 0; du < 2; ++du) lo = std::min(lo, gt_full.at<float>(2 * v + dv, 2 * u + du));
      float sum = 0;
      for (int dv = 0; dv < 2; ++dv)
        for (int du = 0; du < 2; ++du) sum += gt_full.at<float>(2 * v + dv, 2 * u + du);
      gt.at<float>(v, u) = sum / 8.0f;  // mean of four, halved
      mask.at<unsigned char>(v, u) = lo > 0 ? 255 : 0;
    }
  }
  StereoOptions o;
  o.min_disparity = 16;
  o.num_disparities = 96;  // 16 .. 111
  for (Algorithm algorithm : {Algorithm::kSgbm3Way, Algorithm::kBm}) {
    o.algorithm = algorithm;
    o.block_size = algorithm == Algorithm::kBm ? 11 : 5;
    const DisparityResult r = ComputeDisparity(left, right, o);
    ASSERT_EQ(r.status, StereoStatus::kOk) << r.message;
    const Scores s = Score(r.disparity, gt, mask);
    std::printf("Aloe/2 %s: coverage %.3f bad2 %.4f bad2(holes bad) %.4f mean |e| %.3f px\n",
                ToString(algorithm), s.coverage, s.bad2, s.bad2_holes, s.mean_abs_px);
    // Measured: SGBM_3WAY coverage 0.730, bad2 0.0371; BM (block 11) 0.647, 0.0256. No
    // occlusion mask for Aloe: occluded pixels are evaluated too (they count against coverage).
    EXPECT_LT(s.bad2, algorithm == Algorithm::kBm ? 0.035 : 0.05);
    EXPECT_GT(s.coverage, algorithm == Algorithm::kBm ? 0.60 : 0.68);
  }
}

// ---- the disparity range from the geometry -------------------------------------------------

TEST(StereoDisparities, ReachTheNearestGroundTheCameraSees) {
  const auto pose = [](double roll_deg, double z_m) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = (Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(roll_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.2, 0.0, z_m);
    return T;
  };
  StereoOptions o;  // num_disparities 0: automatic
  // The simulator's mast camera: 1 m up, tilted 30° down, f 300 px, b 0.2 m, 480×360. The
  // image's lower edge sees the ground 1/(sin 30° + 0.6 cos 30°) = 0.981 m away; 80 % of that
  // is d = 76.4 px -> 80.
  const StereoCamera sim{300, 300, 240, 180, 0.2, 0.0};
  EXPECT_EQ(DisparitiesForGround(sim, 480, 360, pose(-120.0, 1.0), o), 80);
  // KITTI's rig (datasets/kitti_stereo51): 1.65 m, 1.2° down, f 707.09, b 0.537 m, 1226×370:
  // ground 5.79 m away at the lower edge, d = 82.1 px at 80 % -> 96.
  const StereoCamera kitti{707.0912, 707.0912, 601.8873, 183.1104, 0.5371506532679237, 0.0};
  EXPECT_EQ(DisparitiesForGround(kitti, 1226, 370, pose(-91.2, 1.65), o), 96);
  // Looking 60° up: no ground; min_range_m decides (0.3 m: d = 200 -> 208), capped by the width.
  EXPECT_EQ(DisparitiesForGround(sim, 480, 360, pose(-30.0, 1.0), o), 208);
  EXPECT_EQ(DisparitiesForGround(sim, 160, 120, pose(-30.0, 1.0), o), 144);
  // A given range is kept; 0 is resolved.
  o.num_disparities = 32;
  EXPECT_EQ(ResolveDisparities(o, sim, 480, 360, pose(-120.0, 1.0)).num_disparities, 32);
  o.num_disparities = 0;
  EXPECT_EQ(ResolveDisparities(o, sim, 480, 360, pose(-120.0, 1.0)).num_disparities, 80);
  const cv::Mat image(60, 80, CV_8U, cv::Scalar(100));
  EXPECT_NE(ComputeDisparity(image, image, o).message.find("ResolveDisparities"),
            std::string::npos);
}

// ---- disparity -> points, error model -----------------------------------------------------

StereoCamera SmallCamera() { return {100.0, 100.0, 40.0, 30.0, 0.2, 0.0}; }

TEST(StereoPoints, FrontoParallelPlaneWithCovarianceAndNormals) {
  cv::Mat disparity(60, 80, CV_32F, cv::Scalar(10.0f));  // z = 100 * 0.2 / 10 = 2 m
  disparity.at<float>(5, 5) = std::nanf("");
  StereoOptions o;
  o.disparity_sigma_px = 0.2;
  o.pixel_sigma_px = 0.3;
  const StereoPointsResult r =
      DisparityToPoints(disparity, SmallCamera(), Eigen::Isometry3d::Identity(), o);
  ASSERT_EQ(r.status, StereoStatus::kOk);
  EXPECT_EQ(r.pixels, 4800u);
  EXPECT_EQ(r.invalid_disparity, 1u);
  EXPECT_EQ(r.cloud.size() + r.no_normal, 4799u);
  EXPECT_EQ(r.no_normal, 0u);
  ASSERT_TRUE(r.cloud.HasNormals() && r.cloud.HasCovariances());
  for (std::size_t i = 0; i < r.cloud.size(); ++i) {
    EXPECT_NEAR(r.cloud.points[i].z(), 2.0, 1e-12);
    EXPECT_NEAR(r.cloud.normals[i].z(), -1.0, 1e-9);  // faces the camera
  }
  // The pixel at the principal point: σ_z = z²σ_d/(f b) = 4 * 0.2 / 20 = 0.04 m,
  // lateral σ = z σ_px / f = 0.006 m.
  const std::size_t centre = 30 * 80 + 40 - 1;  // one NaN pixel earlier in the scan
  EXPECT_NEAR(r.cloud.points[centre].x(), 0.0, 1e-12);
  const Eigen::Matrix3d& cov = r.cloud.covariances[centre];
  EXPECT_NEAR(std::sqrt(cov(2, 2)), 0.04, 1e-12);
  EXPECT_NEAR(std::sqrt(cov(0, 0)), 0.006, 1e-12);
  EXPECT_NEAR(cov(0, 2), 0.0, 1e-15);
}

TEST(StereoPoints, CovarianceMatchesMonteCarlo) {
  const StereoCamera c = SmallCamera();
  const double u = 70, v = 10, d = 8;
  const double sigma_d = 0.3, sigma_px = 0.5;
  auto triangulate = [&](double uu, double vv, double dd) {
    const double z = c.fx * c.baseline_m / dd;
    return Eigen::Vector3d((uu - c.cx) * z / c.fx, (vv - c.cy) * z / c.fy, z);
  };
  const Eigen::Matrix3d model = PointCovariance(triangulate(u, v, d), c, sigma_d, sigma_px);
  std::mt19937 rng(7);
  std::normal_distribution<double> n01(0, 1);
  const int n = 200000;
  std::vector<Eigen::Vector3d> samples(n);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (auto& p : samples) {
    p = triangulate(u + sigma_px * n01(rng), v + sigma_px * n01(rng), d + sigma_d * n01(rng));
    mean += p / n;
  }
  Eigen::Matrix3d empirical = Eigen::Matrix3d::Zero();
  for (const auto& p : samples) empirical += (p - mean) * (p - mean).transpose() / (n - 1);
  // First order: within a few % for σ_d/d = 4 %.
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(std::sqrt(empirical(i, i)), std::sqrt(model(i, i)), 0.03 * std::sqrt(model(i, i)));
  }
  EXPECT_NEAR(empirical(0, 2) / std::sqrt(empirical(0, 0) * empirical(2, 2)),
              model(0, 2) / std::sqrt(model(0, 0) * model(2, 2)), 0.02);
}

TEST(StereoPoints, BodyFrameRangeLimitsAndCounts) {
  cv::Mat disparity(20, 80, CV_32F, cv::Scalar(10.0f));             // 2 m
  disparity(cv::Rect(0, 0, 80, 5)).setTo(100.0f);                   // 0.2 m: too near
  disparity(cv::Rect(0, 15, 80, 5)).setTo(0.5f);                    // 40 m: too far
  disparity(cv::Rect(0, 10, 80, 1)).setTo(-1.0f);                   // invalid
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();  // level camera, rpy
  T_body_sensor.linear() = (Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()))
                               .toRotationMatrix();  // [-90, 0, -90]
  T_body_sensor.translation() = Eigen::Vector3d(0.1, 0, 1.5);
  StereoOptions o;
  o.min_range_m = 0.5;
  o.max_range_m = 20.0;
  o.compute_normals = false;
  StereoCamera camera = SmallCamera();
  camera.cy = 2;  // so that the rows sit below the optical axis, whatever
  const StereoPointsResult r = DisparityToPoints(disparity, camera, T_body_sensor, o);
  EXPECT_EQ(r.too_near, 400u);
  EXPECT_EQ(r.too_far, 400u);
  EXPECT_EQ(r.invalid_disparity, 80u);
  EXPECT_EQ(r.cloud.size(), 1600u - 880u);
  EXPECT_FALSE(r.cloud.HasNormals());
  for (std::size_t i = 0; i < r.cloud.size(); ++i) {
    // Forward (body x) = camera depth 2 m plus the mount offset; below the mast.
    EXPECT_NEAR(r.cloud.points[i].x(), 2.1, 1e-9);
    EXPECT_LT(r.cloud.points[i].z(), 1.5);
    // The depth variance ends up along body x.
    const Eigen::Matrix3d& cov = r.cloud.covariances[i];
    EXPECT_GT(cov(0, 0), 4 * cov(1, 1));
    EXPECT_GT(cov(0, 0), 4 * cov(2, 2));
  }
}

TEST(StereoPoints, VoxelDownsamplingFusesPointsAndCovariances) {
  registration::PointCloud cloud;
  for (int i = 0; i < 4; ++i) {
    cloud.points.emplace_back(0.01 * i, 0.02, 0.03);  // one 10 cm voxel
    cloud.covariances.push_back(0.01 * Eigen::Matrix3d::Identity());
    cloud.normals.push_back(Eigen::Vector3d::UnitZ());
  }
  cloud.points.emplace_back(0.5, 0.5, 0.5);  // another
  cloud.covariances.push_back(0.04 * Eigen::Matrix3d::Identity());
  cloud.normals.push_back(Eigen::Vector3d::UnitX());
  EXPECT_EQ(VoxelDownsample(&cloud, 0.0), 0u);
  EXPECT_EQ(cloud.size(), 5u);
  EXPECT_EQ(VoxelDownsample(&cloud, 0.1), 3u);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_TRUE(cloud.points[0].isApprox(Eigen::Vector3d(0.015, 0.02, 0.03), 1e-12));
  EXPECT_TRUE(cloud.covariances[0].isApprox(0.0025 * Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_TRUE(cloud.normals[0].isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(cloud.points[1].isApprox(Eigen::Vector3d(0.5, 0.5, 0.5)));
}

TEST(StereoPoints, InvalidInputIsAStatusNotAnException) {
  const cv::Mat a(40, 100, CV_8U, cv::Scalar(0)), b(41, 100, CV_8U, cv::Scalar(0));
  StereoOptions o;
  EXPECT_EQ(ComputeDisparity(a, b, o).status, StereoStatus::kInvalidInput);
  o.num_disparities = 50;
  const DisparityResult r = ComputeDisparity(a, a, o);
  EXPECT_EQ(r.status, StereoStatus::kInvalidInput);
  EXPECT_NE(r.message.find("num_disparities"), std::string::npos);
  StereoCamera bad = SmallCamera();
  bad.baseline_m = 0;
  EXPECT_EQ(DisparityToPoints(cv::Mat(4, 4, CV_32F, cv::Scalar(1.0f)), bad,
                              Eigen::Isometry3d::Identity(), StereoOptions{})
                .status,
            StereoStatus::kInvalidInput);
  const StereoPointsResult p =
      ComputePoints(a, b, SmallCamera(), Eigen::Isometry3d::Identity(), StereoOptions{});
  EXPECT_EQ(p.status, StereoStatus::kInvalidInput);
  EXPECT_TRUE(p.cloud.empty());
}

}  // namespace
}  // namespace rovermap::stereo
