#include "dem/OctoMapFusion.hpp"

#include <octomap/AbstractOcTree.h>

#include <cmath>
#include <cstdint>
#include <istream>
#include <memory>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "dem/OcTreeBytes.hpp"
#include "dem/QuietStderr.hpp"

namespace rovermap::dem {
namespace {

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
  tree_ = std::make_unique<octomap::OcTree>(options_.resolution_m);
  tree_->setProbHit(options_.prob_hit);
  tree_->setProbMiss(options_.prob_miss);
}

OctoMapFrameStats OctoMapFusion::InsertFrame(const std::vector<Eigen::Vector3d>& points_world,
                                             const Eigen::Vector3d& sensor_origin_world) {
  OctoMapFrameStats stats;
  stats.points = points_world.size();
  if (!tree_ || !sensor_origin_world.allFinite()) {
    stats.skipped = true;
    return stats;
  }
  octomap::Pointcloud cloud;
  cloud.reserve(points_world.size());
  for (const Eigen::Vector3d& p : points_world) {
    if (!p.allFinite()) {
      ++stats.dropped_nonfinite;
      continue;
    }
    cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                    static_cast<float>(p.z()));
  }
  stats.inserted = cloud.size();
  const octomap::point3d origin(static_cast<float>(sensor_origin_world.x()),
                                static_cast<float>(sensor_origin_world.y()),
                                static_cast<float>(sensor_origin_world.z()));
  const double max_range = options_.max_range_m > 0.0 ? options_.max_range_m : -1.0;
  // Discretized: endpoints sharing a voxel cast one ray; lazy: inner nodes once, below.
  tree_->insertPointCloud(cloud, origin, max_range, /*lazy_eval=*/true, /*discretize=*/true);
  // The inner nodes (and pruning) only matter to readers, and updating them walks the whole
  // tree: once per frame made a frame's cost grow with the map (bench_replay, 300-frame loop).
  // Every kInnerUpdateFrames frames bounds the unpruned memory; tree() does the rest.
  constexpr int kInnerUpdateFrames = 50;
  inner_stale_ = true;
  if (++frames_since_update_ >= kInnerUpdateFrames) UpdateInner();
  return stats;
}

void OctoMapFusion::UpdateInner() const {
  if (tree_ && inner_stale_) tree_->updateInnerOccupancy();
  inner_stale_ = false;
  frames_since_update_ = 0;
}

bool OctoMapFusion::Save(std::ostream& out) const {
  const std::int32_t schedule[2] = {frames_since_update_, inner_stale_ ? 1 : 0};
  out.write(reinterpret_cast<const char*>(schedule), sizeof(schedule));
  if (tree_) {
    const std::string bytes = FullOcTreeBytes(*tree_);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  return static_cast<bool>(out);
}

void OctoMapFusion::Restore(std::istream& in) {
  std::int32_t schedule[2] = {0, 0};
  in.read(reinterpret_cast<char*>(schedule), sizeof(schedule));
  if (!in) throw std::runtime_error("OctoMap state: truncated");
  if (options_.enabled) {
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
    read.release();
    tree_.reset(tree);
    // .ot keeps the log-odds, not the sensor model.
    tree_->setProbHit(options_.prob_hit);
    tree_->setProbMiss(options_.prob_miss);
  }
  frames_since_update_ = schedule[0];
  inner_stale_ = schedule[1] != 0;
}

const octomap::OcTree* OctoMapFusion::tree() const {
  UpdateInner();
  return tree_.get();
}

}  // namespace rovermap::dem
