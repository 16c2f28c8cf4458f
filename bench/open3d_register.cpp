// open3d_register: Open3D's point-to-plane ICP as a user runs it once, for bench_cold: read two
// PLY files with Open3D's reader, estimate the target's normals (10 nearest neighbours) and run
// RegistrationICP from the given initial estimate with a fixed correspondence gate. Prints the
// 4×4 T_target_source, row-major, on one line. Linked against Open3D alone, so that its start-up
// is Open3D's, not rovermap's.
//
//   open3d_register SOURCE.ply TARGET.ply --init "rx ry rz tx ty tz" --gate METRES

#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

int main(int argc, char** argv) {
  std::string source_path, target_path, init_text;
  double gate = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--init" && i + 1 < argc) {
      init_text = argv[++i];
    } else if (arg == "--gate" && i + 1 < argc) {
      gate = std::stod(argv[++i]);
    } else if (source_path.empty()) {
      source_path = arg;
    } else if (target_path.empty()) {
      target_path = arg;
    } else {
      std::cerr << "open3d_register: unexpected argument '" << arg << "'\n";
      return 2;
    }
  }
  std::istringstream init_stream(init_text);
  Eigen::Matrix<double, 6, 1> x;
  for (int k = 0; k < 6; ++k) init_stream >> x(k);
  if (source_path.empty() || target_path.empty() || !init_stream || !(gate > 0.0)) {
    std::cerr << "usage: open3d_register SOURCE.ply TARGET.ply --init \"rx ry rz tx ty tz\" "
                 "--gate METRES\n";
    return 2;
  }
  open3d::geometry::PointCloud source, target;
  if (!open3d::io::ReadPointCloud(source_path, source) ||
      !open3d::io::ReadPointCloud(target_path, target)) {
    std::cerr << "open3d_register: cannot read " << source_path << " or " << target_path << "\n";
    return 1;
  }
  Eigen::Matrix4d init = Eigen::Matrix4d::Identity();
  const double angle = x.head<3>().norm();
  if (angle > 0.0)
    init.topLeftCorner<3, 3>() = Eigen::AngleAxisd(angle, x.head<3>() / angle).toRotationMatrix();
  init.topRightCorner<3, 1>() = x.tail<3>();

  namespace o3r = open3d::pipelines::registration;
  target.EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(10));
  const o3r::RegistrationResult r =
      o3r::RegistrationICP(source, target, gate, init, o3r::TransformationEstimationPointToPlane(),
                           o3r::ICPConvergenceCriteria(1e-6, 1e-6, 100));
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col)
      std::printf("%.17g%s", r.transformation_(row, col), row == 3 && col == 3 ? "\n" : " ");
  return 0;
}
