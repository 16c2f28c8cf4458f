#include "bench/StereoVo.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>

#include "io/Sequence.hpp"

namespace rovermap::bench {
namespace {

struct Landmarks {
  std::vector<cv::Point2f> left;    // pixels in the left image
  std::vector<cv::Point3f> points;  // camera frame [m]
};

// Good features of the left image with a disparity from KLT into the right image (rectified:
// the match must stay on its row and lie to the left).
Landmarks Triangulate(const cv::Mat& left, const cv::Mat& right, const io::CameraModel& c) {
  std::vector<cv::Point2f> corners, in_right;
  cv::goodFeaturesToTrack(left, corners, 2000, 0.01, 8);
  Landmarks out;
  if (corners.empty()) return out;
  std::vector<unsigned char> status;
  std::vector<float> error;
  cv::calcOpticalFlowPyrLK(left, right, corners, in_right, status, error, cv::Size(21, 21), 3);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const double disparity = corners[i].x - in_right[i].x;
    if (!status[i] || std::abs(corners[i].y - in_right[i].y) > 1.0 || disparity < 1.0) continue;
    const double z = c.fx * c.baseline_m / disparity;
    if (z > 40.0) continue;
    out.left.push_back(corners[i]);
    out.points.emplace_back(static_cast<float>((corners[i].x - c.cx) * z / c.fx),
                            static_cast<float>((corners[i].y - c.cy) * z / c.fy),
                            static_cast<float>(z));
  }
  return out;
}

}  // namespace

std::vector<Eigen::Isometry3d> StereoVisualOdometry(const std::filesystem::path& sequence_dir,
                                                    const Eigen::Isometry3d& T_world_body0,
                                                    std::size_t max_frames) {
  io::SequenceReader reader(sequence_dir);
  const io::SequenceInfo& info = reader.info();
  if (info.sensor_type != io::SensorType::kStereo || !info.camera)
    throw std::invalid_argument("visual odometry needs a stereo sequence");
  const io::CameraModel& c = *info.camera;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const Eigen::Isometry3d& T_body_cam = info.T_body_sensor;

  std::vector<Eigen::Isometry3d> poses;
  Eigen::Isometry3d last_step = Eigen::Isometry3d::Identity();  // T_prev_curr, camera frame
  Landmarks previous;
  cv::Mat previous_left;
  io::Frame frame;
  while ((max_frames == 0 || poses.size() < max_frames) && reader.Next(&frame)) {
    if (poses.empty()) {
      poses.push_back(T_world_body0);
    } else {
      std::vector<cv::Point2f> tracked;
      std::vector<unsigned char> status;
      std::vector<float> error;
      std::vector<cv::Point3f> object;
      std::vector<cv::Point2f> image;
      if (!previous.left.empty()) {
        cv::calcOpticalFlowPyrLK(previous_left, frame.left, previous.left, tracked, status, error,
                                 cv::Size(21, 21), 3);
        for (std::size_t i = 0; i < tracked.size(); ++i) {
          if (!status[i]) continue;
          object.push_back(previous.points[i]);
          image.push_back(tracked[i]);
        }
      }
      cv::Mat rvec, tvec;
      std::vector<int> inliers;
      if (object.size() >= 12 &&
          cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, 200, 1.0, 0.999,
                             inliers) &&
          inliers.size() >= 12) {
        // PnP gives T_curr_prev (points of the previous camera frame into the current one).
        cv::Mat R;
        cv::Rodrigues(rvec, R);
        Eigen::Matrix3d r;
        Eigen::Vector3d t;
        cv::cv2eigen(R, r);
        cv::cv2eigen(tvec, t);
        Eigen::Isometry3d T_curr_prev = Eigen::Isometry3d::Identity();
        T_curr_prev.linear() = r;
        T_curr_prev.translation() = t;
        last_step = T_curr_prev.inverse();
      }
      poses.push_back(poses.back() * T_body_cam * last_step * T_body_cam.inverse());
    }
    previous = Triangulate(frame.left, frame.right, c);
    previous_left = frame.left.clone();
  }
  return poses;
}

}  // namespace rovermap::bench
