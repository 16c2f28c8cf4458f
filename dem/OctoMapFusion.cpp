#include "dem/OctoMapFusion.hpp"

#include <octomap/AbstractOcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <istream>
#include <memory>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dem/OcTreeBytes.hpp"
#include "dem/QuietStderr.hpp"

namespace rovermap::dem {
namespace {

constexpr char kTagsMagic[8] = {'R', 'M', 'T', 'A', 'G', 'S', '0', '1'};

void Check(bool ok, const std::string& field, const std::string& rule, double got) {
  if (ok) return;
  std::ostringstream msg;
  msg << field << ": must be " << rule << " (got " << got << ")";
  throw std::invalid_argument(msg.str());
}

}  // namespace

void Validate(const OctoMapOptions& o) {
  Check(std::isfinite(o.resolution_m) && o.resolution_m > 0.0, "resolution_m", "> 0",
        o.resolution_m);
  Check(std::isfinite(o.max_range_m) && o.max_range_m >= 0.0, "max_range_m", ">= 0", o.max_range_m);
  Check(o.prob_hit > 0.5 && o.prob_hit < 1.0, "prob_hit", "in (0.5, 1)", o.prob_hit);
  Check(o.prob_miss > 0.0 && o.prob_miss < 0.5, "prob_miss", "in (0, 0.5)", o.prob_miss);
}

OctoMapFusion::OctoMapFusion(const OctoMapOptions& options) : options_(options) {
  Validate(options_);
  if (!options_.enabled) return;
  tree_ = std::make_unique<BatchOcTree>(options_.resolution_m);
  tree_->setProbHit(options_.prob_hit);
  tree_->setProbMiss(options_.prob_miss);
}

OctoMapFrameStats OctoMapFusion::InsertFrame(const std::vector<Eigen::Vector3d>& points_world,
                                             const Eigen::Vector3d& sensor_origin_world,
                                             std::uint32_t frame) {
  OctoMapFrameStats stats;
  stats.points = points_world.size();
  if (!tree_ || !sensor_origin_world.allFinite()) {
    stats.skipped = true;
    return stats;
  }
  points_.clear();
  points_.reserve(points_world.size());
  for (const Eigen::Vector3d& p : points_world) {
    if (!p.allFinite()) {
      ++stats.dropped_nonfinite;
      continue;
    }
    points_.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                         static_cast<float>(p.z()));
  }
  const octomap::point3d origin(static_cast<float>(sensor_origin_world.x()),
                                static_cast<float>(sensor_origin_world.y()),
                                static_cast<float>(sensor_origin_world.z()));
  const double max_range = options_.max_range_m > 0.0 ? options_.max_range_m : -1.0;
  const BatchCounts counts = tree_->InsertDiscretized(points_, origin, max_range, frame);
  stats.dropped_out_of_bounds = counts.dropped_out_of_bounds;
  stats.inserted = points_.size() - counts.dropped_out_of_bounds;
  stats.free_voxels = counts.free_voxels;
  stats.occupied_voxels = counts.occupied_voxels;
  return stats;
}

bool OctoMapFusion::Save(std::ostream& out) const {
  const std::int32_t schedule[2] = {0, 0};  // inner nodes current: nothing scheduled
  out.write(reinterpret_cast<const char*>(schedule), sizeof(schedule));
  if (tree_) {
    const std::string bytes = FullOcTreeBytes(*tree_);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    // The tags, sorted so that a state saves to the same bytes whatever the hash order.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> tags(tree_->block_frames().begin(),
                                                              tree_->block_frames().end());
    std::sort(tags.begin(), tags.end());
    const std::uint64_t count = tags.size();
    out.write(kTagsMagic, sizeof(kTagsMagic));
    out.write(reinterpret_cast<const char*>(&count), sizeof(count));
    for (const auto& [block, frame] : tags) {
      out.write(reinterpret_cast<const char*>(&block), sizeof(block));
      out.write(reinterpret_cast<const char*>(&frame), sizeof(frame));
    }
  }
  return static_cast<bool>(out);
}

void OctoMapFusion::Restore(std::istream& in) {
  std::int32_t schedule[2] = {0, 0};
  in.read(reinterpret_cast<char*>(schedule), sizeof(schedule));
  if (!in) throw std::runtime_error("OctoMap state: truncated");
  if (!options_.enabled) return;
  std::unique_ptr<octomap::AbstractOcTree> read;
  {
    const QuietStderr quiet;  // liboctomap reports the read on stderr
    read.reset(octomap::AbstractOcTree::read(in));
  }
  auto* tree = dynamic_cast<octomap::OcTree*>(read.get());
  if (tree == nullptr) throw std::runtime_error("OctoMap state: not an OcTree");
  if (tree->getResolution() != options_.resolution_m) {
    throw std::runtime_error("OctoMap state: resolution differs from octomap.resolution_m");
  }
  auto restored = std::make_unique<BatchOcTree>(options_.resolution_m);
  restored->swapContent(*tree);  // the nodes move over; the batch tree keeps its buffers
  // .ot keeps the log-odds, not the sensor model.
  restored->setProbHit(options_.prob_hit);
  restored->setProbMiss(options_.prob_miss);
  // A state saved with stale inner nodes (earlier versions): the walk assumes current ones.
  if (schedule[1] != 0) restored->updateInnerOccupancy();
  // The blocks' tags; a state saved before they were kept has none.
  char magic[sizeof(kTagsMagic)] = {};
  if (in.read(magic, sizeof(magic)) && std::equal(magic, magic + sizeof(magic), kTagsMagic)) {
    std::uint64_t count = 0;
    if (!in.read(reinterpret_cast<char*>(&count), sizeof(count)))
      throw std::runtime_error("OctoMap state: truncated tags");
    BatchOcTree::BlockFrames tags;
    for (std::uint64_t i = 0; i < count; ++i) {
      std::uint64_t block = 0;
      std::uint32_t frame = 0;
      if (!in.read(reinterpret_cast<char*>(&block), sizeof(block)) ||
          !in.read(reinterpret_cast<char*>(&frame), sizeof(frame)))
        throw std::runtime_error("OctoMap state: truncated tags");
      tags.emplace(block, frame);
    }
    restored->SetBlockFrames(std::move(tags));
  }
  tree_ = std::move(restored);
}

}  // namespace rovermap::dem
