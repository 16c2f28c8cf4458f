#include "mapper/LocalMap.hpp"

#include <numeric>
#include <utility>

#include "registration/VoxelGrid.hpp"

namespace rovermap::mapper {
namespace {

std::vector<std::size_t> Sample(const std::vector<Eigen::Vector3d>& points, double voxel_m) {
  if (voxel_m > 0.0)
    return registration::VoxelSample(points, voxel_m, registration::VoxelChoice::kFirst);
  std::vector<std::size_t> all(points.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  return all;
}

void Append(registration::PointCloud* to, const registration::PointCloud& from) {
  to->points.insert(to->points.end(), from.points.begin(), from.points.end());
  to->normals.insert(to->normals.end(), from.normals.begin(), from.normals.end());
  to->covariances.insert(to->covariances.end(), from.covariances.begin(), from.covariances.end());
}

}  // namespace

registration::PointCloud TransformSubset(const registration::PointCloud& cloud,
                                         const std::vector<std::size_t>& indices,
                                         const Eigen::Isometry3d& T) {
  registration::PointCloud out;
  const Eigen::Matrix3d R = T.linear();
  const bool normals = cloud.HasNormals();
  const bool covariances = cloud.HasCovariances();
  out.points.reserve(indices.size());
  for (std::size_t i : indices) {
    out.points.push_back(T * cloud.points[i]);
    if (normals) out.normals.push_back(R * cloud.normals[i]);
    if (covariances) out.covariances.push_back(R * cloud.covariances[i] * R.transpose());
  }
  return out;
}

void LocalMap::Add(const registration::PointCloud& cloud, const Eigen::Isometry3d& T_world_body,
                   double voxel_m) {
  frames_.push_back(TransformSubset(cloud, Sample(cloud.points, voxel_m), T_world_body));
  while (frames_.size() > max_frames_) frames_.pop_front();
}

std::size_t LocalMap::points() const {
  std::size_t n = 0;
  for (const auto& f : frames_) n += f.size();
  return n;
}

std::unique_ptr<registration::IndexedCloud> LocalMap::Build(
    const Eigen::Isometry3d& T_world_ref, double voxel_m,
    const registration::RegistrationOptions& options) const {
  registration::PointCloud merged;
  // Newest first: where frames overlap, the voxel sample keeps the latest view.
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) Append(&merged, *it);
  // Attributes are kept only when every frame had them.
  if (merged.normals.size() != merged.points.size()) merged.normals.clear();
  if (merged.covariances.size() != merged.points.size()) merged.covariances.clear();
  registration::PointCloud local =
      TransformSubset(merged, Sample(merged.points, voxel_m), T_world_ref.inverse());
  return std::make_unique<registration::IndexedCloud>(std::move(local), options);
}

}  // namespace rovermap::mapper
