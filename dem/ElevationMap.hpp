#pragma once
// The elevation grid: sparse 256×256-cell tiles allocated on first touch (GridIndex), six
// layers per cell, and per-cell two-hypothesis Kalman fusion of registered points
// (docs/design.md §3, §9, §9a).
//
// Grid frame. Cells are laid out in a horizontal frame rotated from the world (ENU) frame by
// `grid_rotation_rad` (counter-clockwise about z): p_grid = R(θ)·(x_world, y_world). The map
// writer sets θ to the meridian convergence of the output projection so that grid north is
// projection north and the GeoTIFF needs no resampling (io/Georeference.hpp); θ = 0 is plain ENU.
// Heights are world z (metres above the origin's altitude) in every frame.
//
// Fusion (docs/design.md §9a: 1–2 % of stereo points are mismatches off the surface along their
// ray, and a spike reads as a rock). Each cell holds two height hypotheses: the primary (the
// estimate published as elevation, variance, count, min, max and last frame; and its start frame)
// and a candidate (height, variance, count, start frame). A point with height z and variance r,
// against a hypothesis (h, σ²), passes the gate when d² = (z − h)² / (σ² + r) <=
// `mahalanobis_gate`:
//  - empty cell: the point starts the primary (h = z, σ² = r);
//  - within the gate of the primary: Kalman update of the primary,
//    h += K(z − h), σ² = (1 − K)σ², K = σ² / (σ² + r);
//  - else within the gate of the candidate: Kalman update of the candidate, which then takes
//    over (the two swap) when it has more points than the primary, or when both started in the
//    same frame (one view saw both: a rock face and its top), the candidate is higher and it has
//    at least max(2, min_support) points. While both started in the same frame and the higher
//    one holds that support, the lower never takes over by count (a face seen under its top);
//  - else a candidate holding at most one point is replaced by the point; otherwise the point
//    disagrees with two hypotheses and is rejected (counted).
// So an isolated outlier first in an empty cell is outvoted by the next two true points, and an
// isolated higher point in one frame is never adopted. Min and max span every point taken into
// either hypothesis (rejected points excluded), so max − min shows a step in the cell.
// Publishing: a cell is published (HeightAt, VarianceAt, ForEachPublishedCell, the writers in
// io/) only when its primary holds at least `min_support` points; its NaN is better than a spike.
// Cell and ForEachCell give the raw layers of every cell holding a point.
// Non-finite points, variances or positions outside the grid are dropped and counted.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "dem/GridIndex.hpp"

namespace rovermap::dem {

/// Options of the elevation grid and its fusion; plain values, in-class defaults.
struct ElevationMapOptions {
  double cell_size_m = 0.05;      ///< [m] edge of a square cell, > 0
  int tile_cells = 256;           ///< [count] cells along a tile edge, >= 1
  double mahalanobis_gate = 9.0;  ///< [chi^2, 1 dof] squared Mahalanobis distance; 9 = 3 sigma
  /// [m] height standard deviation of a point given without a covariance.
  double default_point_stddev_m = 0.02;
  /// [m^2] floor on a point's height variance, so one perfect point cannot freeze a cell.
  double min_point_variance_m2 = 1e-6;
  /// [count] points the primary needs before the cell is published (and before a higher
  /// hypothesis of the same view takes over, at least 2); >= 1. 1 publishes every cell.
  int min_support = 3;
  /// [frames] a cell is published only when the points of its primary span at least this many
  /// frames (last − first + 1): stereo mismatches that one frame makes (SGBM filling untextured
  /// sky or shadow from its edges) land where no other frame confirms them, while true ground
  /// is seen again by the next frame. 1 = off; >= 1.
  int min_frame_span = 2;
  /// [cells] a point whose horizontal position is less certain than this many cells (the
  /// larger σ of its covariance's horizontal block) is not fused: a far stereo point lands in
  /// a cell it may not belong to, and on sloping ground its height is then wrong by the slope ×
  /// that error, which its height variance does not say. 0 = fuse every point. Needs
  /// covariances (points without are fused).
  double max_horizontal_sigma_cells = 2.0;
  /// [count] a supported cell is published only when at least this many of its 8 neighbours
  /// are supported and agree with it (height step within max(neighbor_step_m, 3σ)): a spike is
  /// one or two cells high above their neighbours (stereo mismatches that every frame repeats,
  /// such as the sky above a skyline), a rock is a patch (its corner cells, with 3, are left
  /// out). 0 = no neighbourhood test; in [0, 8].
  int min_agreeing_neighbors = 4;
  /// [m] height step to a neighbour that still agrees (when larger than 3σ of the two cells).
  double neighbor_step_m = 0.1;
  /// The points of one frame that fall in one cell share their errors (correlation stereo
  /// matches each pixel over a window of its neighbours, and all share the frame's pose): true
  /// makes them weigh together as one measurement (each one's Kalman update uses its variance ×
  /// the frame's point count in that cell; the gate its own variance). false counts every point
  /// as independent, which made the published σ 5× too small (docs/maps.md, "The published σ").
  bool frame_points_correlated = true;
  /// With normals (FrameContext::normals), a point's height variance is that of its distance to
  /// the surface along the vertical at the cell centre: nᵀΣn / n_z² (its error across the
  /// surface; on a slope its horizontal error moves it up or down the slope) plus
  /// ((n_x·d_x + n_y·d_y) / n_z)², d its horizontal offset from the cell centre (the slope
  /// between where it lies and where the cell's height is read). n_z is floored at 0.3 (73°).
  bool slope_aware_variance = true;
  /// The pose's roll and pitch error (FrameContext::pose_covariance) is shared by the frames
  /// that see a cell (the chain's attitude is held to dead reckoning's gravity-referenced one,
  /// so its error is an offset that neighbouring frames repeat, not noise that averages out):
  /// true keeps a cell's published variance (CellValue::variance_m2) from falling below the
  /// attitude's share of the updating point's variance, or below what it was before the
  /// update; the fusion's own variance, hence the heights, are unchanged. Its position share
  /// still averages over frames (the rig's share, FrameContext::rig_*, does not). docs/maps.md,
  /// "The published σ".
  bool attitude_error_shared = true;
  /// Visibility clearing (ElevationMap::ClearSeenThrough): a published surface that a later
  /// frame's rays pass under, toward points it saw beyond, is no longer there (a person, a car
  /// or another rover that moved away): the cell is emptied for later frames to fill. A cell
  /// is seen through by a frame when at least clear_min_rays of its rays pass below its height
  /// by more than clear_margin_m + 3σ, and emptied once more frames saw through it since it was
  /// last seen than saw it (CellEvidence). 0 rays = off.
  int clear_min_rays = 1;
  double clear_margin_m = 0.1;  ///< [m] beyond the cell's 3σ: the pose's and the ray's error
  /// [cells] the rays are cast to one point per square of this many cells (the frame's first
  /// in each): 8 (40 cm squares) keeps a KITTI frame's DEM fusion within its time without
  /// clearing (4 doubled it: 47 → 100 ms).
  int clear_ray_spacing_cells = 8;
  /// [rad] counter-clockwise rotation from world ENU to the grid axes (see above). Not a config
  /// key: derived from the georeference.
  double grid_rotation_rad = 0.0;
};

/// @throw std::invalid_argument naming the field if a value is out of range.
void Validate(const ElevationMapOptions& options);

/// The largest eigenvalue of a point covariance's horizontal block, `horizontal` · cov ·
/// `horizontal`ᵀ (the rows of the rotation to the frame whose x and y are horizontal) [m²]:
/// what max_horizontal_sigma_cells is tested against. Also the stereo's DEM fill uses it, to
/// make no point the DEM would drop.
inline double LargestHorizontalVariance(const Eigen::Matrix<double, 2, 3>& horizontal,
                                        const Eigen::Matrix3d& cov) {
  const Eigen::Matrix2d h = horizontal * cov * horizontal.transpose();
  const double mean = 0.5 * (h(0, 0) + h(1, 1));
  const double half = 0.5 * (h(0, 0) - h(1, 1));
  return mean + std::sqrt(half * half + h(0, 1) * h(0, 1));
}

/// One cell's published layers (the primary hypothesis). Empty cells have NaN elevation,
/// variance, min and max and count 0.
struct CellValue {
  static constexpr float kEmpty = std::numeric_limits<float>::quiet_NaN();
  float elevation_m = kEmpty;  ///< fused height [m] (world z)
  /// Variance of elevation_m as published [m^2]: fused_variance_m2, kept from falling below the
  /// shares every frame repeats (ElevationMapOptions::attitude_error_shared, FrameContext::rig_*).
  float variance_m2 = kEmpty;
  float min_m = kEmpty;           ///< lowest point taken into either hypothesis [m]
  float max_m = kEmpty;           ///< highest such point [m]
  std::uint32_t count = 0;        ///< points fused into the current estimate
  std::uint32_t last_frame = 0;   ///< frame of the last update
  std::uint32_t first_frame = 0;  ///< frame of the first point of the current estimate
  /// The fusion's own variance [m^2], every frame's error averaged as independent: what the
  /// gate and the Kalman gain read, so that sharing the attitude's error changes σ, not heights.
  float fused_variance_m2 = kEmpty;
  bool Empty() const { return count == 0; }
};

/// A cell's second hypothesis: points that disagree with the primary (see the rule above).
struct CellCandidate {
  float height_m = CellValue::kEmpty;     ///< fused height [m]
  float variance_m2 = CellValue::kEmpty;  ///< its variance [m^2]
  std::uint32_t count = 0;                ///< points fused into it; 0 = none
  std::uint32_t start_frame = 0;          ///< frame of its first point
};

/// One cell as stored: the primary's layers, then the candidate. 48 bytes, no
/// padding (44 before the published and the fused variance were told apart; docs/benchmarks.md,
/// "Maps").
struct CellRecord {
  CellValue value;
  CellCandidate candidate;
};
static_assert(sizeof(CellRecord) == 48, "CellRecord: keep the layout compact (see above)");

/// A cell's evidence for visibility clearing, counted in frames (saturating at 255): kept beside
/// the records, 2 bytes a cell, so that CellRecord keeps its layout.
struct CellEvidence {
  std::uint8_t seen_frames = 0;     ///< frames that fused a point into the primary
  std::uint8_t through_frames = 0;  ///< frames that saw through it since it was last seen
};

/// Storage of one tile: tile_cells² records, row-major, rows south to north
/// (GridIndex::LinearIndex).
struct Tile {
  explicit Tile(int tile_cells);
  std::vector<CellRecord> cells;
  std::vector<CellEvidence> evidence;  ///< one per cell, as `cells`
  std::size_t filled = 0;              ///< cells with count > 0
};

/// What FuseFrame did with the points it was given: points = fused + candidate + swapped +
/// rejected_outliers + dropped_nonfinite + dropped_out_of_grid + dropped_imprecise.
struct FusionStats {
  std::size_t points = 0;               ///< points given
  std::size_t fused = 0;                ///< into the primary (first points of empty cells too)
  std::size_t candidate = 0;            ///< into the candidate (started or updated), no swap
  std::size_t swapped = 0;              ///< into the candidate, which then became the primary
  std::size_t rejected_outliers = 0;    ///< outside the gate of both hypotheses
  std::size_t dropped_nonfinite = 0;    ///< NaN/inf coordinates; non-finite or negative variance
  std::size_t dropped_out_of_grid = 0;  ///< beyond ±kMaxCellIndex
  std::size_t dropped_imprecise = 0;    ///< horizontal σ above max_horizontal_sigma_cells
  std::size_t new_tiles = 0;            ///< tiles allocated by this call
  /// Cells the frame saw through and emptied (ClearSeenThrough, when the caller runs it).
  std::size_t cells_cleared = 0;
};

/// Per-frame context of FuseFrame.
struct FrameContext {
  std::uint32_t frame = 0;  ///< frame index (the vertical-structure rule compares start frames)
  /// Rotation taking the covariances' frame into the world frame (e.g. R_world_sensor when
  /// the covariances are in the sensor frame); identity when they are already in world.
  Eigen::Matrix3d R_world_cov = Eigen::Matrix3d::Identity();
  /// Centre of the pose perturbation [m, world] (the sensor position).
  Eigen::Vector3d sensor_origin_world = Eigen::Vector3d::Zero();
  /// Optional 6×6 covariance of the frame's pose, order rx ry rz tx ty tz [rad, m], a
  /// perturbation applied on the left in the world frame about sensor_origin_world: the point
  /// p moves by δθ×(p − c) + δt. Adds J Σ Jᵀ, J = ∂z/∂(δθ, δt) = (dy, −dx, 0, 0, 0, 1).
  std::optional<Eigen::Matrix<double, 6, 6>> pose_covariance;
  /// The rig's calibration error, which every frame repeats (io::RigCalibrationSigma): the
  /// sensor's mounting rotation ω (in the body frame, R_world_body into the world), variance
  /// per axis [rad²], and the relative scale s of its depths [ratio²]. Registered with that
  /// rig, every step turned by ω and scaled by s too, so by this frame the chain has moved the
  /// sensor by rig_drift·ω + s·(c − rig_scale_origin) (the chain's start), and a point p at v =
  /// p − c from the sensor moves by δ = (rig_drift − [v]×R_world_body)·ω + s·(p −
  /// rig_scale_origin). Its height variance gains σω²·|δ's map ᵀn|² + σs²·(n·(p − o))², over
  /// n_z² (n the surface normal, else up), shared by the frames that see a cell: it bounds the
  /// published variance as the attitude's share does, whatever attitude_error_shared says, and
  /// leaves the heights alone. The defaults (no drift, o = c) are a single frame's.
  double rig_rotation_variance_rad2 = 0.0;
  double rig_scale_variance = 0.0;
  Eigen::Matrix3d rig_drift = Eigen::Matrix3d::Zero();         ///< [m/rad] δc = rig_drift·ω
  Eigen::Matrix3d R_world_body = Eigen::Matrix3d::Identity();  ///< ω's frame into the world
  std::optional<Eigen::Vector3d> rig_scale_origin;             ///< [m, world]; nullopt = the sensor
  /// Optional unit surface normals, one per point, in the covariances' frame (rotated by
  /// R_world_cov into the world); their sign does not matter. See slope_aware_variance.
  const std::vector<Eigen::Vector3d>* normals = nullptr;
  /// Points from this index on are fill between measured ones (stereo::StereoPointsResult::
  /// fill): each is fused only into a cell that none of the points before this index reach,
  /// else skipped and not counted in FusionStats (it measures nothing there). Default: none.
  std::size_t fill_from = std::numeric_limits<std::size_t>::max();
};

/// Part of a frame's points as the frame holds them (FuseFrame's no-copy form): in the frame
/// FuseFrame's pose moves into the world, with their covariances and normals in the frame
/// ctx.R_world_cov rotates (either may be null or empty), and a mask (null = all; 0 = not fused
/// and not counted).
struct FramePart {
  const std::vector<Eigen::Vector3d>* points = nullptr;
  const std::vector<Eigen::Matrix3d>* covariances = nullptr;
  const std::vector<Eigen::Vector3d>* normals = nullptr;
  const std::vector<unsigned char>* keep = nullptr;
};

/// What ClearSeenThrough did.
struct ClearingStats {
  std::size_t rays = 0;           ///< rays cast
  std::size_t cells_crossed = 0;  ///< published cells the rays passed over or under [count]
  std::size_t cells_cleared = 0;  ///< emptied [count]
};

/// For each of `cells`, how many of `cells` are the same cell (a frame's points per cell).
std::vector<std::uint32_t> CountPerCell(const std::vector<CellIndex>& cells);

/// The sparse elevation grid. Not thread-safe for writes; const queries are.
class ElevationMap {
 public:
  /// @throw std::invalid_argument if `options` are invalid (see Validate).
  explicit ElevationMap(const ElevationMapOptions& options = {});

  const ElevationMapOptions& options() const { return options_; }
  const GridIndex& index() const { return index_; }

  /// Fuses one frame of world points. `covariances` is empty (every point gets
  /// default_point_stddev_m) or one 3×3 covariance [m^2] per point in the frame rotated by
  /// ctx.R_world_cov; the height variance is r₃ᵀΣr₃ (r₃ = third row of R_world_cov), or the
  /// slope-aware one with normals, plus the pose term; with frame_points_correlated, the
  /// frame's points in a cell weigh as one. Never throws (a size mismatch makes the covariances
  /// or normals ignored, see `covariances_ignored`).
  FusionStats FuseFrame(const std::vector<Eigen::Vector3d>& points_world,
                        const std::vector<Eigen::Matrix3d>& covariances, const FrameContext& ctx);
  /// The same for a frame's measured points and its fill (ctx.fill_from and ctx.normals are
  /// ignored: the parts say), each moved into the world by `T_world_points` as it is read, so
  /// that nothing of the frame is copied (a KITTI frame's 700 000 points and covariances were,
  /// every frame). Gives the same as FuseFrame on the kept points moved and concatenated.
  FusionStats FuseFrame(const Eigen::Isometry3d& T_world_points, const FramePart& measured,
                        const FramePart& fill, const FrameContext& ctx);

  /// Visibility clearing after a frame is fused (options' clear_*): rays from `sensor_world` to
  /// the frame's points (`part`, moved into the world by `T_world_points`; one point per
  /// clear_ray_spacing_cells square) are walked over the grid; a published cell this frame did
  /// not update whose height lies above a ray by more than clear_margin_m + 3σ counts that ray;
  /// with clear_min_rays such rays the frame saw through it, and the cell is emptied once more
  /// frames saw through it than saw it (CellEvidence). Depth errors do not matter: they
  /// move a point along its ray, not the ray. Never throws.
  ClearingStats ClearSeenThrough(const Eigen::Isometry3d& T_world_points, const FramePart& part,
                                 const Eigen::Vector3d& sensor_world, std::uint32_t frame);

  /// Fuses one point with a height variance [m^2] (the rule above). Returns true if the point is
  /// now part of the primary (fused into it, or its candidate took over); false if it went into
  /// the candidate only, or was rejected or dropped. Never throws.
  bool FusePoint(const Eigen::Vector3d& point_world, double height_variance_m2, std::uint32_t frame,
                 FusionStats* stats = nullptr);

  /// Overwrites one cell (e.g. a simulator's true terrain): elevation and variance, count
  /// (default: min_support) and frames `frame` .. frame + min_frame_span − 1, so that the cell is
  /// published; min = max = elevation; no candidate.
  /// Allocates the tile. A non-finite elevation or a count of 0 empties the cell.
  void SetCell(CellIndex cell, double elevation_m, double variance_m2,
               std::optional<std::uint32_t> count = std::nullopt, std::uint32_t frame = 0);

  /// Grid-frame position of a world position [m]: R(θ)·(x, y).
  Eigen::Vector2d WorldToGrid(double x_m, double y_m) const;
  /// World position of a grid-frame position [m].
  Eigen::Vector2d GridToWorld(const Eigen::Vector2d& grid_m) const;
  /// The cell holding world (x, y); nullopt if non-finite or beyond the grid.
  std::optional<CellIndex> WorldToCell(double x_m, double y_m) const;
  /// World (x, y) of a cell's centre [m].
  Eigen::Vector2d CellCenterWorld(CellIndex cell) const;

  /// The cell's raw layers, published or not; nullopt if its tile was never allocated or the
  /// cell is empty.
  std::optional<CellValue> Cell(CellIndex cell) const;
  /// True if the cell's primary holds at least min_support points from frames spanning at
  /// least min_frame_span.
  bool Supported(const CellValue& value) const {
    return value.count >= static_cast<std::uint32_t>(options_.min_support) &&
           value.last_frame - value.first_frame >=
               static_cast<std::uint32_t>(options_.min_frame_span - 1);
  }
  /// The one test of what the map publishes (HeightAt, ForEachPublishedCell,
  /// io::WriteDemGeoTiff, io::WriteDemPreview): `value` (the layers of `cell`) is Supported and
  /// at least min_agreeing_neighbors of its 8 neighbours are Supported and agree with it.
  bool Published(CellIndex cell, const CellValue& value) const;
  /// Published height at world (x, y) [m]; NaN if the cell is not published or the input is
  /// non-finite.
  double HeightAt(double x_m, double y_m) const;
  /// Variance of that height [m^2]; NaN likewise.
  double VarianceAt(double x_m, double y_m) const;

  /// Calls f(CellIndex, const CellValue&) for every non-empty cell, published or not, tile by
  /// tile (unordered).
  template <typename F>
  void ForEachCell(F&& f) const {
    const int n = index_.geometry().tile_cells;
    for (const auto& [tile_index, tile] : tiles_) {
      if (tile->filled == 0) continue;
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          const std::size_t i = index_.LinearIndex({x, y});
          const CellValue& value = tile->cells[i].value;
          if (value.count == 0) continue;
          f(index_.TileLocalToCell(tile_index, {x, y}), value);
        }
      }
    }
  }

  /// ForEachCell restricted to the published cells (Published).
  template <typename F>
  void ForEachPublishedCell(F&& f) const {
    ForEachCell([&](CellIndex cell, const CellValue& value) {
      if (Published(cell, value)) f(cell, value);
    });
  }

  /// The tile holding `tile_index`, or nullptr if never allocated.
  const Tile* FindTile(TileIndex tile_index) const;
  /// Every allocated tile index (unordered).
  std::vector<TileIndex> TileIndices() const;
  std::size_t TileCount() const { return tiles_.size(); }
  /// Cells holding at least one point, published or not [count] (kept per tile: O(tiles)).
  std::size_t CellCount() const;
  /// Published cells [count] (scans every allocated cell).
  std::size_t PublishedCellCount() const;
  /// Bounding box of the cells ever written (grid cells); empty for a new map.
  const CellBounds& bounds() const { return bounds_; }
  /// Bytes held by the tiles' layers (not the hash table overhead).
  std::size_t MemoryBytes() const;
  /// Restoring a saved map (service/Checkpoint): replaces the tile at `tile_index` by `cells`
  /// (tile_cells² records as Tile stores them; its filled count is recounted) and `evidence`
  /// (as many, or none: then each cell's seen frames are bounded by its points and frames).
  /// @throw std::invalid_argument if `cells` or `evidence` has the wrong size.
  void RestoreTile(TileIndex tile_index, std::vector<CellRecord> cells,
                   std::vector<CellEvidence> evidence = {});
  /// ...and the counters that FuseFrame keeps beside the tiles.
  void RestoreCounters(const CellBounds& bounds, std::size_t covariances_ignored);

  /// Sizes mismatched between points and covariances (or normals) over all FuseFrame calls
  /// [count].
  std::size_t covariances_ignored() const { return covariances_ignored_; }

 private:
  Tile& TileFor(TileIndex tile_index, FusionStats* stats);
  // r gates the point, r_update is its variance in the Kalman update (>= r); an update leaves
  // the primary's published variance at least min(shared_m2, what it was before).
  bool FuseAt(CellIndex cell, double z, double r, double r_update, std::uint32_t frame,
              FusionStats* stats, double shared_m2 = 0.0);
  bool WithinGate(double h, double p, double z, double r) const;
  // FuseFrame's work: `count` points, the k-th from `at(k, &p_world, &cov, &normal, &fill)`
  // (false: masked out, not counted).
  template <typename At>
  FusionStats FuseFrameWith(std::size_t count, const At& at, bool use_cov, const FrameContext& ctx);
  // A point's height variance before the pose term (FuseFrame; normal may be null).
  double HeightVariance(const Eigen::Vector3d& p, const Eigen::Matrix3d* covariance,
                        const Eigen::Vector3d* normal, const Eigen::Matrix3d& R_world_cov,
                        CellIndex cell) const;
  std::optional<CellValue> PublishedAt(double x_m, double y_m) const;
  bool CandidateTakesOver(const CellRecord& record) const;

  ElevationMapOptions options_;
  GridIndex index_;
  double cos_ = 1.0;
  double sin_ = 0.0;
  std::unordered_map<TileIndex, std::unique_ptr<Tile>, TileIndexHash> tiles_;
  // The last tile touched: points arrive in spatially coherent runs. Moving a map clears the
  // source's cache (its tiles went with the move).
  struct TileCache {
    TileIndex index{};
    Tile* tile = nullptr;
    TileCache() = default;
    TileCache(TileCache&& other) noexcept : index(other.index), tile(other.tile) {
      other.tile = nullptr;
    }
    TileCache& operator=(TileCache&& other) noexcept {
      index = other.index;
      tile = other.tile;
      other.tile = nullptr;
      return *this;
    }
  };
  TileCache cache_;
  CellBounds bounds_;
  std::size_t covariances_ignored_ = 0;
};

}  // namespace rovermap::dem
