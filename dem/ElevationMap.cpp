#include "dem/ElevationMap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace rovermap::dem {
namespace {

[[noreturn]] void Invalid(const std::string& field, const std::string& rule, double got) {
  std::ostringstream msg;
  msg << field << ": must be " << rule << " (got " << got << ")";
  throw std::invalid_argument(msg.str());
}

// A cell's seen frames when they were not counted one by one (a candidate that took over, a
// restored tile): no more than its points, nor than the frames first_frame .. frame.
CellEvidence SeenSince(const CellValue& v, std::uint32_t frame) {
  const std::uint64_t frames = frame >= v.first_frame ? frame - v.first_frame + 1ull : 1ull;
  return {static_cast<std::uint8_t>(std::min<std::uint64_t>({frames, v.count, 255})), 0};
}

// Kalman update of a constant height observed directly (H = 1).
void KalmanUpdate(float* height_m, float* variance_m2, double z, double r) {
  const double h = *height_m;
  const double p = *variance_m2;
  const double k = p / (p + r);
  *height_m = static_cast<float>(h + k * (z - h));
  *variance_m2 = static_cast<float>((1.0 - k) * p);
}

// `shared` is the part of the point's variance that the cell's earlier points share with it
// (their frames' pose error, the rig's calibration): averaging cannot remove it, so the published
// variance stays at least min(shared, what it was), never rising with an update.
float PublishedVariance(float fused, float published_before, double shared) {
  return std::max(fused,
                  static_cast<float>(std::min(shared, static_cast<double>(published_before))));
}

// Steeper than 73° a cell's height means little; the floor keeps the variance finite.
constexpr double kMinNormalZ = 0.3;

// FrameContext::rig_*: the rig's calibration error's share of the height variance of the point
// p (see there): ω moves it by Bω, B = rig_drift − [v]×R, which a surface of normal n reads as
// nᵀBω / n_z, of variance σω²·|Bᵀn|² / n_z²; Bᵀn = rig_driftᵀn + Rᵀ(v × n).
double RigHeightVariance(const Eigen::Vector3d& p, const Eigen::Vector3d* normal,
                         const FrameContext& ctx) {
  // The normal as HeightVariance reads it: rotated into the world, n_z floored.
  const Eigen::Vector3d n = normal != nullptr && normal->allFinite()
                                ? Eigen::Vector3d(ctx.R_world_cov * *normal)
                                : Eigen::Vector3d::UnitZ();
  const double nz = std::max(std::abs(n.z()), kMinNormalZ);
  const Eigen::Vector3d v = p - ctx.sensor_origin_world;
  const Eigen::Vector3d turn =
      ctx.rig_drift.transpose() * n + ctx.R_world_body.transpose() * v.cross(n);
  const double along = n.dot(p - ctx.rig_scale_origin.value_or(ctx.sensor_origin_world));
  return (ctx.rig_rotation_variance_rad2 * turn.squaredNorm() +
          ctx.rig_scale_variance * along * along) /
         (nz * nz);
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
  if (options.min_support < 1) Invalid("min_support", ">= 1", options.min_support);
  if (options.min_frame_span < 1) Invalid("min_frame_span", ">= 1", options.min_frame_span);
  if (options.min_agreeing_neighbors < 0 || options.min_agreeing_neighbors > 8) {
    Invalid("min_agreeing_neighbors", "in [0, 8]", options.min_agreeing_neighbors);
  }
  if (!(options.neighbor_step_m >= 0.0) || !std::isfinite(options.neighbor_step_m)) {
    Invalid("neighbor_step_m", "finite and >= 0", options.neighbor_step_m);
  }
  if (!(options.max_horizontal_sigma_cells >= 0.0) ||
      !std::isfinite(options.max_horizontal_sigma_cells)) {
    Invalid("max_horizontal_sigma_cells", "finite and >= 0", options.max_horizontal_sigma_cells);
  }
  if (options.clear_min_rays < 0) Invalid("clear_min_rays", ">= 0", options.clear_min_rays);
  if (!(options.clear_margin_m >= 0.0) || !std::isfinite(options.clear_margin_m)) {
    Invalid("clear_margin_m", "finite and >= 0", options.clear_margin_m);
  }
  if (options.clear_ray_spacing_cells < 1) {
    Invalid("clear_ray_spacing_cells", ">= 1", options.clear_ray_spacing_cells);
  }
  if (!std::isfinite(options.grid_rotation_rad)) {
    Invalid("grid_rotation_rad", "finite", options.grid_rotation_rad);
  }
}

Tile::Tile(int tile_cells)
    : cells(static_cast<std::size_t>(tile_cells) * static_cast<std::size_t>(tile_cells)),
      evidence(cells.size()) {}

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

void ElevationMap::RestoreTile(TileIndex tile_index, std::vector<CellRecord> cells,
                               std::vector<CellEvidence> evidence) {
  const auto n = static_cast<std::size_t>(options_.tile_cells);
  if (cells.size() != n * n) {
    throw std::invalid_argument("ElevationMap::RestoreTile: " + std::to_string(cells.size()) +
                                " cells, a tile holds " + std::to_string(n * n));
  }
  if (!evidence.empty() && evidence.size() != cells.size()) {
    throw std::invalid_argument("ElevationMap::RestoreTile: " + std::to_string(evidence.size()) +
                                " cells' evidence, a tile holds " + std::to_string(n * n));
  }
  auto tile = std::make_unique<Tile>(0);
  tile->cells = std::move(cells);
  const bool derive = evidence.empty();
  tile->evidence = std::move(evidence);
  tile->evidence.resize(tile->cells.size());
  for (std::size_t i = 0; i < tile->cells.size(); ++i) {
    const CellValue& v = tile->cells[i].value;
    if (v.count == 0) continue;
    ++tile->filled;
    if (derive) tile->evidence[i] = SeenSince(v, v.last_frame);
  }
  cache_ = TileCache{};
  tiles_[tile_index] = std::move(tile);
}

void ElevationMap::RestoreCounters(const CellBounds& bounds, std::size_t covariances_ignored) {
  bounds_ = bounds;
  covariances_ignored_ = covariances_ignored;
}

std::vector<std::uint32_t> CountPerCell(const std::vector<CellIndex>& cells) {
  std::vector<std::uint32_t> counts(cells.size(), 1);
  if (cells.empty()) return counts;
  // A dense count over the cells' bounding box when it is small (a frame spans metres: some
  // ten thousand cells), a sort otherwise (e.g. a stray far point).
  std::int64_t x0 = cells[0].x, x1 = x0, y0 = cells[0].y, y1 = y0;
  for (const CellIndex& c : cells) {
    x0 = std::min(x0, c.x);
    x1 = std::max(x1, c.x);
    y0 = std::min(y0, c.y);
    y1 = std::max(y1, c.y);
  }
  const auto width = static_cast<std::uint64_t>(x1 - x0) + 1;
  const auto height = static_cast<std::uint64_t>(y1 - y0) + 1;
  const std::uint64_t max_dense = std::max<std::uint64_t>(std::uint64_t{1} << 22, 8 * cells.size());
  if (width <= max_dense && height <= max_dense / width) {
    std::vector<std::uint32_t> dense(width * height, 0);
    auto at = [&](const CellIndex& c) -> std::uint32_t& {
      return dense[static_cast<std::uint64_t>(c.y - y0) * width +
                   static_cast<std::uint64_t>(c.x - x0)];
    };
    for (const CellIndex& c : cells) ++at(c);
    for (std::size_t i = 0; i < cells.size(); ++i) counts[i] = at(cells[i]);
    return counts;
  }
  std::vector<std::size_t> order(cells.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto less = [&](std::size_t a, std::size_t b) {
    return cells[a].y != cells[b].y ? cells[a].y < cells[b].y : cells[a].x < cells[b].x;
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t begin = 0; begin < order.size();) {
    std::size_t end = begin + 1;
    while (end < order.size() && !less(order[begin], order[end])) ++end;
    for (std::size_t j = begin; j < end; ++j) {
      counts[order[j]] = static_cast<std::uint32_t>(end - begin);
    }
    begin = end;
  }
  return counts;
}

namespace {

// Which cells a frame's measured points reach: a dense mask over their bounding box when it is
// small (CountPerCell's reasoning), a sorted list otherwise.
class CellSet {
 public:
  explicit CellSet(const std::vector<CellIndex>& cells) {
    if (cells.empty()) return;
    x0_ = x1_ = cells[0].x;
    y0_ = y1_ = cells[0].y;
    for (const CellIndex& c : cells) {
      x0_ = std::min(x0_, c.x), x1_ = std::max(x1_, c.x);
      y0_ = std::min(y0_, c.y), y1_ = std::max(y1_, c.y);
    }
    width_ = static_cast<std::uint64_t>(x1_ - x0_) + 1;
    const auto height = static_cast<std::uint64_t>(y1_ - y0_) + 1;
    const std::uint64_t max_dense =
        std::max<std::uint64_t>(std::uint64_t{1} << 22, 8 * cells.size());
    if (width_ <= max_dense && height <= max_dense / width_) {
      dense_.assign(width_ * height, 0);
      for (const CellIndex& c : cells) dense_[Offset(c)] = 1;
    } else {
      for (const CellIndex& c : cells) sorted_.emplace_back(c.x, c.y);
      std::sort(sorted_.begin(), sorted_.end());
    }
  }
  bool Contains(const CellIndex& c) const {
    if (!dense_.empty()) {
      return c.x >= x0_ && c.x <= x1_ && c.y >= y0_ && c.y <= y1_ && dense_[Offset(c)] != 0;
    }
    return std::binary_search(sorted_.begin(), sorted_.end(), std::pair{c.x, c.y});
  }

 private:
  std::uint64_t Offset(const CellIndex& c) const {
    return static_cast<std::uint64_t>(c.y - y0_) * width_ + static_cast<std::uint64_t>(c.x - x0_);
  }
  std::int64_t x0_ = 0, x1_ = -1, y0_ = 0, y1_ = -1;
  std::uint64_t width_ = 0;
  std::vector<std::uint8_t> dense_;
  std::vector<std::pair<std::int64_t, std::int64_t>> sorted_;
};

}  // namespace

bool ElevationMap::WithinGate(double h, double p, double z, double r) const {
  const double d = z - h;
  return d * d <= options_.mahalanobis_gate * (p + r);
}

bool ElevationMap::CandidateTakesOver(const CellRecord& record) const {
  const CellValue& v = record.value;
  const CellCandidate& c = record.candidate;
  if (c.start_frame == v.first_frame) {
    // One view saw both: a vertical structure (rock face and top). The higher hypothesis wins
    // once it has support, never as an isolated point.
    const auto support = static_cast<std::uint32_t>(std::max(2, options_.min_support));
    if (c.height_m > v.elevation_m) {
      if (c.count >= support) return true;
    } else if (v.count >= support) {
      return false;
    }
  }
  return c.count > v.count;
}

bool ElevationMap::FuseAt(CellIndex cell, double z, double r, double r_update, std::uint32_t frame,
                          FusionStats* stats, double shared_m2) {
  Tile& tile = TileFor(index_.CellToTile(cell), stats);
  const std::size_t at = index_.LinearIndex(index_.CellToLocal(cell));
  CellRecord& record = tile.cells[at];
  CellValue& v = record.value;
  CellCandidate& c = record.candidate;
  CellEvidence& e = tile.evidence[at];
  const auto zf = static_cast<float>(z);
  const auto rf = static_cast<float>(r_update);
  if (v.count == 0) {
    // Published from the first point on at no less than the share every frame repeats.
    const auto published = static_cast<float>(std::max(r_update, shared_m2));
    v = {zf, published, zf, zf, 1, frame, frame, rf};
    e = {1, 0};
    ++tile.filled;
    bounds_.Extend(cell);
    if (stats != nullptr) ++stats->fused;
    return true;
  }
  bool into_primary = true;
  if (WithinGate(v.elevation_m, v.fused_variance_m2, z, r)) {
    KalmanUpdate(&v.elevation_m, &v.fused_variance_m2, z, r_update);
    v.variance_m2 = PublishedVariance(v.fused_variance_m2, v.variance_m2, shared_m2);
    ++v.count;
    // A frame that sees the surface again outweighs the frames that saw through it before.
    if (v.last_frame != frame) e = {static_cast<std::uint8_t>(std::min(255, e.seen_frames + 1)), 0};
    v.last_frame = frame;
    if (stats != nullptr) ++stats->fused;
  } else if (c.count > 0 && WithinGate(c.height_m, c.variance_m2, z, r)) {
    KalmanUpdate(&c.height_m, &c.variance_m2, z, r_update);
    ++c.count;
    if (!CandidateTakesOver(record)) {
      into_primary = false;
      if (stats != nullptr) ++stats->candidate;
    } else {
      // The candidate keeps only its fused variance; the new primary publishes it, kept from
      // falling below the shared share of the point that made it take over.
      std::swap(v.elevation_m, c.height_m);
      std::swap(v.fused_variance_m2, c.variance_m2);
      v.variance_m2 = std::max(v.fused_variance_m2, static_cast<float>(shared_m2));
      std::swap(v.count, c.count);
      std::swap(v.first_frame, c.start_frame);
      v.last_frame = frame;
      // The candidate's frames were not counted: its points and its frames bound them.
      e = SeenSince(v, frame);
      if (stats != nullptr) ++stats->swapped;
    }
  } else if (c.count <= 1) {  // a lone point is no evidence to keep: the newer one replaces it
    c = {zf, rf, 1, frame};
    into_primary = false;
    if (stats != nullptr) ++stats->candidate;
  } else {
    if (stats != nullptr) ++stats->rejected_outliers;
    return false;
  }
  v.min_m = std::min(v.min_m, zf);
  v.max_m = std::max(v.max_m, zf);
  return into_primary;
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
  return FuseAt(*cell, point_world.z(), r, r, frame, stats);
}

FusionStats ElevationMap::FuseFrame(const std::vector<Eigen::Vector3d>& points_world,
                                    const std::vector<Eigen::Matrix3d>& covariances,
                                    const FrameContext& ctx) {
  const std::size_t n = points_world.size();
  const bool use_cov = !covariances.empty() && covariances.size() == n;
  if (!covariances.empty() && !use_cov) ++covariances_ignored_;
  const bool has_normals = ctx.normals != nullptr && !ctx.normals->empty();
  if (has_normals && ctx.normals->size() != n) ++covariances_ignored_;
  const bool use_normals = has_normals && ctx.normals->size() == n && options_.slope_aware_variance;
  return FuseFrameWith(
      n,
      [&](std::size_t k, Eigen::Vector3d* p, const Eigen::Matrix3d** cov,
          const Eigen::Vector3d** normal, bool* is_fill) {
        *p = points_world[k];
        *cov = use_cov ? &covariances[k] : nullptr;
        *normal = use_normals ? &(*ctx.normals)[k] : nullptr;
        *is_fill = k >= ctx.fill_from;
        return true;
      },
      use_cov, ctx);
}

FusionStats ElevationMap::FuseFrame(const Eigen::Isometry3d& T_world_points,
                                    const FramePart& measured, const FramePart& fill,
                                    const FrameContext& ctx) {
  struct Part {
    const FramePart* part;
    std::size_t n;
    bool cov, normals, masked;
  };
  auto size = [](const auto* v) { return v == nullptr ? std::size_t{0} : v->size(); };
  Part parts[2];
  bool use_cov = true, use_normals = options_.slope_aware_variance;
  for (int i = 0; i < 2; ++i) {
    const FramePart& f = i == 0 ? measured : fill;
    Part& q = parts[i];
    q.part = &f;
    q.n = size(f.points);
    q.cov = size(f.covariances) == q.n;
    q.normals = size(f.normals) == q.n;
    q.masked = f.keep != nullptr && f.keep->size() == q.n;
    if (q.n == 0) continue;
    if (size(f.covariances) != 0 && !q.cov) ++covariances_ignored_;
    if (size(f.normals) != 0 && !q.normals) ++covariances_ignored_;
    use_cov = use_cov && q.cov && size(f.covariances) != 0;
    use_normals = use_normals && q.normals && size(f.normals) != 0;
  }
  FrameContext context = ctx;
  context.fill_from = parts[0].n;
  return FuseFrameWith(
      parts[0].n + parts[1].n,
      [&](std::size_t k, Eigen::Vector3d* p, const Eigen::Matrix3d** cov,
          const Eigen::Vector3d** normal, bool* is_fill) {
        *is_fill = k >= parts[0].n;
        const Part& q = parts[*is_fill ? 1 : 0];
        const std::size_t i = *is_fill ? k - parts[0].n : k;
        if (q.masked && (*q.part->keep)[i] == 0) return false;
        *p = T_world_points * (*q.part->points)[i];
        *cov = use_cov ? &(*q.part->covariances)[i] : nullptr;
        *normal = use_normals ? &(*q.part->normals)[i] : nullptr;
        return true;
      },
      use_cov, context);
}

template <typename At>
FusionStats ElevationMap::FuseFrameWith(std::size_t n, const At& at, bool use_cov,
                                        const FrameContext& ctx) {
  FusionStats stats;

  // Pose term J Σ Jᵀ with J = (dy, −dx, 0, 0, 0, 1): only rows/cols rx, ry, tz of Σ matter.
  Eigen::Matrix3d pose_block = Eigen::Matrix3d::Zero();
  const bool use_pose = ctx.pose_covariance.has_value() && ctx.pose_covariance->allFinite();
  if (use_pose) {
    const int idx[3] = {0, 1, 5};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) pose_block(a, b) = (*ctx.pose_covariance)(idx[a], idx[b]);
  }
  const Eigen::Vector3d& c = ctx.sensor_origin_world;
  const Eigen::Matrix<double, 2, 3> horizontal = ctx.R_world_cov.topRows<2>();
  const double max_h = options_.max_horizontal_sigma_cells * options_.cell_size_m;
  const bool limit_h = use_cov && options_.max_horizontal_sigma_cells > 0.0;
  const bool use_rig = ctx.rig_rotation_variance_rad2 > 0.0 || ctx.rig_scale_variance > 0.0;

  // Pass 1: each point's cell and height variance, or why it is dropped. The cells go in their
  // own array, which CountPerCell takes as it is.
  struct Fusable {
    double z;
    double r;
    double shared;  // the share every frame repeats (attitude_error_shared, FrameContext::rig_*)
  };
  std::vector<Fusable> fusable;
  std::vector<CellIndex> cells;
  fusable.reserve(n);
  cells.reserve(n);
  std::optional<CellSet> measured;  // the cells of the points before the fill
  std::size_t fill_skipped = 0;
  Eigen::Vector3d p;
  const Eigen::Matrix3d* cov = nullptr;
  const Eigen::Vector3d* normal = nullptr;
  bool is_fill = false;
  for (std::size_t k = 0; k < n; ++k) {
    if (!at(k, &p, &cov, &normal, &is_fill)) continue;
    ++stats.points;
    if (is_fill) {
      if (!measured) measured.emplace(cells);
      const auto cell = WorldToCell(p.x(), p.y());
      if (!cell || measured->Contains(*cell)) {
        ++fill_skipped;
        continue;
      }
    }
    if (limit_h) {
      if (LargestHorizontalVariance(horizontal, *cov) > max_h * max_h) {
        ++stats.dropped_imprecise;
        continue;
      }
    }
    if (!p.allFinite()) {
      ++stats.dropped_nonfinite;
      continue;
    }
    const auto cell = WorldToCell(p.x(), p.y());
    if (!cell) {
      ++stats.dropped_out_of_grid;
      continue;
    }
    double r = HeightVariance(p, cov, normal, ctx.R_world_cov, *cell);
    double shared = 0.0;
    if (use_pose) {
      const Eigen::Vector3d j(p.y() - c.y(), -(p.x() - c.x()), 1.0);
      r += j.dot(pose_block * j);
      if (options_.attitude_error_shared) {
        const Eigen::Vector2d ja = j.head<2>();
        shared = ja.dot(pose_block.topLeftCorner<2, 2>() * ja);
      }
    }
    if (use_rig) shared += RigHeightVariance(p, normal, ctx);
    if (!std::isfinite(r) || r < 0.0) {
      ++stats.dropped_nonfinite;
      continue;
    }
    fusable.push_back({p.z(), std::max(r, options_.min_point_variance_m2), shared});
    cells.push_back(*cell);
  }

  // Pass 2: fuse; with frame_points_correlated the frame's points in a cell weigh as one.
  const std::vector<std::uint32_t> counts =
      options_.frame_points_correlated ? CountPerCell(cells) : std::vector<std::uint32_t>();
  for (std::size_t i = 0; i < fusable.size(); ++i) {
    const Fusable& f = fusable[i];
    const double m = counts.empty() ? 1.0 : static_cast<double>(counts[i]);
    FuseAt(cells[i], f.z, f.r, f.r * m, ctx.frame, &stats, f.shared);
  }
  stats.points -= fill_skipped;
  return stats;
}

double ElevationMap::HeightVariance(const Eigen::Vector3d& p, const Eigen::Matrix3d* covariance,
                                    const Eigen::Vector3d* normal,
                                    const Eigen::Matrix3d& R_world_cov, CellIndex cell) const {
  if (normal == nullptr || !normal->allFinite()) {
    if (covariance == nullptr) {
      return options_.default_point_stddev_m * options_.default_point_stddev_m;
    }
    const Eigen::Vector3d r3 = R_world_cov.row(2).transpose();
    return r3.dot(*covariance * r3);
  }
  // The sign of the normal cancels in both terms below; n_z's does not.
  const Eigen::Vector3d n = R_world_cov * *normal;
  const double nz = std::max(std::abs(n.z()), kMinNormalZ);
  const double across = covariance != nullptr ? normal->dot(*covariance * *normal)
                                              : options_.default_point_stddev_m *
                                                    options_.default_point_stddev_m * n.z() * n.z();
  const Eigen::Vector2d d = p.head<2>() - CellCenterWorld(cell);
  const double offset = n.x() * d.x() + n.y() * d.y();
  return (across + offset * offset) / (nz * nz);
}

void ElevationMap::SetCell(CellIndex cell, double elevation_m, double variance_m2,
                           std::optional<std::uint32_t> count, std::uint32_t frame) {
  const std::uint32_t n = count.value_or(static_cast<std::uint32_t>(options_.min_support));
  Tile& tile = TileFor(index_.CellToTile(cell), nullptr);
  const std::size_t at = index_.LinearIndex(index_.CellToLocal(cell));
  CellRecord& record = tile.cells[at];
  const bool was_filled = record.value.count > 0;
  tile.evidence[at] = CellEvidence{};
  if (!std::isfinite(elevation_m) || n == 0) {
    record = CellRecord{};
    if (was_filled) --tile.filled;
    return;
  }
  const auto zf = static_cast<float>(elevation_m);
  record = CellRecord{};
  const auto span = static_cast<std::uint32_t>(options_.min_frame_span - 1);
  record.value = {zf,    static_cast<float>(variance_m2), zf, zf, n, frame + span,
                  frame, static_cast<float>(variance_m2)};
  tile.evidence[at] = SeenSince(record.value, record.value.last_frame);
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

bool ElevationMap::Published(CellIndex cell, const CellValue& value) const {
  if (!Supported(value)) return false;
  if (options_.min_agreeing_neighbors <= 0) return true;
  // Neighbours inside the cell's own tile are read from it directly; only those across a tile
  // edge go through the tile table (a publication tests every cell: dem.tif, dem.png, counts).
  const Tile* tile = FindTile(index_.CellToTile(cell));
  const LocalIndex local = index_.CellToLocal(cell);
  const int n = options_.tile_cells;
  int agreeing = 0;
  for (std::int64_t dy = -1; dy <= 1; ++dy) {
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) continue;
      const int x = local.x + static_cast<int>(dx);
      const int y = local.y + static_cast<int>(dy);
      CellValue inside;
      std::optional<CellValue> across;
      const CellValue* neighbour = nullptr;
      if (tile != nullptr && x >= 0 && x < n && y >= 0 && y < n) {
        inside = tile->cells[index_.LinearIndex({x, y})].value;
        neighbour = &inside;
      } else {
        across = Cell({cell.x + dx, cell.y + dy});
        if (across) neighbour = &*across;
      }
      if (neighbour == nullptr || !Supported(*neighbour)) continue;
      const double step = std::abs(static_cast<double>(neighbour->elevation_m) - value.elevation_m);
      // The fused variances: an attitude error the two cells share moves both alike.
      const double three_sigma =
          3.0 * std::sqrt(std::max(0.0, static_cast<double>(neighbour->fused_variance_m2) +
                                            static_cast<double>(value.fused_variance_m2)));
      if (step <= std::max(options_.neighbor_step_m, three_sigma) &&
          ++agreeing >= options_.min_agreeing_neighbors) {
        return true;
      }
    }
  }
  return false;
}

std::optional<CellValue> ElevationMap::PublishedAt(double x_m, double y_m) const {
  const auto cell = WorldToCell(x_m, y_m);
  if (!cell) return std::nullopt;
  const auto value = Cell(*cell);
  if (!value || !Published(*cell, *value)) return std::nullopt;
  return value;
}

double ElevationMap::HeightAt(double x_m, double y_m) const {
  const auto value = PublishedAt(x_m, y_m);
  return value ? value->elevation_m : std::numeric_limits<double>::quiet_NaN();
}

double ElevationMap::VarianceAt(double x_m, double y_m) const {
  const auto value = PublishedAt(x_m, y_m);
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

std::size_t ElevationMap::PublishedCellCount() const {
  std::size_t n = 0;
  ForEachPublishedCell([&n](CellIndex, const CellValue&) { ++n; });
  return n;
}

std::size_t ElevationMap::MemoryBytes() const {
  const auto cells =
      static_cast<std::size_t>(options_.tile_cells) * static_cast<std::size_t>(options_.tile_cells);
  return tiles_.size() * (sizeof(Tile) + cells * (sizeof(CellRecord) + sizeof(CellEvidence)));
}

}  // namespace rovermap::dem
