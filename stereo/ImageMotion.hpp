#pragma once
// The increment between two stereo frames as the images see it: corners of the previous left
// image with their stereo depth, tracked into the current left image (KLT), the motion from
// their reprojections (PnP with RANSAC, then Gauss-Newton on the inliers) and its information.
// A check of the registration against the images (docs/replay.md, step 5b): pixels hold the
// rotation to a fraction of a pixel at any range, where a far stereo point's depth is uncertain
// by decimetres, so the images know the heading better than the points do.

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stereo/Stereo.hpp"

namespace rovermap::stereo {

struct ImageMotionOptions {
  int max_corners = 1500;            ///< corners detected per frame [count]
  double corner_quality = 0.01;      ///< goodFeaturesToTrack quality level [ratio]
  double corner_spacing_px = 8.0;    ///< least distance between corners [px]
  int window_px = 21;                ///< KLT window edge [px]
  int pyramid_levels = 3;            ///< KLT pyramid levels [count]
  double max_range_m = 40.0;         ///< corners farther than this are not used [m]
  double ransac_threshold_px = 1.0;  ///< PnP RANSAC reprojection threshold [px]
  int min_inliers = 30;              ///< fewer = no estimate [count]
  double pixel_sigma_px = 0.3;       ///< a tracked corner's error per axis [px]
  double disparity_sigma_px = 0.3;   ///< its stereo match's disparity error [px]
};

/// One frame's corners with their stereo depth (camera frame, OpenCV axes) and covariances,
/// and the grey left image they will be tracked from.
struct ImageLandmarks {
  std::vector<cv::Point2f> pixels;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Matrix3d> covariances;
  cv::Mat left;
  bool empty() const { return pixels.empty(); }
};

/// Corners of `left` matched into `right` by KLT along the row (rectified pair): a match must
/// stay within a pixel of its row and have a positive disparity. Never throws; empty images
/// give no landmarks.
ImageLandmarks DetectLandmarks(const cv::Mat& left, const cv::Mat& right,
                               const StereoCamera& camera, const ImageMotionOptions& options);

struct ImageMotion {
  bool ok = false;
  /// T_previous_current of the camera (current camera points into the previous camera frame).
  Eigen::Isometry3d T_previous_current = Eigen::Isometry3d::Identity();
  /// Information of T_previous_current for a left perturbation [rx ry rz (rad) tx ty tz (m)] in
  /// the previous camera frame: Σ Jᵀ (σ_px² I + J_X Σ_X J_Xᵀ)⁻¹ J over the inliers, the
  /// landmarks' depth errors carried into their reprojections.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  int tracked = 0;  ///< landmarks tracked into the current image [count]
  int inliers = 0;  ///< kept by RANSAC and the final residual test [count]
  double rms_px = 0.0;
  /// Σ rᵀ W r / (2·inliers − 6) at the solution: 1 when the pixel and disparity σ of the
  /// options describe the residuals.
  double variance_factor = 0.0;
  std::string message;  ///< why not ok
};

/// The camera's motion from `previous`'s landmarks to `current_left`. Never throws.
ImageMotion EstimateImageMotion(const ImageLandmarks& previous, const cv::Mat& current_left,
                                const StereoCamera& camera, const ImageMotionOptions& options);

}  // namespace rovermap::stereo
