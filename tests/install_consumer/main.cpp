// An outside program built against the installed rovermap (tests/install_consumer/check.sh):
// registers a synthetic terrain patch onto the same patch moved by a known small rigid motion
// with rovermap's matcher, and exits 0 only if the motion is recovered within 2 mm and 0.05°.
#include <cmath>
#include <cstdio>
#include <rovermap/registration/Icp.hpp>

namespace reg = rovermap::registration;

namespace {

// 4 m × 4 m sampled every 5 cm: gentle undulation and three bumps, so that every direction of
// the motion is constrained (a bare plane would let the patch slide).
reg::PointCloud Terrain() {
  reg::PointCloud cloud;
  for (double x = -2.0; x <= 2.0; x += 0.05) {
    for (double y = -2.0; y <= 2.0; y += 0.05) {
      double z = 0.05 * std::sin(1.7 * x) * std::cos(1.3 * y);
      const double bumps[3][3] = {{-0.8, 0.6, 0.25}, {0.9, -0.4, 0.15}, {0.2, 1.2, 0.2}};
      for (const auto& b : bumps) {
        const double d2 = (x - b[0]) * (x - b[0]) + (y - b[1]) * (y - b[1]);
        z += b[2] * std::exp(-d2 / (2 * 0.3 * 0.3));
      }
      cloud.points.emplace_back(x, y, z);
    }
  }
  return cloud;
}

}  // namespace

int main() {
  const reg::PointCloud source = Terrain();
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() =
      Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d(0.3, -0.2, 1.0).normalized())
          .toRotationMatrix();
  truth.translation() = Eigen::Vector3d(0.06, -0.04, 0.02);
  reg::PointCloud target;
  for (const auto& p : source.points) target.points.push_back(truth * p);

  const reg::RegistrationOptions options;
  const reg::RegistrationResult result =
      reg::Register(source, target, Eigen::Isometry3d::Identity(), options);

  const Eigen::Isometry3d error = truth.inverse() * result.T_target_source;
  const double translation_m = error.translation().norm();
  const double rotation_deg = Eigen::AngleAxisd(error.linear()).angle() * 180.0 / M_PI;
  std::printf("status %s, %d iterations, error %.2e m, %.2e deg\n", reg::ToString(result.status),
              result.iterations, translation_m, rotation_deg);
  const bool ok = result.converged && translation_m < 0.002 && rotation_deg < 0.05;
  return ok ? 0 : 1;
}
