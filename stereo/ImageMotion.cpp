#include "stereo/ImageMotion.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace rovermap::stereo {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

cv::Mat Grey(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Isometry3d ExpLeft(const Vector6d& delta) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  const double angle = delta.head<3>().norm();
  if (angle > 0.0)
    D.linear() = Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
  D.translation() = delta.tail<3>();
  return D;
}

// χ² with 2 degrees of freedom at 99.9 %: a tracked corner beyond it is not the landmark.
constexpr double kResidualGate = 13.8;
constexpr int kGaussNewtonIterations = 8;

// One landmark's reprojection in the current image at T (= T_previous_current), its Jacobian
// for a left perturbation of T, and the inverse of its covariance.
struct Reprojection {
  Eigen::Vector2d residual;
  Eigen::Matrix<double, 2, 6> J;
  Eigen::Matrix2d weight;
  bool valid = false;
};

Reprojection Reproject(const Eigen::Vector3d& X_p, const Eigen::Matrix3d& cov_p,
                       const cv::Point2f& observed, const Eigen::Isometry3d& T,
                       const StereoCamera& c, double pixel_variance) {
  Reprojection r;
  const Eigen::Matrix3d Rt = T.linear().transpose();
  const Eigen::Vector3d X_c = Rt * (X_p - T.translation());
  if (!(X_c.z() > 1e-3)) return r;
  const double iz = 1.0 / X_c.z();
  Eigen::Matrix<double, 2, 3> Jpi;
  Jpi << c.fx * iz, 0, -c.fx * X_c.x() * iz * iz, 0, c.fy * iz, -c.fy * X_c.y() * iz * iz;
  r.residual << observed.x - (c.fx * X_c.x() * iz + c.cx),
      observed.y - (c.fy * X_c.y() * iz + c.cy);
  // X_c(δ) = Rᵀ (Exp(−δ) X_p − t) ≈ X_c + Rᵀ ([X_p]× δr − δt).
  Eigen::Matrix<double, 3, 6> dX;
  dX.leftCols<3>() = Rt * Hat(X_p);
  dX.rightCols<3>() = -Rt;
  r.J = Jpi * dX;
  const Eigen::Matrix<double, 2, 3> JX = Jpi * Rt;
  const Eigen::Matrix2d cov =
      pixel_variance * Eigen::Matrix2d::Identity() + JX * cov_p * JX.transpose();
  r.weight = cov.inverse();
  r.valid = r.weight.allFinite();
  return r;
}

}  // namespace

ImageLandmarks DetectLandmarks(const cv::Mat& left_in, const cv::Mat& right_in,
                               const StereoCamera& camera, const ImageMotionOptions& options) {
  ImageLandmarks out;
  if (left_in.empty() || right_in.empty() || left_in.size() != right_in.size()) return out;
  const cv::Mat left = Grey(left_in);
  const cv::Mat right = Grey(right_in);
  out.left = left.clone();
  std::vector<cv::Point2f> corners, in_right;
  cv::goodFeaturesToTrack(left, corners, options.max_corners, options.corner_quality,
                          options.corner_spacing_px);
  if (corners.empty()) return out;
  std::vector<unsigned char> status;
  std::vector<float> error;
  const cv::Size window(options.window_px, options.window_px);
  cv::calcOpticalFlowPyrLK(left, right, corners, in_right, status, error, window,
                           options.pyramid_levels);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (!status[i] || std::abs(corners[i].y - in_right[i].y) > 1.0) continue;
    const double disparity = corners[i].x - in_right[i].x + camera.disparity_offset_px;
    if (!(disparity > 0.5)) continue;
    const double z = camera.fx * camera.baseline_m / disparity;
    if (!(z <= options.max_range_m)) continue;
    const Eigen::Vector3d p((corners[i].x - camera.cx) * z / camera.fx,
                            (corners[i].y - camera.cy) * z / camera.fy, z);
    out.pixels.push_back(corners[i]);
    out.points.push_back(p);
    out.covariances.push_back(
        PointCovariance(p, camera, options.disparity_sigma_px, options.pixel_sigma_px));
  }
  return out;
}

ImageMotion EstimateImageMotion(const ImageLandmarks& previous, const cv::Mat& current_left,
                                const StereoCamera& c, const ImageMotionOptions& options) {
  ImageMotion out;
  if (previous.empty() || previous.left.empty() || current_left.empty() ||
      previous.left.size() != current_left.size()) {
    out.message = "no landmarks in the previous frame";
    return out;
  }
  const cv::Mat current = Grey(current_left);
  std::vector<cv::Point2f> tracked;
  std::vector<unsigned char> status;
  std::vector<float> error;
  const cv::Size window(options.window_px, options.window_px);
  cv::calcOpticalFlowPyrLK(previous.left, current, previous.pixels, tracked, status, error, window,
                           options.pyramid_levels);
  std::vector<int> index;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (std::size_t i = 0; i < tracked.size(); ++i) {
    if (!status[i]) continue;
    index.push_back(static_cast<int>(i));
    const Eigen::Vector3d& p = previous.points[i];
    object.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                        static_cast<float>(p.z()));
    image.push_back(tracked[i]);
  }
  out.tracked = static_cast<int>(index.size());
  if (out.tracked < options.min_inliers) {
    out.message = "too few corners tracked";
    return out;
  }
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> ransac_inliers;
  if (!cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, 200,
                          static_cast<float>(options.ransac_threshold_px), 0.999, ransac_inliers) ||
      static_cast<int>(ransac_inliers.size()) < options.min_inliers) {
    out.message = "PnP found too few inliers";
    return out;
  }
  // PnP gives T_current_previous.
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  cv::cv2eigen(R_cv, R);
  cv::cv2eigen(tvec, t);
  Eigen::Isometry3d T_cp = Eigen::Isometry3d::Identity();
  T_cp.linear() = R;
  T_cp.translation() = t;
  Eigen::Isometry3d T = T_cp.inverse();

  // Gauss-Newton on the RANSAC inliers, each weighted by its reprojection's covariance; a
  // landmark whose residual leaves the χ² gate is dropped as the estimate settles.
  const double pixel_variance = options.pixel_sigma_px * options.pixel_sigma_px;
  std::vector<int> used;
  for (int k : ransac_inliers) used.push_back(index[static_cast<std::size_t>(k)]);
  Matrix6d H = Matrix6d::Zero();
  double sum_sq = 0.0;
  double sum_chi2 = 0.0;
  int kept = 0;
  for (int iteration = 0; iteration < kGaussNewtonIterations; ++iteration) {
    H.setZero();
    Vector6d g = Vector6d::Zero();
    sum_sq = 0.0;
    sum_chi2 = 0.0;
    kept = 0;
    for (int i : used) {
      const auto u = static_cast<std::size_t>(i);
      const Reprojection r =
          Reproject(previous.points[u], previous.covariances[u], tracked[u], T, c, pixel_variance);
      if (!r.valid) continue;
      const double chi2 = r.residual.dot(r.weight * r.residual);
      if (iteration > 0 && chi2 > kResidualGate) continue;
      H += r.J.transpose() * r.weight * r.J;
      g += r.J.transpose() * r.weight * r.residual;
      sum_sq += r.residual.squaredNorm();
      sum_chi2 += chi2;
      ++kept;
    }
    if (kept < options.min_inliers) {
      out.message = "too few landmarks fit the motion";
      return out;
    }
    const Eigen::LDLT<Matrix6d> ldlt(H);
    if (ldlt.info() != Eigen::Success) {
      out.message = "the landmarks do not constrain the motion";
      return out;
    }
    const Vector6d delta = ldlt.solve(g);
    if (!delta.allFinite()) {
      out.message = "the landmarks do not constrain the motion";
      return out;
    }
    T = ExpLeft(delta) * T;
    if (delta.head<3>().norm() < 1e-9 && delta.tail<3>().norm() < 1e-7) break;
  }
  out.ok = true;
  out.T_previous_current = T;
  out.information = H;
  out.inliers = kept;
  out.rms_px = std::sqrt(sum_sq / std::max(kept, 1));
  out.variance_factor = sum_chi2 / std::max(2 * kept - 6, 1);
  return out;
}

}  // namespace rovermap::stereo
