#include "stereo/Stereo.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "core/Stopwatch.hpp"
#include "dem/ElevationMap.hpp"
#include "registration/VoxelGrid.hpp"

namespace rovermap::stereo {
namespace {

using Clock = std::chrono::steady_clock;
using core::MsSince;

cv::Mat ToGrey(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

std::string CheckCamera(const StereoCamera& c) {
  if (!(c.fx > 0 && c.fy > 0 && std::isfinite(c.fx) && std::isfinite(c.fy)))
    return "focal lengths must be finite and > 0";
  if (!(c.baseline_m > 0 && std::isfinite(c.baseline_m))) return "baseline must be > 0";
  if (!std::isfinite(c.cx) || !std::isfinite(c.cy) || !std::isfinite(c.disparity_offset_px))
    return "principal point and disparity offset must be finite";
  return "";
}

// Gradient-based sub-pixel refinement (Lucas & Kanade 1981, in one dimension). OpenCV's
// parabola through the matching costs is biased towards whole pixels and, on the simulator's
// pairs, read the disparity short by an amount that depends on the disparity (docs/stereo.md,
// "Sub-pixel refinement"): a non-affine error that bends the ground differently in successive
// frames and tilts every registered step.
// With L(x) ≈ R(x − d), the right image warped by the current disparity, W(x) = R(x − d), gives
// W − L ≈ Δ·G for the missing shift Δ, G the x-gradient; Δ = Σ(W − L)G / ΣG² over the window.
// Each pixel is warped by its own disparity, so slanted ground needs no fronto-parallel window.
// (Also solving for a brightness offset between the cameras was better on Middlebury's
// Motorcycle but worse on the simulator's traverses and no better on KITTI: measured.)
void RefineSubpixel(const cv::Mat& left8, const cv::Mat& right8, int window, cv::Mat* disparity) {
  constexpr float kMinGradientSquared = 1.0f;  // [grey²/px²] mean over the window; else untextured
  constexpr float kMaxShift = 1.0f;            // [px] beyond: not the same minimum, keep it
  cv::Mat left, right;
  left8.convertTo(left, CV_32F);
  right8.convertTo(right, CV_32F);
  cv::Mat& d = *disparity;
  cv::Mat map_x(d.size(), CV_32F), map_y(d.size(), CV_32F), valid(d.size(), CV_32F);
  for (int v = 0; v < d.rows; ++v) {
    const float* dv = d.ptr<float>(v);
    float* mx = map_x.ptr<float>(v);
    float* my = map_y.ptr<float>(v);
    float* ok = valid.ptr<float>(v);
    for (int u = 0; u < d.cols; ++u) {
      ok[u] = std::isfinite(dv[u]) ? 1.0f : 0.0f;
      mx[u] = ok[u] > 0.0f ? static_cast<float>(u) - dv[u] : static_cast<float>(u);
      my[u] = static_cast<float>(v);
    }
  }
  cv::Mat warped, gradient;
  cv::remap(right, warped, map_x, map_y, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  cv::Sobel(0.5f * (warped + left), gradient, CV_32F, 1, 0, 3, 1.0 / 8.0);  // [grey/px]
  // Window sums over the pixels with a disparity (the others are not warped correctly).
  cv::Mat error_gradient = (warped - left).mul(gradient).mul(valid);
  cv::Mat gradient_squared = gradient.mul(gradient).mul(valid);
  const cv::Size box(window, window);
  cv::boxFilter(error_gradient, error_gradient, CV_32F, box, cv::Point(-1, -1), false);
  cv::boxFilter(gradient_squared, gradient_squared, CV_32F, box, cv::Point(-1, -1), false);
  const float min_energy = kMinGradientSquared * static_cast<float>(window * window);
  for (int v = 0; v < d.rows; ++v) {
    float* dv = d.ptr<float>(v);
    const float* eg = error_gradient.ptr<float>(v);
    const float* gg = gradient_squared.ptr<float>(v);
    for (int u = 0; u < d.cols; ++u) {
      if (!std::isfinite(dv[u]) || !(gg[u] > min_energy)) continue;
      const float shift = eg[u] / gg[u];
      if (std::abs(shift) < kMaxShift) dv[u] += shift;
    }
  }
}

double PixelSpacing(const std::vector<Eigen::Vector3d>& organised, int rows, int cols,
                    std::size_t valid) {
  constexpr std::size_t kSample = 16384;
  const std::size_t stride = std::max<std::size_t>(1, valid / kSample);
  std::vector<float> nearest;
  nearest.reserve(std::min(valid, kSample + 1));
  std::size_t seen = 0;
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) {
      const Eigen::Vector3d& p = organised[static_cast<std::size_t>(v) * cols + u];
      if (std::isnan(p.z()) || seen++ % stride != 0) continue;
      double best = INFINITY;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) {
          const int x = u + du, y = v + dv;
          if ((du == 0 && dv == 0) || x < 0 || y < 0 || x >= cols || y >= rows) continue;
          const Eigen::Vector3d& q = organised[static_cast<std::size_t>(y) * cols + x];
          if (!std::isnan(q.z())) best = std::min(best, (q - p).squaredNorm());
        }
      }
      if (std::isfinite(best)) nearest.push_back(static_cast<float>(std::sqrt(best)));
    }
  }
  if (nearest.empty()) return 0.0;
  const auto mid = nearest.begin() + static_cast<long>(nearest.size() / 2);
  std::nth_element(nearest.begin(), mid, nearest.end());
  return *mid;
}

void FillBetweenPixels(const std::vector<Eigen::Vector3d>& organised,
                       const std::vector<int>& point_of, int cols,
                       const registration::PointCloud& cloud, const StereoCamera& camera,
                       const Eigen::Isometry3d& T_body_sensor, const StereoOptions& o,
                       registration::PointCloud* fill) {
  // Far ground is sampled more coarsely than the DEM's cells along the view (one image row
  // spans 6.8 cm of ground at 6 m on a 340 px camera 1.7 m up), and pixel locking bunches the
  // rows' depths further, so each frame's points cover the cells in stripes of constant range
  // and a cell between them never gets the two frames it needs. Points on the segment between
  // neighbouring pixels of one surface fill the stripes.
  constexpr int kMaxFillPerPair = 16;
  const Eigen::Matrix3d R = T_body_sensor.linear();
  const bool normals = cloud.HasNormals();
  const double fb = camera.fx * camera.baseline_m;
  const auto rows = static_cast<int>(organised.size() / static_cast<std::size_t>(cols));
  const double max_h_sq = o.fill_max_horizontal_sigma_m * o.fill_max_horizontal_sigma_m;
  const Eigen::Matrix<double, 2, 3> horizontal = R.topRows<2>();  // body x, y of a sensor vector
  // Room for twice the measured points (KITTI's frames: 1.6 times): grown point by point, the
  // fill's covariances were copied again at every doubling, with the page faults of each new
  // block (docs/benchmarks.md, "Figures behind the frame pipeline's code"). Pages never written
  // cost nothing.
  const std::size_t room = fill->points.size() + 2 * cloud.size();
  fill->points.reserve(room);
  fill->covariances.reserve(room);
  if (normals) fill->normals.reserve(room);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * cols + u;
      if (point_of[i] < 0) continue;
      const Eigen::Vector3d& p = organised[i];
      for (const auto& [du, dv] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (u + du >= cols || v + dv >= rows) continue;
        const std::size_t j = static_cast<std::size_t>(v + dv) * cols + (u + du);
        if (point_of[j] < 0) continue;
        const Eigen::Vector3d& q = organised[j];
        // Only along one surface. Not the normals' relative depth rule: pixel locking holds
        // runs of rows at one disparity and then steps by a whole pixel, 5 % of the depth at
        // 18 px, which that rule reads as an edge; occlusion edges step by more.
        const double step = std::abs(fb / q.z() - fb / p.z());
        if (step > o.fill_max_step_px) continue;
        // Neighbours closer than the spacing (most of the near field) need no point between.
        const double gap = (q - p).norm();
        const int n =
            std::min(kMaxFillPerPair, static_cast<int>(std::ceil(gap / o.fill_spacing_m)) - 1);
        if (n <= 0) continue;
        // A point between two pixels may be off by half their disparity step (a locked run's
        // step is mostly error), beyond the disparity noise of either.
        const double sigma_d = std::hypot(o.disparity_sigma_px, 0.5 * step);
        // The fill's nearer end is its most precise point: past the DEM's limit there, no
        // point of the segment would be fused.
        // Its farther end is its least precise: within the limit there, every point is.
        bool check_each = false;
        if (max_h_sq > 0.0) {
          const bool p_nearer = p.z() < q.z();
          if (dem::LargestHorizontalVariance(
                  horizontal,
                  PointCovariance(p_nearer ? p : q, camera, sigma_d, o.pixel_sigma_px)) > max_h_sq)
            continue;
          check_each = dem::LargestHorizontalVariance(
                           horizontal, PointCovariance(p_nearer ? q : p, camera, sigma_d,
                                                       o.pixel_sigma_px)) > max_h_sq;
        }
        for (int k = 1; k <= n; ++k) {
          const double t = static_cast<double>(k) / (n + 1);
          const Eigen::Vector3d x = p + t * (q - p);
          const Eigen::Matrix3d cov = PointCovariance(x, camera, sigma_d, o.pixel_sigma_px);
          if (check_each && dem::LargestHorizontalVariance(horizontal, cov) > max_h_sq) continue;
          fill->points.push_back(T_body_sensor * x);
          fill->covariances.push_back(R * cov * R.transpose());
          if (normals) {
            const int nearer = t < 0.5 ? point_of[i] : point_of[j];
            fill->normals.push_back(cloud.normals[static_cast<std::size_t>(nearer)]);
          }
        }
      }
    }
  }
}

}  // namespace

const char* ToString(Algorithm algorithm) {
  switch (algorithm) {
    case Algorithm::kSgbm3Way:
      return "sgbm_3way";
    case Algorithm::kSgbm:
      return "sgbm";
    case Algorithm::kSgbmHh:
      return "sgbm_hh";
    case Algorithm::kBm:
      return "bm";
  }
  return "?";
}

std::string CheckOptions(const StereoOptions& o) {
  if (o.num_disparities < 0 || o.num_disparities % 16 != 0)
    return "stereo.num_disparities must be a positive multiple of 16";
  if (o.block_size < 1 || o.block_size % 2 == 0) return "stereo.block_size must be odd and >= 1";
  if (o.algorithm == Algorithm::kBm && (o.block_size < 5 || o.block_size > 255))
    return "stereo.block_size must be in [5, 255] for bm";
  if (o.algorithm == Algorithm::kBm && (o.pre_filter_cap < 1 || o.pre_filter_cap > 63))
    return "stereo.pre_filter_cap must be in [1, 63] for bm";
  if (o.p1 < 0 || o.p2 < 0 || (o.p1 > 0 && o.p2 > 0 && o.p2 <= o.p1))
    return "stereo.p2 must be > stereo.p1";
  if (!(o.min_range_m >= 0 && o.max_range_m > o.min_range_m))
    return "stereo.max_range_m must be > stereo.min_range_m >= 0";
  if (o.normal_step_px < 1) return "stereo.normal_step_px must be >= 1";
  if (o.subpixel_window_px != 0 && (o.subpixel_window_px < 3 || o.subpixel_window_px % 2 == 0))
    return "stereo.subpixel_window_px must be 0 or odd and >= 3";
  if (!(o.fill_spacing_m >= 0.0) || !(o.fill_max_step_px >= 0.0))
    return "stereo.fill_spacing_m and stereo.fill_max_step_px must be >= 0";
  return "";
}

DisparityResult ComputeDisparity(const cv::Mat& left_in, const cv::Mat& right_in,
                                 const StereoOptions& o) {
  DisparityResult result;
  const auto start = Clock::now();
  if (left_in.empty() || right_in.empty() || left_in.size() != right_in.size() ||
      left_in.depth() != CV_8U || right_in.depth() != CV_8U) {
    result.status = StereoStatus::kInvalidInput;
    result.message = "stereo: need two non-empty 8-bit images of the same size";
    return result;
  }
  if (const std::string problem = CheckOptions(o); !problem.empty()) {
    result.status = StereoStatus::kInvalidInput;
    result.message = problem;
    return result;
  }
  if (o.num_disparities == 0) {
    result.status = StereoStatus::kInvalidInput;
    result.message =
        "stereo.num_disparities is 0 (automatic): resolve it first (stereo::ResolveDisparities)";
    return result;
  }
  if (left_in.cols <= o.num_disparities + o.block_size) {
    result.status = StereoStatus::kInvalidInput;
    result.message = "stereo: image narrower than num_disparities + block_size";
    return result;
  }
  const cv::Mat left = ToGrey(left_in);
  const cv::Mat right = ToGrey(right_in);

  cv::Mat raw;  // CV_16S, disparity × 16
  if (o.algorithm == Algorithm::kBm) {
    cv::Ptr<cv::StereoBM> bm = cv::StereoBM::create(o.num_disparities, o.block_size);
    bm->setMinDisparity(o.min_disparity);
    bm->setPreFilterCap(o.pre_filter_cap);
    bm->setUniquenessRatio(o.uniqueness_ratio);
    bm->setTextureThreshold(o.texture_threshold);
    bm->setSpeckleWindowSize(o.speckle_window_size);
    // StereoBM filters the ×16 disparity without rescaling the range (SGBM rescales).
    bm->setSpeckleRange(16 * o.speckle_range);
    bm->setDisp12MaxDiff(o.disp12_max_diff);
    bm->compute(left, right, raw);
  } else {
    const int area = o.block_size * o.block_size;
    const int mode = o.algorithm == Algorithm::kSgbm3Way ? cv::StereoSGBM::MODE_SGBM_3WAY
                     : o.algorithm == Algorithm::kSgbmHh ? cv::StereoSGBM::MODE_HH
                                                         : cv::StereoSGBM::MODE_SGBM;
    cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
        o.min_disparity, o.num_disparities, o.block_size, o.p1 > 0 ? o.p1 : 8 * area,
        o.p2 > 0 ? o.p2 : 32 * area, o.disp12_max_diff, o.pre_filter_cap, o.uniqueness_ratio,
        o.speckle_window_size, o.speckle_range, mode);
    sgbm->compute(left, right, raw);
  }

  result.disparity.create(raw.size(), CV_32F);
  const int invalid_below = o.min_disparity * 16;
  for (int v = 0; v < raw.rows; ++v) {
    const std::int16_t* in = raw.ptr<std::int16_t>(v);
    float* out = result.disparity.ptr<float>(v);
    for (int u = 0; u < raw.cols; ++u) {
      if (in[u] < invalid_below) {
        out[u] = std::numeric_limits<float>::quiet_NaN();
        ++result.invalid;
      } else {
        out[u] = static_cast<float>(in[u]) / 16.0f;
        ++result.valid;
      }
    }
  }
  if (o.subpixel_window_px > 0)
    RefineSubpixel(left, right, o.subpixel_window_px, &result.disparity);
  result.time_ms = MsSince(start);
  return result;
}

int DisparitiesForGround(const StereoCamera& camera, int width, int height,
                         const Eigen::Isometry3d& T_body_sensor, const StereoOptions& options) {
  constexpr double kNearerThanGround = 0.8;  // rocks and relief stand up to 20 % nearer
  const double height_m = T_body_sensor.translation().z();
  double nearest_m = std::numeric_limits<double>::infinity();
  // The nearest ground lies under the image's lower edge; corners and centre cover a roll.
  for (const double u : {0.0, 0.5 * width, static_cast<double>(width)}) {
    for (const double v : {0.0, static_cast<double>(height)}) {
      const Eigen::Vector3d ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      const double down = -(T_body_sensor.linear() * ray).z();  // body-z drop per metre of depth
      if (height_m > 0.0 && down > 0.0) nearest_m = std::min(nearest_m, height_m / down);
    }
  }
  const double depth_m = std::isfinite(nearest_m)
                             ? std::max(kNearerThanGround * nearest_m, options.min_range_m)
                             : options.min_range_m;
  double disparity = camera.fx * camera.baseline_m / std::max(depth_m, 1e-6) -
                     camera.disparity_offset_px - options.min_disparity;
  if (!std::isfinite(disparity)) disparity = 256.0;
  const int widest = std::max(16, (width - options.block_size - 1) / 16 * 16);
  const int needed = static_cast<int>(std::ceil(std::max(disparity, 1.0) / 16.0)) * 16;
  return std::clamp(needed, 16, std::min(256, widest));
}

StereoOptions ResolveDisparities(const StereoOptions& options, const StereoCamera& camera,
                                 int width, int height, const Eigen::Isometry3d& T_body_sensor) {
  StereoOptions resolved = options;
  if (resolved.num_disparities == 0) {
    resolved.num_disparities = DisparitiesForGround(camera, width, height, T_body_sensor, options);
  }
  return resolved;
}

Eigen::Matrix3d PointCovariance(const Eigen::Vector3d& p, const StereoCamera& c,
                                double disparity_sigma_px, double pixel_sigma_px) {
  // d' = fx·b / z; ∂(x,y,z)/∂u = (z/fx, 0, 0), ∂/∂v = (0, z/fy, 0), ∂/∂d = −p / d'.
  const double z = p.z();
  const double d = c.fx * c.baseline_m / z;
  const Eigen::Vector3d j_d = -p / d;
  const double su = pixel_sigma_px * z / c.fx;
  const double sv = pixel_sigma_px * z / c.fy;
  Eigen::Matrix3d cov = disparity_sigma_px * disparity_sigma_px * j_d * j_d.transpose();
  cov(0, 0) += su * su;
  cov(1, 1) += sv * sv;
  return cov;
}

StereoPointsResult DisparityToPoints(const cv::Mat& disparity, const StereoCamera& camera,
                                     const Eigen::Isometry3d& T_body_sensor,
                                     const StereoOptions& o) {
  StereoPointsResult result;
  const auto start = Clock::now();
  std::string problem = CheckCamera(camera);
  if (problem.empty()) problem = CheckOptions(o);
  if (problem.empty() && (disparity.empty() || disparity.type() != CV_32F))
    problem = "stereo: disparity must be a non-empty CV_32F image";
  if (!problem.empty()) {
    result.status = StereoStatus::kInvalidInput;
    result.message = problem;
    return result;
  }

  // Organised camera-frame points; NaN z marks a pixel without a point.
  const int rows = disparity.rows;
  const int cols = disparity.cols;
  std::vector<Eigen::Vector3d> organised(static_cast<std::size_t>(rows) * cols,
                                         Eigen::Vector3d::Constant(std::nan("")));
  const double fb = camera.fx * camera.baseline_m;
  std::size_t valid = 0;
  for (int v = 0; v < rows; ++v) {
    const float* row = disparity.ptr<float>(v);
    for (int u = 0; u < cols; ++u) {
      ++result.pixels;
      const double d = static_cast<double>(row[u]) + camera.disparity_offset_px;
      if (!(d > 0.0) || !std::isfinite(d)) {
        ++result.invalid_disparity;
        continue;
      }
      const double z = fb / d;
      const Eigen::Vector3d p((u - camera.cx) * z / camera.fx, (v - camera.cy) * z / camera.fy, z);
      if (!p.allFinite()) {
        ++result.invalid_disparity;
        continue;
      }
      const double range = p.norm();
      if (range < o.min_range_m) {
        ++result.too_near;
        continue;
      }
      if (range > o.max_range_m) {
        ++result.too_far;
        continue;
      }
      organised[static_cast<std::size_t>(v) * cols + u] = p;
      ++valid;
    }
  }

  const Eigen::Matrix3d R = T_body_sensor.linear();
  const int s = o.normal_step_px;
  auto at = [&](int u, int v) -> const Eigen::Vector3d* {
    if (u < 0 || v < 0 || u >= cols || v >= rows) return nullptr;
    const Eigen::Vector3d& q = organised[static_cast<std::size_t>(v) * cols + u];
    return std::isnan(q.z()) ? nullptr : &q;
  };
  registration::PointCloud& cloud = result.cloud;
  // Sized once: grown point by point, a KITTI frame's 260 000 covariances were copied and
  // faulted in again at every doubling (docs/benchmarks.md, "Figures behind the frame pipeline's
  // code").
  cloud.points.reserve(valid);
  cloud.covariances.reserve(valid);
  if (o.compute_normals) cloud.normals.reserve(valid);
  // Each pixel's point in `cloud` (-1: none), for the fill below.
  std::vector<int> point_of(o.fill_spacing_m > 0.0 ? organised.size() : 0, -1);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) {
      const Eigen::Vector3d* p = at(u, v);
      if (p == nullptr) continue;
      Eigen::Vector3d normal_camera = Eigen::Vector3d::Zero();
      if (o.compute_normals) {
        // Central difference where both neighbours are on the same surface, else one-sided.
        const double jump = o.normal_max_depth_jump * p->z() * s;
        auto neighbour = [&](int du, int dv) -> const Eigen::Vector3d* {
          const Eigen::Vector3d* q = at(u + du, v + dv);
          return q != nullptr && std::abs(q->z() - p->z()) <= jump ? q : nullptr;
        };
        auto tangent = [&](int du, int dv, Eigen::Vector3d* t) {
          const Eigen::Vector3d* a = neighbour(du, dv);
          const Eigen::Vector3d* b = neighbour(-du, -dv);
          if (a != nullptr && b != nullptr)
            *t = *a - *b;
          else if (a != nullptr)
            *t = *a - *p;
          else if (b != nullptr)
            *t = *p - *b;
          else
            return false;
          return true;
        };
        Eigen::Vector3d tu, tv;
        if (tangent(s, 0, &tu) && tangent(0, s, &tv)) normal_camera = tu.cross(tv);
        const double norm = normal_camera.norm();
        if (!(norm > 0.0) || !std::isfinite(norm)) {
          ++result.no_normal;
          continue;
        }
        normal_camera /= norm;
        if (normal_camera.dot(*p) > 0.0) normal_camera = -normal_camera;  // face the camera
      }
      if (!point_of.empty())
        point_of[static_cast<std::size_t>(v) * cols + u] = static_cast<int>(cloud.points.size());
      cloud.points.push_back(T_body_sensor * *p);
      cloud.covariances.push_back(
          R * PointCovariance(*p, camera, o.disparity_sigma_px, o.pixel_sigma_px) * R.transpose());
      if (o.compute_normals) cloud.normals.push_back(R * normal_camera);
    }
  }
  if (!point_of.empty()) {
    FillBetweenPixels(organised, point_of, cols, cloud, camera, T_body_sensor, o, &result.fill);
  }
  result.spacing_m = PixelSpacing(organised, rows, cols, valid);
  result.merged = VoxelDownsample(&cloud, o.voxel_size_m);
  result.points_ms = MsSince(start);
  return result;
}

StereoPointsResult ComputePoints(const cv::Mat& left, const cv::Mat& right,
                                 const StereoCamera& camera, const Eigen::Isometry3d& T_body_sensor,
                                 const StereoOptions& options) {
  DisparityResult disparity = ComputeDisparity(left, right, options);
  if (disparity.status != StereoStatus::kOk) {
    StereoPointsResult result;
    result.status = disparity.status;
    result.message = disparity.message;
    return result;
  }
  StereoPointsResult result =
      DisparityToPoints(disparity.disparity, camera, T_body_sensor, options);
  result.disparity = disparity.disparity;
  result.disparity_ms = disparity.time_ms;
  return result;
}

std::size_t VoxelDownsample(registration::PointCloud* cloud, double voxel_size_m) {
  if (!(voxel_size_m > 0.0) || cloud->empty()) return 0;
  const bool has_cov = cloud->HasCovariances();
  const bool has_normals = cloud->HasNormals();
  struct Accumulator {
    Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  // Σ Σᵢ⁻¹ (or count·I)
    Eigen::Vector3d weighted = Eigen::Vector3d::Zero();     // Σ Σᵢ⁻¹ pᵢ (or Σ pᵢ)
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    std::size_t count = 0;
  };
  registration::VoxelGrid grid(voxel_size_m, cloud->size() / 4 + 1);
  std::vector<Accumulator> voxels;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const Eigen::Vector3d& p = cloud->points[i];
    const std::size_t id = grid.Insert(p);
    if (id == voxels.size()) voxels.emplace_back();
    Accumulator& a = voxels[id];
    Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
    if (has_cov) {
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(cloud->covariances[i]);
      if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
        info = ldlt.solve(Eigen::Matrix3d::Identity());
      }
      if (!info.allFinite()) info = Eigen::Matrix3d::Identity() / cloud->covariances[i].trace();
    }
    a.information += info;
    a.weighted += info * p;
    if (has_normals) a.normal += cloud->normals[i];
    ++a.count;
  }
  registration::PointCloud out;
  out.points.reserve(voxels.size());
  for (const Accumulator& a : voxels) {
    const Eigen::Matrix3d cov = a.information.inverse();
    out.points.push_back(cov * a.weighted);
    if (has_cov) out.covariances.push_back(cov);
    if (has_normals) {
      const double n = a.normal.norm();
      out.normals.push_back(n > 0 ? Eigen::Vector3d(a.normal / n) : Eigen::Vector3d::UnitZ());
    }
  }
  const std::size_t merged = cloud->size() - out.size();
  out.chain_ids.clear();
  *cloud = std::move(out);
  return merged;
}

}  // namespace rovermap::stereo
