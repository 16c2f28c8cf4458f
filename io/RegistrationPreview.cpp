#include "io/RegistrationPreview.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {
namespace {

// Orthographic view of the target's principal plane: the mean and two largest axes.
struct View {
  Eigen::Vector3d center;
  Eigen::Matrix<double, 2, 3> axes;
  double scale = 1.0;  // px per metre
  int size = 600;
  cv::Point Project(const Eigen::Vector3d& p) const {
    const Eigen::Vector2d uv = axes * (p - center) * scale;
    return {static_cast<int>(size / 2 + uv.x()), static_cast<int>(size / 2 - uv.y())};
  }
};

View MakeView(const registration::PointCloud& target, int size) {
  View v;
  v.size = size;
  v.center.setZero();
  for (const auto& p : target.points) v.center += p;
  v.center /= static_cast<double>(target.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : target.points) cov += (p - v.center) * (p - v.center).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  v.axes.row(0) = eig.eigenvectors().col(2).transpose();
  v.axes.row(1) = eig.eigenvectors().col(1).transpose();
  double extent = 1e-9;
  for (const auto& p : target.points) extent = std::max(extent, (v.axes * (p - v.center)).cwiseAbs().maxCoeff());
  v.scale = 0.42 * size / extent;  // leaves a margin for the moved source
  return v;
}

void DrawCloud(cv::Mat& img, const View& view, const registration::PointCloud& cloud,
               const Eigen::Isometry3d& T, const cv::Vec3b& colour) {
  // At most ~60k dots per cloud keeps large clouds legible and fast.
  const std::size_t step = std::max<std::size_t>(1, cloud.size() / 60000);
  for (std::size_t i = 0; i < cloud.size(); i += step) {
    const cv::Point px = view.Project(T * cloud.points[i]);
    if (px.x >= 0 && px.y >= 0 && px.x < img.cols && px.y < img.rows) img.at<cv::Vec3b>(px) = colour;
  }
}

}  // namespace

void WriteRegistrationPreview(const std::filesystem::path& path,
                              const registration::PointCloud& source,
                              const registration::PointCloud& target,
                              const Eigen::Isometry3d& T_init, const Eigen::Isometry3d& T_final,
                              const PreviewOptions& options) {
  if (source.empty() || target.empty())
    throw std::invalid_argument("WriteRegistrationPreview: empty cloud");
  const int n = options.panel_size_px, header = 36;
  cv::Mat img(n + header, 2 * n, CV_8UC3, cv::Scalar(255, 255, 255));
  const View view = MakeView(target, n);
  const cv::Vec3b blue(200, 110, 30), orange(20, 120, 240);  // BGR
  const Eigen::Isometry3d transforms[2] = {T_init, T_final};
  const char* labels[2] = {"initial", "registered"};
  for (int k = 0; k < 2; ++k) {
    cv::Mat panel = img(cv::Rect(k * n, header, n, n));
    DrawCloud(panel, view, target, Eigen::Isometry3d::Identity(), blue);
    DrawCloud(panel, view, source, transforms[k], orange);
    cv::putText(panel, labels[k], {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(0, 0, 0), 2);
    cv::rectangle(img, cv::Rect(k * n, header, n, n), cv::Scalar(160, 160, 160), 1);
  }
  const std::string title =
      (options.title.empty() ? std::string("registration") : options.title) +
      "   (blue: target, orange: source)";
  cv::putText(img, title, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1);
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png)) throw IoError(path.string() + ": PNG encoding failed");
  WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

}  // namespace rovermap::io
