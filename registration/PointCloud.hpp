#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace rovermap::registration {

/// A set of 3-D points with optional per-point attributes.
///
/// Optional attributes are either empty or exactly as long as `points`.
struct PointCloud {
  std::vector<Eigen::Vector3d> points;       ///< [m]
  std::vector<Eigen::Vector3d> normals;      ///< unit surface normals (optional)
  std::vector<Eigen::Matrix3d> covariances;  ///< per-point covariance [m^2] (optional)
  /// Chain index per point for curves (optional): consecutive points with the same
  /// chain id are neighbours along a curve.
  std::vector<int> chain_ids;

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool HasNormals() const { return !normals.empty() && normals.size() == points.size(); }
  bool HasCovariances() const {
    return !covariances.empty() && covariances.size() == points.size();
  }
  bool HasChains() const { return !chain_ids.empty() && chain_ids.size() == points.size(); }
};

}  // namespace rovermap::registration
