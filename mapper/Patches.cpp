#include "mapper/Patches.hpp"

#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace rovermap::mapper {
namespace {

constexpr double kBinM = 0.25;

// Two signed bin indices in one key (unsigned: shifting a negative value is undefined).
std::uint64_t Key(std::int64_t col, std::int64_t row) {
  return (static_cast<std::uint64_t>(col) << 32) ^ (static_cast<std::uint64_t>(row) & 0xffffffffu);
}

}  // namespace

FrameBins BinFrame(const registration::PointCloud& points_body,
                   const std::vector<unsigned char>& keep) {
  std::unordered_map<std::uint64_t, std::size_t> index;
  FrameBins bins;
  const bool masked = keep.size() == points_body.size();
  for (std::size_t i = 0; i < points_body.size(); ++i) {
    if (masked && keep[i] == 0) continue;
    const Eigen::Vector3d& p = points_body.points[i];
    if (!p.allFinite()) continue;
    const auto col = static_cast<std::int64_t>(std::floor(p.x() / kBinM));
    const auto row = static_cast<std::int64_t>(std::floor(p.y() / kBinM));
    const auto [it, inserted] = index.emplace(Key(col, row), bins.sum.size());
    if (inserted) {
      bins.sum.push_back(Eigen::Vector3d::Zero());
      bins.count.push_back(0);
    }
    bins.sum[it->second] += p;
    ++bins.count[it->second];
  }
  return bins;
}

std::size_t NearestPose(const std::vector<Eigen::Isometry3d>& poses,
                        const Eigen::Vector2d& centre) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    if ((poses[k].translation().head<2>() - centre).norm() <
        (poses[best].translation().head<2>() - centre).norm())
      best = k;
  }
  return best;
}

void PatchAccumulator::Add(std::size_t frame, const Eigen::Isometry3d& T_world_body,
                           const FrameBins& bins) {
  Placed placed;
  placed.frame = frame;
  placed.count = bins.count;
  placed.centroid.reserve(bins.sum.size());
  for (std::size_t b = 0; b < bins.sum.size(); ++b)
    placed.centroid.push_back(T_world_body * (bins.sum[b] / static_cast<double>(bins.count[b])));
  frames_.push_back(std::move(placed));
}

std::size_t PatchAccumulator::Advance(std::size_t frame, const Eigen::Isometry3d& T_world_body,
                                      const FrameBins& bins, double window_m) {
  const Eigen::Vector3d position = T_world_body.translation();
  path_m_.push_back(path_m_.empty() ? 0.0 : path_m_.back() + (position - last_position_).norm());
  last_position_ = position;
  Add(frame, T_world_body, bins);
  // path_m_[k] is frame (frame − (size − 1 − k))'s.
  std::size_t first = path_m_.size() - 1;
  while (first > 0 && path_m_.back() - path_m_[first - 1] <= window_m) --first;
  const std::size_t first_frame = frame - (path_m_.size() - 1 - first);
  DropBefore(first_frame);
  return first_frame;
}

void PatchAccumulator::DropBefore(std::size_t frame) {
  while (!frames_.empty() && frames_.front().frame < frame) frames_.pop_front();
}

std::vector<Post> PatchAccumulator::Window(std::size_t first, std::size_t last, double spacing_m,
                                           std::size_t min_points) const {
  std::unordered_map<std::uint64_t, std::size_t> index;
  std::vector<Eigen::Vector3d> sum;
  std::vector<std::size_t> count;
  for (const Placed& f : frames_) {
    if (f.frame < first || f.frame > last) continue;
    for (std::size_t b = 0; b < f.centroid.size(); ++b) {
      const Eigen::Vector3d& c = f.centroid[b];
      const auto col = static_cast<std::int64_t>(std::lround(c.x() / spacing_m));
      const auto row = static_cast<std::int64_t>(std::lround(c.y() / spacing_m));
      const auto [it, inserted] = index.emplace(Key(col, row), sum.size());
      if (inserted) {
        sum.push_back(Eigen::Vector3d::Zero());
        count.push_back(0);
      }
      sum[it->second] += static_cast<double>(f.count[b]) * c;
      count[it->second] += f.count[b];
    }
  }
  std::vector<Post> posts;
  for (std::size_t k = 0; k < sum.size(); ++k) {
    if (count[k] < min_points) continue;
    posts.push_back({sum[k] / static_cast<double>(count[k]), count[k]});
  }
  return posts;
}

}  // namespace rovermap::mapper
