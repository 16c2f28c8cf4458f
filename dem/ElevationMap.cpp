#include "dem/ElevationMap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace rovermap::dem {
namespace {

[[noreturn]] void Invalid(const std::string& field, const std::string& rule, double got) {
  std::ostringstream msg;
  msg << field << ": must be " << rule << " (got " << got << ")";
  throw std::invalid_argument(msg.str());
}

}  // namespace

void Validate(const ElevationMapOptions& options) {
  Validate(GridGeometry{options.cell_size_m, options.tile_cells});
  if (!(options.mahalanobis_gate > 0.0) || !std::isfinite(options.mahalanobis_gate)) {
    Invalid("mahalanobis_gate", "finite and > 0", options.mahalanobis_gate);
  }
  if (!(options.default_point_stddev_m > 0.0) || !std::isfinite(options.default_point_stddev_m)) {
    Invalid("default_point_stddev_m", "finite and > 0", options.default_point_stddev_m);
  }
  if (!(options.min_point_variance_m2 >= 0.0) || !std::isfinite(options.min_point_variance_m2)) {
    Invalid("min_point_variance_m2", "finite and >= 0", options.min_point_variance_m2);
  }
  if (!std::isfinite(options.grid_rotation_rad)) {
    Invalid("grid_rotation_rad", "finite", options.grid_rotation_rad);
  }
}

Tile::Tile(int tile_cells)
    : cells(static_cast<std::size_t>(tile_cells) * static_cast<std::size_t>(tile_cells)) {}

ElevationMap::ElevationMap(const ElevationMapOptions& options)
    : options_(options),
      index_((Validate(options), GridGeometry{options.cell_size_m, options.tile_cells})),
      cos_(std::cos(options.grid_rotation_rad)),
      sin_(std::sin(options.grid_rotation_rad)) {}

Eigen::Vector2d ElevationMap::WorldToGrid(double x_m, double y_m) const {
  return {cos_ * x_m - sin_ * y_m, sin_ * x_m + cos_ * y_m};
}

Eigen::Vector2d ElevationMap::GridToWorld(const Eigen::Vector2d& grid_m) const {
  return {cos_ * grid_m.x() + sin_ * grid_m.y(), -sin_ * grid_m.x() + cos_ * grid_m.y()};
}

std::optional<CellIndex> ElevationMap::WorldToCell(double x_m, double y_m) const {
  if (options_.grid_rotation_rad == 0.0) return index_.WorldToCell(x_m, y_m);
  const Eigen::Vector2d g = WorldToGrid(x_m, y_m);
  return index_.WorldToCell(g.x(), g.y());
}

Eigen::Vector2d ElevationMap::CellCenterWorld(CellIndex cell) const {
  return GridToWorld(index_.CellCenter(cell));
}

Tile& ElevationMap::TileFor(TileIndex tile_index, FusionStats* stats) {
  if (cache_.tile != nullptr && cache_.index == tile_index) return *cache_.tile;
  auto& slot = tiles_[tile_index];
  if (!slot) {
    slot = std::make_unique<Tile>(options_.tile_cells);
    if (stats != nullptr) ++stats->new_tiles;
  }
  cache_.index = tile_index;
  cache_.tile = slot.get();
  return *slot;
}

bool ElevationMap::FuseAt(CellIndex cell, double z, double r, std::uint32_t frame,
                          FusionStats* stats) {
  Tile& tile = TileFor(index_.CellToTile(cell), stats);
  CellRecord& record = tile.cells[index_.LinearIndex(index_.CellToLocal(cell))];
  CellValue& v = record.value;
  const auto zf = static_cast<float>(z);
  if (v.count == 0) {
    v = {zf, static_cast<float>(r), zf, zf, 1, frame};
    record.start_frame = frame;
    ++tile.filled;
    bounds_.Extend(cell);
    if (stats != nullptr) ++stats->fused;
    return true;
  }
  const double h = v.elevation_m;
  const double p = v.variance_m2;
  const double d = z - h;
  const double s = p + r;
  if (d * d <= options_.mahalanobis_gate * s) {
    // Kalman update of a constant height observed directly (H = 1).
    const double k = p / s;
    v.elevation_m = static_cast<float>(h + k * d);
    v.variance_m2 = static_cast<float>((1.0 - k) * p);
    v.min_m = std::min(v.min_m, zf);
    v.max_m = std::max(v.max_m, zf);
    ++v.count;
    v.last_frame = frame;
    if (stats != nullptr) ++stats->fused;
    return true;
  }
  if (record.start_frame != frame) {  // disagrees with the map built by earlier frames
    if (stats != nullptr) ++stats->rejected_outliers;
    return false;
  }
  // Same frame, outside the gate: a vertical structure in the cell; the higher point wins.
  v.min_m = std::min(v.min_m, zf);
  v.max_m = std::max(v.max_m, zf);
  if (d < 0.0) {
    if (stats != nullptr) ++stats->below_in_frame;
    return false;
  }
  v.elevation_m = zf;
  v.variance_m2 = static_cast<float>(r);
  v.count = 1;
  v.last_frame = frame;
  if (stats != nullptr) ++stats->replaced;
  return true;
}

bool ElevationMap::FusePoint(const Eigen::Vector3d& point_world, double height_variance_m2,
                             std::uint32_t frame, FusionStats* stats) {
  if (stats != nullptr) ++stats->points;
  if (!point_world.allFinite() || !std::isfinite(height_variance_m2) || height_variance_m2 < 0.0) {
    if (stats != nullptr) ++stats->dropped_nonfinite;
    return false;
  }
  const auto cell = WorldToCell(point_world.x(), point_world.y());
  if (!cell) {
    if (stats != nullptr) ++stats->dropped_out_of_grid;
    return false;
  }
  const double r = std::max(height_variance_m2, options_.min_point_variance_m2);
  return FuseAt(*cell, point_world.z(), r, frame, stats);
}

FusionStats ElevationMap::FuseFrame(const std::vector<Eigen::Vector3d>& points_world,
                                    const std::vector<Eigen::Matrix3d>& covariances,
                                    const FrameContext& ctx) {
  FusionStats stats;
  const bool use_cov = !covariances.empty() && covariances.size() == points_world.size();
  if (!covariances.empty() && !use_cov) ++covariances_ignored_;
  const Eigen::Vector3d r3 = ctx.R_world_cov.row(2).transpose();
  const double default_var = options_.default_point_stddev_m * options_.default_point_stddev_m;

  // Pose term J Σ Jᵀ with J = (dy, −dx, 0, 0, 0, 1): only rows/cols rx, ry, tz of Σ matter.
  Eigen::Matrix3d pose_block = Eigen::Matrix3d::Zero();
  const bool use_pose = ctx.pose_covariance.has_value() && ctx.pose_covariance->allFinite();
  if (use_pose) {
    const int idx[3] = {0, 1, 5};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) pose_block(a, b) = (*ctx.pose_covariance)(idx[a], idx[b]);
  }
  const Eigen::Vector3d& c = ctx.sensor_origin_world;

  for (std::size_t k = 0; k < points_world.size(); ++k) {
    const Eigen::Vector3d& p = points_world[k];
    double r = use_cov ? r3.dot(covariances[k] * r3) : default_var;
    if (use_pose) {
      const Eigen::Vector3d j(p.y() - c.y(), -(p.x() - c.x()), 1.0);
      r += j.dot(pose_block * j);
    }
    FusePoint(p, r, ctx.frame, &stats);
  }
  return stats;
}

void ElevationMap::SetCell(CellIndex cell, double elevation_m, double variance_m2,
                           std::uint32_t count, std::uint32_t frame) {
  Tile& tile = TileFor(index_.CellToTile(cell), nullptr);
  CellRecord& record = tile.cells[index_.LinearIndex(index_.CellToLocal(cell))];
  const bool was_filled = record.value.count > 0;
  if (!std::isfinite(elevation_m) || count == 0) {
    record = CellRecord{};
    if (was_filled) --tile.filled;
    return;
  }
  const auto zf = static_cast<float>(elevation_m);
  record.value = {zf, static_cast<float>(variance_m2), zf, zf, count, frame};
  record.start_frame = frame;
  if (!was_filled) ++tile.filled;
  bounds_.Extend(cell);
}

std::optional<CellValue> ElevationMap::Cell(CellIndex cell) const {
  const Tile* tile = FindTile(index_.CellToTile(cell));
  if (tile == nullptr) return std::nullopt;
  const CellValue& value = tile->cells[index_.LinearIndex(index_.CellToLocal(cell))].value;
  if (value.Empty()) return std::nullopt;
  return value;
}

double ElevationMap::HeightAt(double x_m, double y_m) const {
  const auto cell = WorldToCell(x_m, y_m);
  if (!cell) return std::numeric_limits<double>::quiet_NaN();
  const auto value = Cell(*cell);
  return value ? value->elevation_m : std::numeric_limits<double>::quiet_NaN();
}

double ElevationMap::VarianceAt(double x_m, double y_m) const {
  const auto cell = WorldToCell(x_m, y_m);
  if (!cell) return std::numeric_limits<double>::quiet_NaN();
  const auto value = Cell(*cell);
  return value ? value->variance_m2 : std::numeric_limits<double>::quiet_NaN();
}

const Tile* ElevationMap::FindTile(TileIndex tile_index) const {
  const auto it = tiles_.find(tile_index);
  return it == tiles_.end() ? nullptr : it->second.get();
}

std::vector<TileIndex> ElevationMap::TileIndices() const {
  std::vector<TileIndex> out;
  out.reserve(tiles_.size());
  for (const auto& entry : tiles_) out.push_back(entry.first);
  return out;
}

std::size_t ElevationMap::CellCount() const {
  std::size_t n = 0;
  for (const auto& entry : tiles_) n += entry.second->filled;
  return n;
}

std::size_t ElevationMap::MemoryBytes() const {
  const auto cells =
      static_cast<std::size_t>(options_.tile_cells) * static_cast<std::size_t>(options_.tile_cells);
  return tiles_.size() * (sizeof(Tile) + cells * sizeof(CellRecord));
}

}  // namespace rovermap::dem
