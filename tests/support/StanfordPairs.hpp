#pragma once
// The Stanford bunny pairs' ground truth (datasets/stanford_bunny/gt_pairs.txt), shared by the
// bunny tests and the registration benchmarks.

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace rovermap::testing {

// Closest rotation (Frobenius) to a nearly orthonormal matrix, det +1.
inline Eigen::Matrix3d Orthonormalize(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) *= -1.0;
  return u * svd.matrixV().transpose();
}

// Row of gt_pairs.txt: "source target r11 r12 r13 tx r21 ... tz ...".
inline Eigen::Isometry3d ReadGroundTruth(const std::string& path, const std::string& source,
                                         const std::string& target) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    std::string s, t;
    ss >> s >> t;
    if (s != source || t != target) continue;
    Eigen::Matrix<double, 3, 4> m;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        if (!(ss >> m(r, c))) throw std::runtime_error(path + ": bad row for " + s + " " + t);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Orthonormalize(m.leftCols<3>());
    T.translation() = m.col(3);
    return T;
  }
  throw std::runtime_error(path + ": no row for " + source + " -> " + target);
}

}  // namespace rovermap::testing
