// ElevationMap::ClearSeenThrough: a surface a later frame sees through is no longer there.
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>

#include "dem/ElevationMap.hpp"

namespace rovermap::dem {
namespace {

// A cell or a square of cells as one hash key (indices within ±2^31 of the origin's cell are
// far beyond any traverse).
std::uint64_t Key(std::int64_t x, std::int64_t y) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) << 32) |
         static_cast<std::uint32_t>(y);
}

}  // namespace

ClearingStats ElevationMap::ClearSeenThrough(const Eigen::Isometry3d& T_world_points,
                                             const FramePart& part,
                                             const Eigen::Vector3d& sensor_world,
                                             std::uint32_t frame) {
  ClearingStats stats;
  if (options_.clear_min_rays <= 0 || part.points == nullptr || !sensor_world.allFinite())
    return stats;
  const double cell = options_.cell_size_m;
  const Eigen::Vector2d s = WorldToGrid(sensor_world.x(), sensor_world.y()) / cell;
  const double spacing = std::max(1, options_.clear_ray_spacing_cells);
  // Rays no longer than the grid's reach from the sensor; a point farther than 4096 cells
  // (200 m at 5 cm) is not used.
  constexpr double kMaxRayCells = 4096.0;
  std::unordered_set<std::uint64_t> squares;
  std::unordered_map<std::uint64_t, std::uint32_t> hits;
  // The last tile looked up: a ray crosses few tiles.
  TileIndex cached_index{};
  const Tile* cached = nullptr;
  bool have_cached = false;
  const auto value_at = [&](CellIndex c) -> const CellValue* {
    const TileIndex t = index_.CellToTile(c);
    if (!have_cached || !(t.x == cached_index.x && t.y == cached_index.y)) {
      cached = FindTile(t);
      cached_index = t;
      have_cached = true;
    }
    if (cached == nullptr) return nullptr;
    return &cached->cells[index_.LinearIndex(index_.CellToLocal(c))].value;
  };

  const std::vector<Eigen::Vector3d>& points = *part.points;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (part.keep != nullptr && (*part.keep)[i] == 0) continue;
    const Eigen::Vector3d p = T_world_points * points[i];
    if (!p.allFinite()) continue;
    const Eigen::Vector2d g = WorldToGrid(p.x(), p.y()) / cell;
    const Eigen::Vector2d d = g - s;
    const double length2 = d.squaredNorm();
    if (!(length2 > 4.0) || length2 > kMaxRayCells * kMaxRayCells) continue;
    if (!squares
             .insert(Key(static_cast<std::int64_t>(std::floor(g.x() / spacing)),
                         static_cast<std::int64_t>(std::floor(g.y() / spacing))))
             .second)
      continue;
    ++stats.rays;
    // Amanatides & Woo's walk over the cells the ray's horizontal projection crosses, from the
    // sensor's cell (left out) to the point's (left out: the ray ends on its surface).
    std::int64_t cx = static_cast<std::int64_t>(std::floor(s.x()));
    std::int64_t cy = static_cast<std::int64_t>(std::floor(s.y()));
    const auto ex = static_cast<std::int64_t>(std::floor(g.x()));
    const auto ey = static_cast<std::int64_t>(std::floor(g.y()));
    const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
    const double delta_x = d.x() != 0.0 ? 1.0 / std::abs(d.x()) : INFINITY;
    const double delta_y = d.y() != 0.0 ? 1.0 / std::abs(d.y()) : INFINITY;
    double next_x = d.x() != 0.0 ? ((cx + (d.x() > 0 ? 1 : 0)) - s.x()) / d.x() : INFINITY;
    double next_y = d.y() != 0.0 ? ((cy + (d.y() > 0 ? 1 : 0)) - s.y()) / d.y() : INFINITY;
    const double dz = p.z() - sensor_world.z();
    for (;;) {
      if (next_x < next_y) {
        cx += step_x;
        next_x += delta_x;
      } else {
        cy += step_y;
        next_y += delta_y;
      }
      if ((cx == ex && cy == ey) || std::min(next_x, next_y) > 1.0 + 1e-9) break;
      const CellValue* v = value_at({cx, cy});
      if (v == nullptr || v->Empty() || v->last_frame == frame || !Supported(*v)) continue;
      ++stats.cells_crossed;
      // The ray's height where it passes the cell's centre.
      const Eigen::Vector2d centre(cx + 0.5, cy + 0.5);
      const double t = std::clamp((centre - s).dot(d) / length2, 0.0, 1.0);
      const double ray_z = sensor_world.z() + t * dz;
      const double limit = options_.clear_margin_m + 3.0 * std::sqrt(v->variance_m2);
      if (v->elevation_m - ray_z > limit) ++hits[Key(cx, cy)];
    }
  }
  // Evidence accumulates over frames, as in an occupancy map: a frame with clear_min_rays such
  // rays saw through the cell, and the cell goes once more frames saw through it since it was
  // last seen than saw it. A thing that moved away is no longer seen and goes; a crown or a
  // parked car seen in many frames and seen through by a few rays of some stays.
  for (const auto& [key, count] : hits) {
    if (count < static_cast<std::uint32_t>(options_.clear_min_rays)) continue;
    const CellIndex c{static_cast<std::int32_t>(key >> 32),
                      static_cast<std::int32_t>(key & 0xffffffffu)};
    const auto it = tiles_.find(index_.CellToTile(c));
    if (it == tiles_.end()) continue;
    const std::size_t at = index_.LinearIndex(index_.CellToLocal(c));
    CellRecord& record = it->second->cells[at];
    if (record.value.Empty()) continue;
    CellEvidence& evidence = it->second->evidence[at];
    if (evidence.through_frames < 255) ++evidence.through_frames;
    if (evidence.through_frames <= evidence.seen_frames) continue;
    record = CellRecord{};
    evidence = CellEvidence{};
    --it->second->filled;
    ++stats.cells_cleared;
  }
  return stats;
}

}  // namespace rovermap::dem
