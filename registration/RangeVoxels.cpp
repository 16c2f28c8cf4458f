#include "registration/RangeVoxels.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numeric>

#include "registration/VoxelGrid.hpp"

namespace rovermap::registration {
namespace {
constexpr int kLevels = 40;  // min_edge · 2^39: far beyond any sensor's range
}  // namespace

RangeVoxels RangeVoxelDownsample(const PointCloud& cloud, const Eigen::Vector3d& origin,
                                 double angle_rad, double min_edge_m,
                                 const std::vector<unsigned char>* keep) {
  RangeVoxels out;
  const std::size_t n = cloud.size();
  if (!(angle_rad > 0.0) || !(min_edge_m > 0.0) || n == 0) {
    out.cloud = cloud;
    out.cloud.chain_ids.clear();
    out.voxel_of.resize(n);
    std::iota(out.voxel_of.begin(), out.voxel_of.end(), 0u);
    return out;
  }
  // Level of each point: the power of two nearest to angle · range / min_edge.
  std::vector<std::uint8_t> level(n);
  const double scale = angle_rad / min_edge_m;
  const auto count = static_cast<long>(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < count; ++i) {
    const double target = scale * (cloud.points[static_cast<std::size_t>(i)] - origin).norm();
    const double k = target > 1.0 ? std::round(std::log2(target)) : 0.0;
    level[static_cast<std::size_t>(i)] =
        static_cast<std::uint8_t>(std::clamp(k, 0.0, static_cast<double>(kLevels - 1)));
  }
  std::array<std::unique_ptr<VoxelGrid>, kLevels> grids;
  std::array<std::vector<std::uint32_t>, kLevels> global;  // a level's ids -> output ids
  std::vector<std::uint32_t> members;                      // points per output voxel
  std::vector<std::uint32_t> first;                        // each voxel's first point
  out.voxel_of.assign(n, RangeVoxels::kNoVoxel);
  const bool masked = keep != nullptr && keep->size() == n;
  for (std::size_t i = 0; i < n; ++i) {
    if (masked && (*keep)[i] == 0) continue;
    const int l = level[i];
    if (!grids[l]) grids[l] = std::make_unique<VoxelGrid>(min_edge_m * std::ldexp(1.0, l), n / 16);
    const std::size_t local = grids[l]->Insert(cloud.points[i]);
    if (local == global[l].size()) {
      global[l].push_back(static_cast<std::uint32_t>(members.size()));
      members.push_back(0);
      first.push_back(static_cast<std::uint32_t>(i));
    }
    const std::uint32_t id = global[l][local];
    out.voxel_of[i] = id;
    ++members[id];
  }
  const std::size_t voxels = members.size();
  const bool has_cov = cloud.HasCovariances();
  const bool has_normals = cloud.HasNormals();
  PointCloud& merged = out.cloud;
  merged.points.assign(voxels, Eigen::Vector3d::Zero());
  if (has_cov) merged.covariances.assign(voxels, Eigen::Matrix3d::Zero());
  if (has_normals) merged.normals.assign(voxels, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t id = out.voxel_of[i];
    if (id == RangeVoxels::kNoVoxel) continue;
    merged.points[id] += cloud.points[i];
    if (has_cov) merged.covariances[id] += cloud.covariances[i];
    if (has_normals) merged.normals[id] += cloud.normals[i];
  }
  for (std::size_t v = 0; v < voxels; ++v) {
    const double inverse = 1.0 / static_cast<double>(members[v]);
    merged.points[v] *= inverse;
    if (has_cov) merged.covariances[v] *= inverse;
    if (has_normals) {
      const double norm = merged.normals[v].norm();
      // Opposite normals in one voxel (a thin edge) cancel: keep the first point's instead.
      merged.normals[v] =
          norm > 1e-6 ? Eigen::Vector3d(merged.normals[v] / norm) : cloud.normals[first[v]];
    }
  }
  // The scatter of a voxel's points about their mean: a merged point stands for a patch, and a
  // point of another frame anywhere on it may pair with it (the matcher's gate adds only the
  // sensor's spacing, D²/12, for that).
  if (has_cov) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t id = out.voxel_of[i];
      if (id == RangeVoxels::kNoVoxel) continue;
      const Eigen::Vector3d e = cloud.points[i] - merged.points[id];
      merged.covariances[id] += (e * e.transpose()) / static_cast<double>(members[id]);
    }
  }
  return out;
}

}  // namespace rovermap::registration
