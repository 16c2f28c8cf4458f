#pragma once
// Correlation stereo: a rectified pair -> disparity (OpenCV SGBM/BM) -> 3-D points in the body
// frame with a per-point covariance from the stereo error model, and surface normals.

#include <Eigen/Geometry>
#include <cstddef>
#include <opencv2/core.hpp>
#include <string>

#include "registration/PointCloud.hpp"
#include "stereo/StereoOptions.hpp"

namespace rovermap::stereo {

/// A rectified pair's projection: x_right = x_left − d, depth z = fx·b / (d + disparity_offset).
struct StereoCamera {
  double fx = 0.0;  ///< [px]
  double fy = 0.0;  ///< [px]
  double cx = 0.0;  ///< [px], left image
  double cy = 0.0;  ///< [px]
  double baseline_m = 0.0;
  /// cx_right − cx_left [px] (Middlebury's doffs); 0 for a pair rectified to a common cx.
  double disparity_offset_px = 0.0;
};

enum class StereoStatus {
  kOk,
  kInvalidInput,  ///< empty/mismatched images, bad camera or options (see `message`)
};

/// Disparity of the left image.
struct DisparityResult {
  StereoStatus status = StereoStatus::kOk;
  std::string message;
  cv::Mat disparity;        ///< CV_32F [px], NaN where no valid match
  std::size_t valid = 0;    ///< pixels with a disparity [count]
  std::size_t invalid = 0;  ///< pixels without (filtered, occluded, untextured) [count]
  double time_ms = 0.0;
};

/// Points of one stereo frame.
struct StereoPointsResult {
  StereoStatus status = StereoStatus::kOk;
  std::string message;
  /// Body-frame points with covariances [m²] (and normals when options.compute_normals).
  registration::PointCloud cloud;
  /// Body-frame points between neighbouring pixels for the DEM (options.fill_spacing_m), with
  /// covariances and (with normals) the nearer pixel's normal; not in `cloud`.
  registration::PointCloud fill;
  cv::Mat disparity;       ///< the disparity used (CV_32F, NaN = invalid), when computed here
  std::size_t pixels = 0;  ///< pixels examined [count]
  std::size_t invalid_disparity = 0;  ///< no match, or non-positive d + offset [count]
  std::size_t too_near = 0;           ///< range < min_range_m [count]
  std::size_t too_far = 0;            ///< range > max_range_m [count]
  std::size_t no_normal = 0;          ///< dropped: no neighbours for a normal [count]
  std::size_t merged = 0;             ///< points merged away by voxel downsampling [count]
  /// Median distance from a point to the nearest point of its 8 neighbouring pixels, over an
  /// even sample of at most 16 384 points: the spacing a k-d tree would measure, without one
  /// [m]; 0 when no point has a neighbour.
  double spacing_m = 0.0;
  double disparity_ms = 0.0;
  double points_ms = 0.0;
};

/// Checks options that OpenCV would otherwise assert on; empty string when usable, else why.
/// (ComputeDisparity also needs num_disparities resolved: > 0.)
std::string CheckOptions(const StereoOptions& options);

/// The disparity search range for a camera at `T_body_sensor` over level ground (the body's
/// z = 0 plane): the largest disparity of the ground any pixel of a width × height image sees,
/// with objects allowed 20 % nearer than the ground (rocks, relief) but none nearer than
/// `options.min_range_m`; rounded up to a multiple of 16, at least 16, at most 256 and below
/// width − block_size. A camera that sees no ground gets the disparity of min_range_m (capped
/// likewise). Never throws.
int DisparitiesForGround(const StereoCamera& camera, int width, int height,
                         const Eigen::Isometry3d& T_body_sensor, const StereoOptions& options);

/// `options` with num_disparities = DisparitiesForGround(...) when it is 0 (unchanged otherwise).
StereoOptions ResolveDisparities(const StereoOptions& options, const StereoCamera& camera, int width,
                                 int height, const Eigen::Isometry3d& T_body_sensor);

/// Left disparity of a rectified pair (8-bit grey, or BGR converted to grey), with the
/// matcher, left-right check, uniqueness and speckle filter of `options`. Never throws.
DisparityResult ComputeDisparity(const cv::Mat& left, const cv::Mat& right,
                                 const StereoOptions& options);

/// Stereo error model: covariance [m²] of a point `p_camera` (camera frame, OpenCV axes)
/// triangulated from pixel (u, v) and disparity d, by first-order propagation of σ_u = σ_v =
/// pixel_sigma_px and σ_d = disparity_sigma_px through x = (u−cx)·z/fx, y = (v−cy)·z/fy,
/// z = fx·b/d. Depth variance is (z²·σ_d/(fx·b))². Never throws.
Eigen::Matrix3d PointCovariance(const Eigen::Vector3d& p_camera, const StereoCamera& camera,
                                double disparity_sigma_px, double pixel_sigma_px);

/// Disparity (CV_32F, NaN or <= −offset = invalid) -> body-frame points: triangulation, range
/// limits, covariances (rotated into the body frame), normals, optional voxel downsampling.
/// Non-finite results are counted as invalid_disparity. Never throws.
StereoPointsResult DisparityToPoints(const cv::Mat& disparity, const StereoCamera& camera,
                                     const Eigen::Isometry3d& T_body_sensor,
                                     const StereoOptions& options);

/// ComputeDisparity then DisparityToPoints. Never throws.
StereoPointsResult ComputePoints(const cv::Mat& left, const cv::Mat& right,
                                 const StereoCamera& camera, const Eigen::Isometry3d& T_body_sensor,
                                 const StereoOptions& options);

/// Voxel downsampling: one point per occupied cube of edge `voxel_size_m`, the
/// information-weighted mean of its points (inverse-covariance weights; plain mean without
/// covariances) with the fused covariance (Σ Σᵢ⁻¹)⁻¹ and the normalised sum of the normals.
/// Output order: voxels in order of their first point. Returns the number of points merged
/// away. voxel_size_m <= 0 leaves the cloud unchanged. Never throws.
std::size_t VoxelDownsample(registration::PointCloud* cloud, double voxel_size_m);

const char* ToString(Algorithm algorithm);

}  // namespace rovermap::stereo
