#include "terrain/TerrainLayers.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "terrain/TerrainTiles.hpp"

namespace rovermap::terrain {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kRadToDeg = 180.0 / M_PI;

// The weighted moments of a region's cells, summed from its top-left corner: a footprint's are
// four lookups. i is the column and j the row from the region's anchor, z the height less the
// region's mean (so that the sums stay far from double's precision).
enum Moment { kW, kWi, kWj, kWii, kWij, kWjj, kWz, kWiz, kWjz, kWzz, kN, kSigma2, kMoments };
using Sums = std::array<double, kMoments>;

struct Region {
  int anchor_row = 0, anchor_col = 0;  ///< grid row and column where the moments count from
  int row0 = 0, col0 = 0;              ///< the region's first grid row and column
  int rows = 0, cols = 0;
  double z0 = 0.0;           ///< [m] the heights' mean, subtracted
  std::vector<Sums> prefix;  ///< (rows + 1) × (cols + 1)
  cv::Mat z_max, z_min;      ///< each cell's highest and lowest height over the footprint
  cv::Mat sigma_max;         ///< the largest σ over the footprint (with σ)

  Sums Box(int r1, int c1, int r2, int c2) const {  // rows r1..r2, cols c1..c2 inclusive
    const auto at = [&](int r, int c) -> const Sums& {
      return prefix[static_cast<std::size_t>(r) * (cols + 1) + c];
    };
    const Sums& a = at(r2 + 1, c2 + 1);
    const Sums& b = at(r1, c2 + 1);
    const Sums& c = at(r2 + 1, c1);
    const Sums& d = at(r1, c1);
    Sums s;
    for (int k = 0; k < kMoments; ++k) s[k] = a[k] - b[k] - c[k] + d[k];
    return s;
  }
};

// The footprints of the tile whose whole extent starts at grid row and column (anchor_row +
// hy, anchor_col + hx): its cells and the halo around them, as far as the grid (and its halo)
// reaches. The moments' coordinates count from the anchor, and cells outside the grid hold no
// height, so a tile's layers depend on the heights within its footprints alone, not on where
// the grid ends: a map that grows gives the same values, to the bit, for the same ground.
Region BuildRegion(const GridView& g, int anchor_row, int anchor_col, int tile, int hx, int hy) {
  Region region;
  region.anchor_row = anchor_row;
  region.anchor_col = anchor_col;
  region.row0 = std::max(anchor_row, -hy);
  region.col0 = std::max(anchor_col, -hx);
  region.rows = std::min(anchor_row + tile + 2 * hy, g.height + hy) - region.row0;
  region.cols = std::min(anchor_col + tile + 2 * hx, g.width + hx) - region.col0;
  const int rows = region.rows, cols = region.cols;
  const auto inside = [&](int r, int c) {
    const int gr = region.row0 + r, gc = region.col0 + c;
    return gr >= 0 && gr < g.height && gc >= 0 && gc < g.width;
  };
  const auto index = [&](int r, int c) {
    return static_cast<std::size_t>(region.row0 + r) * static_cast<std::size_t>(g.width) +
           static_cast<std::size_t>(region.col0 + c);
  };
  constexpr float kNoHeight = std::numeric_limits<float>::quiet_NaN();
  const auto height_at = [&](int r, int c) {
    return inside(r, c) ? g.elevation_m[index(r, c)] : kNoHeight;
  };
  double sum = 0.0;
  std::size_t n = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const float z = height_at(r, c);
      if (std::isfinite(z)) {
        sum += z;
        ++n;
      }
    }
  }
  region.z0 = n > 0 ? sum / static_cast<double>(n) : 0.0;
  region.prefix.assign(static_cast<std::size_t>(rows + 1) * (cols + 1), Sums{});
  cv::Mat high(rows, cols, CV_32F), low(rows, cols, CV_32F), sigma(rows, cols, CV_32F);
  constexpr float kBig = std::numeric_limits<float>::max();
  for (int r = 0; r < rows; ++r) {
    Sums row_sum{};
    for (int c = 0; c < cols; ++c) {
      const float z = height_at(r, c);
      const float s = g.stddev_m != nullptr && inside(r, c) ? g.stddev_m[index(r, c)] : 0.0f;
      const bool valid = std::isfinite(z) && (g.stddev_m == nullptr || (std::isfinite(s) && s > 0));
      high.at<float>(r, c) = valid ? z : -kBig;
      low.at<float>(r, c) = valid ? z : kBig;
      sigma.at<float>(r, c) = valid ? s : 0.0f;
      if (valid) {
        const double w = g.stddev_m != nullptr ? 1.0 / (static_cast<double>(s) * s) : 1.0;
        const double i = region.col0 - anchor_col + c, j = region.row0 - anchor_row + r;
        const double dz = z - region.z0;
        const Sums cell = {w,          w * i,       w * j,  w * i * i,
                           w * i * j,  w * j * j,   w * dz, w * i * dz,
                           w * j * dz, w * dz * dz, 1.0,    static_cast<double>(s) * s};
        for (int k = 0; k < kMoments; ++k) row_sum[k] += cell[k];
      }
      const Sums& above = region.prefix[static_cast<std::size_t>(r) * (cols + 1) + c + 1];
      Sums& here = region.prefix[static_cast<std::size_t>(r + 1) * (cols + 1) + c + 1];
      for (int k = 0; k < kMoments; ++k) here[k] = above[k] + row_sum[k];
    }
  }
  const cv::Mat kernel = cv::Mat::ones(2 * hy + 1, 2 * hx + 1, CV_8U);
  // Beyond the region nothing counts: OpenCV's default border value for dilate and erode
  // leaves the extremes to the cells inside.
  cv::dilate(high, region.z_max, kernel);
  cv::erode(low, region.z_min, kernel);
  if (g.stddev_m != nullptr) cv::dilate(sigma, region.sigma_max, kernel);
  return region;
}

struct Decision {
  double q = 0.0;          // (value + kσ) / limit
  bool uncertain = false;  // |value − limit| < kσ
};

Decision Decide(double value, double sigma, double limit, double k) {
  return {(value + k * sigma) / limit, std::abs(value - limit) < k * sigma};
}

}  // namespace

std::string CheckOptions(const TerrainOptions& o) {
  if (!(o.footprint_m > 0.0) || !std::isfinite(o.footprint_m))
    return "terrain.footprint_m must be > 0";
  if (!(o.max_slope_deg > 0.0 && o.max_slope_deg < 90.0))
    return "terrain.max_slope_deg must be in (0, 90)";
  if (!(o.max_step_m > 0.0) || !std::isfinite(o.max_step_m))
    return "terrain.max_step_m must be > 0";
  if (!(o.max_roughness_m > 0.0) || !std::isfinite(o.max_roughness_m))
    return "terrain.max_roughness_m must be > 0";
  if (!(o.min_coverage > 0.0 && o.min_coverage <= 1.0))
    return "terrain.min_coverage must be in (0, 1]";
  if (!(o.uncertainty_sigmas >= 0.0) || !std::isfinite(o.uncertainty_sigmas))
    return "terrain.uncertainty_sigmas must be >= 0";
  if (o.tile_cells < 16 || o.tile_cells > 4096) return "terrain.tile_cells must be in [16, 4096]";
  return "";
}

TileLayout LayoutFor(const GridView& g, const TerrainOptions& o) {
  if (const std::string problem = CheckOptions(o); !problem.empty()) throw TerrainError(problem);
  if (!(g.cell_x_m > 0.0) || !(g.cell_y_m > 0.0) || g.width <= 0 || g.height <= 0 ||
      g.elevation_m == nullptr) {
    throw TerrainError("terrain: the DEM has no cells or no positive cell spacing");
  }
  const double cells_x = o.footprint_m / g.cell_x_m, cells_y = o.footprint_m / g.cell_y_m;
  if (cells_x < 2.0 - 1e-9 || cells_y < 2.0 - 1e-9) {
    throw TerrainError("terrain.footprint_m " + std::to_string(o.footprint_m) +
                       " m is smaller than two cells of the DEM (" + std::to_string(g.cell_x_m) +
                       " × " + std::to_string(g.cell_y_m) + " m)");
  }
  // An odd number of cells, centred on the cell, nearest to the footprint; an even number
  // rounds up (0.6 m on 5 cm cells: 13, not 11 because 0.6 / 0.05 is 11.999… in binary).
  constexpr double kRoundingSlack = 1e-9;
  TileLayout layout;
  layout.hx = static_cast<int>(std::lround((cells_x - 1.0) / 2.0 + kRoundingSlack));
  layout.hy = static_cast<int>(std::lround((cells_y - 1.0) / 2.0 + kRoundingSlack));
  if (2 * layout.hx + 1 > g.width || 2 * layout.hy + 1 > g.height) {
    throw TerrainError("terrain.footprint_m " + std::to_string(o.footprint_m) +
                       " m is larger than the DEM (" + std::to_string(g.width) + " × " +
                       std::to_string(g.height) + " cells)");
  }
  // Tiles start where the global index is a multiple of tile_cells, so that a grid that grows
  // keeps its tiles where they were.
  const auto spans = [&](std::int64_t origin, int size) {
    std::vector<TileSpan> out;
    const std::int64_t tile = o.tile_cells;
    for (int begin = 0; begin < size;) {
      const std::int64_t global = origin + begin;
      const std::int64_t index = global >= 0 ? global / tile : -((-global + tile - 1) / tile);
      const int end = static_cast<int>(std::min<std::int64_t>(size, (index + 1) * tile - origin));
      out.push_back({begin, end, index});
      begin = end;
    }
    return out;
  };
  layout.tile = o.tile_cells;
  layout.origin_row = g.origin_row;
  layout.origin_col = g.origin_col;
  layout.rows = spans(g.origin_row, g.height);
  layout.cols = spans(g.origin_col, g.width);
  return layout;
}

TerrainLayers EmptyLayers(const GridView& g, const TileLayout& layout) {
  TerrainLayers out;
  out.width = g.width;
  out.height = g.height;
  out.has_sigma = g.stddev_m != nullptr;
  out.footprint_cols = 2 * layout.hx + 1;
  out.footprint_rows = 2 * layout.hy + 1;
  const std::size_t cells = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  for (const auto layer : kLayerFields) (out.*layer).assign(cells, kNaN);
  return out;
}

void ComputeTile(const GridView& g, const TerrainOptions& o, const TileLayout& layout,
                 const TileSpan& rows, const TileSpan& cols, TerrainLayers* out) {
  const int hx = layout.hx, hy = layout.hy;
  const double footprint_cells = static_cast<double>(out->footprint_cols) * out->footprint_rows;
  const double dx = g.cell_x_m, dy = g.cell_y_m, k = o.uncertainty_sigmas;
  const auto anchor = [&](const TileSpan& span, std::int64_t origin, int halo) {
    return static_cast<int>(span.index * layout.tile - origin) - halo;
  };
  const Region region = BuildRegion(g, anchor(rows, layout.origin_row, hy),
                                    anchor(cols, layout.origin_col, hx), layout.tile, hx, hy);
  for (int r = rows.begin; r < rows.end; ++r) {
    for (int c = cols.begin; c < cols.end; ++c) {
      const int lr = r - region.row0, lc = c - region.col0;
      const Sums s = region.Box(lr - hy, lc - hx, lr + hy, lc + hx);
      const double n = s[kN];
      if (n < 3.0 || n < o.min_coverage * footprint_cells) continue;
      // The plane z = β0 + β1 u + β2 v, u and v [m] east and south of the cell's centre
      // (the slope's size does not depend on the axes' signs).
      const double a = c - region.anchor_col, b = r - region.anchor_row;
      const double su = dx * (s[kWi] - a * s[kW]);
      const double sv = dy * (s[kWj] - b * s[kW]);
      const double suu = dx * dx * (s[kWii] - 2.0 * a * s[kWi] + a * a * s[kW]);
      const double svv = dy * dy * (s[kWjj] - 2.0 * b * s[kWj] + b * b * s[kW]);
      const double suv = dx * dy * (s[kWij] - a * s[kWj] - b * s[kWi] + a * b * s[kW]);
      Eigen::Matrix3d normal;
      normal << s[kW], su, sv, su, suu, suv, sv, suv, svv;
      const Eigen::Vector3d rhs(s[kWz], dx * (s[kWiz] - a * s[kWz]), dy * (s[kWjz] - b * s[kWz]));
      // Cells all on one line give no plane.
      const double scale = normal.diagonal().prod();
      if (!(normal.determinant() > 1e-9 * scale)) continue;
      const Eigen::Matrix3d inverse = normal.inverse();
      const Eigen::Vector3d beta = inverse * rhs;
      const double rss = std::max(0.0, s[kWzz] - beta.dot(rhs));
      // The heights' noise, cell to cell: with σ, the weights are 1/σ² and the fit's
      // covariance is c (AᵀWA)⁻¹ with c = min(1, χ²/dof). A DEM's σ also holds errors its
      // cells share (the pose's), which tilt or lift a footprint as a whole and so leave its
      // residuals smaller than σ says: c < 1 scales σ down to the scatter the cells show.
      // Residuals above σ are the ground's relief, not noise (c stays 1). Without σ, the
      // residuals' own variance stands for the noise (σ = 1 per cell, c = RSS/dof).
      const double dof = n - 3.0;
      const double c_noise = out->has_sigma ? (dof > 0.0 ? std::min(1.0, rss / dof) : 1.0)
                                            : (dof > 0.0 ? rss / dof : 0.0);
      const Eigen::Matrix2d cov = c_noise * inverse.bottomRightCorner<2, 2>();
      const Eigen::Vector2d grad = beta.tail<2>();
      const double grad_norm = grad.norm();
      const double var_grad =
          grad_norm > 1e-12 ? grad.dot(cov * grad) / (grad_norm * grad_norm) : 0.5 * cov.trace();
      const double slope = std::atan(grad_norm);
      const double slope_sigma = std::sqrt(std::max(0.0, var_grad)) / (1.0 + grad_norm * grad_norm);
      const double roughness = std::sqrt(rss / s[kW]);
      // The noise alone would read as this much roughness; a step is the difference of two
      // heights, the noisiest of the footprint's at worst.
      const double mean_var = out->has_sigma ? s[kSigma2] / n : 1.0;
      const double max_sigma =
          out->has_sigma ? static_cast<double>(region.sigma_max.at<float>(lr, lc)) : 1.0;
      const double roughness_sigma = std::sqrt(c_noise * mean_var);
      const double step = static_cast<double>(region.z_max.at<float>(lr, lc)) -
                          static_cast<double>(region.z_min.at<float>(lr, lc));
      const double step_sigma = std::sqrt(2.0 * c_noise) * max_sigma;

      const Decision d_slope =
          Decide(slope * kRadToDeg, slope_sigma * kRadToDeg, o.max_slope_deg, k);
      const Decision d_step = Decide(step, step_sigma, o.max_step_m, k);
      const Decision d_rough = Decide(roughness, roughness_sigma, o.max_roughness_m, k);
      const double q = std::max({d_slope.q, d_step.q, d_rough.q});
      const std::size_t i = static_cast<std::size_t>(r) * g.width + c;
      out->slope_deg[i] = static_cast<float>(slope * kRadToDeg);
      out->slope_sigma_deg[i] = static_cast<float>(slope_sigma * kRadToDeg);
      out->roughness_m[i] = static_cast<float>(roughness);
      out->step_m[i] = static_cast<float>(step);
      out->traversability[i] = static_cast<float>(std::clamp(1.0 - q, 0.0, 1.0));
      out->uncertain[i] = d_slope.uncertain || d_step.uncertain || d_rough.uncertain ? 1.0f : 0.0f;
    }
  }
}

void CountLayers(const TerrainOptions& o, TerrainLayers* out) {
  // The hazard count reads the layers as written (the point estimates against the limits).
  out->known = out->hazard = out->uncertain_cells = out->benign = 0;
  for (std::size_t i = 0; i < out->traversability.size(); ++i) {
    if (std::isnan(out->traversability[i])) continue;
    ++out->known;
    if (out->uncertain[i] > 0.0f) ++out->uncertain_cells;
    if (out->traversability[i] > 0.0f) ++out->benign;
    if (out->slope_deg[i] >= o.max_slope_deg || out->step_m[i] >= o.max_step_m ||
        out->roughness_m[i] >= o.max_roughness_m)
      ++out->hazard;
  }
}

TerrainLayers ComputeTerrain(const GridView& g, const TerrainOptions& o) {
  const TileLayout layout = LayoutFor(g, o);
  TerrainLayers out = EmptyLayers(g, layout);
  const int tiles_x = static_cast<int>(layout.cols.size());
  const int tiles = static_cast<int>(layout.rows.size()) * tiles_x;
#pragma omp parallel for schedule(dynamic)
  for (int t = 0; t < tiles; ++t) {
    ComputeTile(g, o, layout, layout.rows[t / tiles_x], layout.cols[t % tiles_x], &out);
  }
  CountLayers(o, &out);
  return out;
}

TerrainLayers ComputeTerrainByRows(const GridShape& shape, const TerrainOptions& o,
                                   const ReadRows& read, const WriteRows& write) {
  const float probe = 0.0f;  // the whole grid's checks and tiles, without its heights
  GridView whole{shape.width,    shape.height, shape.cell_x_m,
                 shape.cell_y_m, &probe,       shape.has_sigma ? &probe : nullptr};
  const TileLayout layout = LayoutFor(whole, o);
  TerrainLayers total;
  total.width = shape.width;
  total.height = shape.height;
  total.has_sigma = shape.has_sigma;
  total.footprint_cols = 2 * layout.hx + 1;
  total.footprint_rows = 2 * layout.hy + 1;
  std::vector<float> elevation, sigma;
  for (const TileSpan& rows : layout.rows) {
    // The tile row and the footprint's halo above and below it, as far as the grid goes.
    const int strip0 = std::max(0, rows.begin - layout.hy);
    const int strip1 = std::min(shape.height, rows.end + layout.hy);
    read(strip0, strip1 - strip0, &elevation, shape.has_sigma ? &sigma : nullptr);
    const std::size_t cells = static_cast<std::size_t>(shape.width) * (strip1 - strip0);
    if (elevation.size() != cells || (shape.has_sigma && sigma.size() != cells))
      throw TerrainError("terrain: rows read do not match the grid's width");
    GridView strip{shape.width,    strip1 - strip0,  shape.cell_x_m,
                   shape.cell_y_m, elevation.data(), shape.has_sigma ? sigma.data() : nullptr};
    strip.origin_row = strip0;
    TileLayout strip_layout = layout;
    strip_layout.origin_row = strip0;
    TerrainLayers layers = EmptyLayers(strip, strip_layout);
    const TileSpan local{rows.begin - strip0, rows.end - strip0, rows.index};
    const int tiles = static_cast<int>(layout.cols.size());
#pragma omp parallel for schedule(dynamic)
    for (int t = 0; t < tiles; ++t)
      ComputeTile(strip, o, strip_layout, local, layout.cols[t], &layers);
    // Only the tile row's own cells: the halo rows' footprints are not whole here.
    TerrainLayers out;
    out.width = shape.width;
    out.height = rows.end - rows.begin;
    out.has_sigma = shape.has_sigma;
    out.footprint_cols = total.footprint_cols;
    out.footprint_rows = total.footprint_rows;
    const std::size_t first = static_cast<std::size_t>(local.begin) * shape.width;
    const std::size_t count = static_cast<std::size_t>(out.height) * shape.width;
    for (const auto layer : kLayerFields) {
      (out.*layer).assign((layers.*layer).begin() + first, (layers.*layer).begin() + first + count);
    }
    CountLayers(o, &out);
    total.known += out.known;
    total.hazard += out.hazard;
    total.uncertain_cells += out.uncertain_cells;
    total.benign += out.benign;
    write(rows.begin, out);
  }
  return total;
}

}  // namespace rovermap::terrain
