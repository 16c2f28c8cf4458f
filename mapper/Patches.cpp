#include "mapper/Patches.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace rovermap::mapper {
namespace {

constexpr double kBinM = 0.25;
// [m] a bin's gate never narrower than this (ties, a bin of two points).
constexpr double kFloorM = 0.01;
constexpr std::size_t kNone = static_cast<std::size_t>(-1);

struct Sample {
  double z = 0.0;
  double w = 0.0;    // weight
  double var = 0.0;  // [m²] the point's own variance (0 when unknown)
  std::size_t index = 0;
};

// The weighted median of the samples' z (reorders them). Needs at least one sample.
double WeightedMedian(std::vector<Sample>* samples) {
  std::sort(samples->begin(), samples->end(),
            [](const Sample& a, const Sample& b) { return a.z < b.z; });
  double total = 0.0;
  for (const Sample& s : *samples) total += s.w;
  double run = 0.0;
  for (const Sample& s : *samples) {
    run += s.w;
    if (run >= 0.5 * total) return s.z;
  }
  return samples->back().z;
}

// Two signed bin indices in one key (unsigned: shifting a negative value is undefined).
std::uint64_t Key(std::int64_t col, std::int64_t row) {
  return (static_cast<std::uint64_t>(col) << 32) ^ (static_cast<std::uint64_t>(row) & 0xffffffffu);
}

}  // namespace

FrameBins BinFrame(const registration::PointCloud& points_body,
                   const std::vector<unsigned char>& keep) {
  const bool masked = keep.size() == points_body.size();
  const bool weighted = points_body.HasCovariances();
  // Each point's bin, then the points grouped by bin (a counting sort: linear in the points).
  std::unordered_map<std::uint64_t, std::size_t> index;
  std::vector<std::size_t> bin_of(points_body.size(), kNone);
  std::vector<std::size_t> sizes;
  for (std::size_t i = 0; i < points_body.size(); ++i) {
    if (masked && keep[i] == 0) continue;
    const Eigen::Vector3d& p = points_body.points[i];
    if (!p.allFinite()) continue;
    if (weighted && !(points_body.covariances[i](2, 2) > 0.0)) continue;
    const auto col = static_cast<std::int64_t>(std::floor(p.x() / kBinM));
    const auto row = static_cast<std::int64_t>(std::floor(p.y() / kBinM));
    const auto [it, inserted] = index.emplace(Key(col, row), sizes.size());
    if (inserted) sizes.push_back(0);
    bin_of[i] = it->second;
    ++sizes[it->second];
  }
  std::vector<std::size_t> offset(sizes.size() + 1, 0);
  for (std::size_t b = 0; b < sizes.size(); ++b) offset[b + 1] = offset[b] + sizes[b];
  std::vector<std::size_t> order(offset.back());
  std::vector<std::size_t> fill(offset.begin(), offset.end() - 1);
  for (std::size_t i = 0; i < points_body.size(); ++i)
    if (bin_of[i] != kNone) order[fill[bin_of[i]]++] = i;

  FrameBins bins;
  bins.weighted = weighted;
  std::vector<Sample> z;
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    z.clear();
    for (std::size_t k = offset[b]; k < offset[b + 1]; ++k) {
      const std::size_t i = order[k];
      const double var = weighted ? points_body.covariances[i](2, 2) : 0.0;
      z.push_back({points_body.points[i].z(), weighted ? 1.0 / var : 1.0, var, i});
    }
    const double median = WeightedMedian(&z);
    std::vector<double> deviation;
    for (const Sample& s : z) deviation.push_back(std::abs(s.z - median));
    std::nth_element(deviation.begin(), deviation.begin() + deviation.size() / 2, deviation.end());
    const double spread = 1.4826 * deviation[deviation.size() / 2];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0.0;
    std::size_t count = 0;
    for (const Sample& s : z) {
      // Within 3σ of the median, σ the bin's spread and the point's own error together.
      if (std::abs(s.z - median) > 3.0 * std::sqrt(spread * spread + s.var) + kFloorM) continue;
      sum += s.w * points_body.points[s.index];
      weight += s.w;
      ++count;
    }
    bins.mean.push_back(sum / weight);
    bins.weight.push_back(weight);
    bins.count.push_back(count);
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
  placed.weight = bins.weight;
  placed.weighted = bins.weighted;
  placed.centroid.reserve(bins.mean.size());
  for (const Eigen::Vector3d& mean : bins.mean) placed.centroid.push_back(T_world_body * mean);
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
                                           double max_sigma_m, std::size_t min_points) const {
  // Each post's bins, one per frame that saw its ground.
  std::unordered_map<std::uint64_t, std::size_t> index;
  std::vector<std::vector<std::pair<const Placed*, std::size_t>>> bins_of;
  for (const Placed& f : frames_) {
    if (f.frame < first || f.frame > last) continue;
    for (std::size_t b = 0; b < f.centroid.size(); ++b) {
      const Eigen::Vector3d& c = f.centroid[b];
      const auto col = static_cast<std::int64_t>(std::lround(c.x() / spacing_m));
      const auto row = static_cast<std::int64_t>(std::lround(c.y() / spacing_m));
      const auto [it, inserted] = index.emplace(Key(col, row), bins_of.size());
      if (inserted) bins_of.emplace_back();
      bins_of[it->second].emplace_back(&f, b);
    }
  }
  std::vector<Post> posts;
  std::vector<Sample> z;
  for (const auto& bins : bins_of) {
    Post post;
    Eigen::Vector2d xy = Eigen::Vector2d::Zero();
    double weight = 0.0;
    bool weighted = true;
    z.clear();
    for (const auto& [f, b] : bins) {
      const double w = f->weight[b];
      z.push_back({f->centroid[b].z(), w, 0.0, 0});
      xy += w * f->centroid[b].head<2>();
      weight += w;
      post.points += f->count[b];
      weighted = weighted && f->weighted;
    }
    if (post.points < min_points || !(weight > 0.0)) continue;
    if (weighted) {
      post.sigma_m = 1.0 / std::sqrt(weight);
      if (post.sigma_m > max_sigma_m) continue;
    }
    post.p << xy / weight, WeightedMedian(&z);
    posts.push_back(post);
  }
  return posts;
}

}  // namespace rovermap::mapper
