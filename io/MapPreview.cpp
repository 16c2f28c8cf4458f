#include "io/MapPreview.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/TickLabel.hpp"

namespace rovermap::io {
namespace {

const cv::Scalar kBackground(255, 255, 255);
const cv::Scalar kText(30, 30, 30);

// 1, 2 or 5 times a power of ten, at most `value`.
double NiceBelow(double value) {
  const double p = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * p <= value) return m * p;
  }
  return p;
}

void EncodeAndWrite(const std::filesystem::path& path, const cv::Mat& image) {
  std::vector<unsigned char> png;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, png);
  } catch (const cv::Exception& e) {
    throw IoError(path.string() + ": cannot encode PNG (" + e.what() + ")");
  }
  if (!ok) throw IoError(path.string() + ": cannot encode PNG");
  WriteFileAtomically(path,
                      std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

// The map's cells and the trajectories' points on one pixel grid, decimated by `step` cells per
// pixel (the cell nearest each pixel).
struct PreviewGrid {
  dem::CellIndex lo, hi;  ///< grid cells covered, inclusive
  std::int64_t step = 1;  ///< [cells] per pixel
  cv::Mat height;         ///< CV_32F [m], NaN where no cell; row 0 north
};

// The cells of the map and of the trajectories' points, and the decimation that fits them in
// `max_map_px`; `height` sized, all NaN.
PreviewGrid PreviewBounds(const DemLayers& layers,
                          const std::vector<PreviewTrajectory>& trajectories, int max_map_px) {
  dem::CellBounds bounds;
  bounds.Extend(layers.min);
  bounds.Extend(layers.max);
  constexpr double kMaxCell = 1e12;  // a point this far out is not drawn (nor sizes the image)
  for (const PreviewTrajectory& trajectory : trajectories) {
    for (const Eigen::Vector3d& p : trajectory.points) {
      const Eigen::Vector2d g = layers.WorldToGrid(p.x(), p.y()) / layers.cell_size_m;
      if (!(std::abs(g.x()) < kMaxCell && std::abs(g.y()) < kMaxCell)) continue;
      bounds.Extend({static_cast<std::int64_t>(std::floor(g.x())),
                     static_cast<std::int64_t>(std::floor(g.y()))});
    }
  }
  PreviewGrid grid;
  grid.lo = bounds.Min();
  grid.hi = bounds.Max();
  const std::int64_t cols_cells = grid.hi.x - grid.lo.x + 1;
  const std::int64_t rows_cells = grid.hi.y - grid.lo.y + 1;
  grid.step = std::max<std::int64_t>(
      1, (std::max(cols_cells, rows_cells) + max_map_px - 1) / std::max(1, max_map_px));
  const int w = static_cast<int>((cols_cells + grid.step - 1) / grid.step);
  const int h = static_cast<int>((rows_cells + grid.step - 1) / grid.step);
  grid.height = cv::Mat(h, w, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  return grid;
}

// Each pixel of `grid` takes the highest elevation of its cells.
void Rasterise(const DemLayers& layers, PreviewGrid* grid) {
  for (int r = 0; r < layers.height; ++r) {
    const std::int64_t cy = layers.max.y - r;
    const int row = static_cast<int>((grid->hi.y - cy) / grid->step);
    const float* z_row = layers.elevation_m.data() + static_cast<std::size_t>(r) * layers.width;
    for (int c = 0; c < layers.width; ++c) {
      const float z = z_row[c];
      if (std::isnan(z)) continue;
      const int col = static_cast<int>((layers.min.x + c - grid->lo.x) / grid->step);
      float& px = grid->height.at<float>(row, col);
      px = std::isnan(px) ? z : std::max(px, z);
    }
  }
}

// The heights the colour map spans, and the extremes beyond it.
struct ColourRange {
  float z_min = 0.0f, z_max = 1.0f;                ///< [m] the ends of the colour map
  float z_lowest = 0.0f, z_highest = 0.0f;         ///< [m] the extremes of the heights
  bool clipped_low = false, clipped_high = false;  ///< an extreme lies beyond its end
};

// The colour range spans the heights between two quantiles, not the extremes: a few wrong
// cells (a spike at a crater rim) would otherwise squeeze the whole map into a few colours.
// Heights beyond take the end colours; the colour bar says so. `height` has a valid pixel.
ColourRange ColourRangeOf(const cv::Mat& height, double colour_quantile) {
  std::vector<float> heights;
  for (int r = 0; r < height.rows; ++r) {
    for (int c = 0; c < height.cols; ++c) {
      if (const float z = height.at<float>(r, c); !std::isnan(z)) heights.push_back(z);
    }
  }
  const auto quantile = [&heights](double q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(heights.size() - 1));
    std::nth_element(heights.begin(), heights.begin() + k, heights.end());
    return heights[static_cast<std::size_t>(k)];
  };
  ColourRange range;
  range.z_lowest = *std::min_element(heights.begin(), heights.end());
  range.z_highest = *std::max_element(heights.begin(), heights.end());
  const double q = std::clamp(colour_quantile, 0.0, 0.49);
  range.z_min = quantile(q);
  range.z_max = quantile(1.0 - q);
  range.clipped_low = range.z_lowest < range.z_min;
  range.clipped_high = range.z_highest > range.z_max;
  if (!(range.z_max > range.z_min)) range.z_max = range.z_min + 1.0f;
  return range;
}

// How much sunlight each pixel takes (Horn-like central differences), blended with
// `hillshade_weight`: 1 in full sun; NaN where no cell (CV_64F).
cv::Mat ShadeFactor(const cv::Mat& height, double pixel_m, const MapPreviewOptions& options) {
  const int h = height.rows, w = height.cols;
  const double az = options.sun_azimuth_deg * M_PI / 180.0;
  const double el = options.sun_elevation_deg * M_PI / 180.0;
  const Eigen::Vector3d sun(std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), std::sin(el));
  const auto at = [&](int r, int c, float fallback) {
    if (r < 0 || c < 0 || r >= h || c >= w) return fallback;
    const float z = height.at<float>(r, c);
    return std::isnan(z) ? fallback : z;
  };
  cv::Mat factor(h, w, CV_64F, cv::Scalar(std::numeric_limits<double>::quiet_NaN()));
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const float z = height.at<float>(r, c);
      if (std::isnan(z)) continue;
      const double dzdx = (at(r, c + 1, z) - at(r, c - 1, z)) / (2.0 * pixel_m);
      const double dzdy = (at(r - 1, c, z) - at(r + 1, c, z)) / (2.0 * pixel_m);  // row 0 north
      const Eigen::Vector3d normal = Eigen::Vector3d(-dzdx, -dzdy, 1.0).normalized();
      const double shade = std::max(0.0, normal.dot(sun));
      factor.at<double>(r, c) = (1.0 - options.hillshade_weight) + options.hillshade_weight * shade;
    }
  }
  return factor;
}

cv::Vec3b Shaded(const cv::Vec3b& in, double f) {
  return cv::Vec3b(cv::saturate_cast<uchar>(in[0] * f), cv::saturate_cast<uchar>(in[1] * f),
                   cv::saturate_cast<uchar>(in[2] * f));
}

// The colour map of the heights, shaded by a sun; white where no cell.
cv::Mat ShadedRelief(const cv::Mat& height, const ColourRange& range, double pixel_m,
                     const MapPreviewOptions& options) {
  const int h = height.rows, w = height.cols;
  const float z_min = range.z_min, z_max = range.z_max;
  cv::Mat normalized(h, w, CV_8U);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const float z = height.at<float>(r, c);
      normalized.at<unsigned char>(r, c) =
          std::isnan(z) ? 0
                        : static_cast<unsigned char>(
                              255.0f * std::clamp((z - z_min) / (z_max - z_min), 0.0f, 1.0f));
    }
  }
  cv::Mat colour;
  cv::applyColorMap(normalized, colour, cv::COLORMAP_TURBO);
  const cv::Mat shade = ShadeFactor(height, pixel_m, options);
  cv::Mat map_image(h, w, CV_8UC3, kBackground);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const double f = shade.at<double>(r, c);
      if (!std::isnan(f)) map_image.at<cv::Vec3b>(r, c) = Shaded(colour.at<cv::Vec3b>(r, c), f);
    }
  }
  return map_image;
}

struct LegendLine {
  std::string label;
  cv::Scalar colour;
  int width;
};

// Draws each trajectory on `map_image` (`zoom` image pixels per grid pixel): a coloured line
// with a black outline and its start marked. Returns the legend lines of the labelled ones.
std::vector<LegendLine> DrawTrajectories(cv::Mat* map_image, const DemLayers& layers,
                                         const PreviewGrid& grid, int zoom,
                                         const std::vector<PreviewTrajectory>& trajectories) {
  std::vector<LegendLine> legend;
  for (const PreviewTrajectory& trajectory : trajectories) {
    const cv::Scalar colour(trajectory.rgb[2], trajectory.rgb[1], trajectory.rgb[0]);
    if (!trajectory.label.empty())
      legend.push_back({trajectory.label, colour, std::max(1, trajectory.width_px)});
    std::vector<cv::Point> line;
    for (const Eigen::Vector3d& p : trajectory.points) {
      if (!p.allFinite()) continue;
      const Eigen::Vector2d g = layers.WorldToGrid(p.x(), p.y());
      const double gx = g.x() / layers.cell_size_m - static_cast<double>(grid.lo.x);
      const double gy = static_cast<double>(grid.hi.y + 1) - g.y() / layers.cell_size_m;
      line.emplace_back(static_cast<int>(std::lround(gx / grid.step * zoom)),
                        static_cast<int>(std::lround(gy / grid.step * zoom)));
    }
    if (!line.empty()) {
      const int width = std::max(1, trajectory.width_px);
      cv::polylines(*map_image, line, false, cv::Scalar(0, 0, 0), width + 2, cv::LINE_AA);
      cv::polylines(*map_image, line, false, colour, width, cv::LINE_AA);
      cv::circle(*map_image, line.front(), 5, cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA);
      cv::circle(*map_image, line.front(), 3, colour, cv::FILLED, cv::LINE_AA);
    }
  }
  return legend;
}

// Canvas: the map at (kMargin, kMargin), the colour bar on its right, the scale bar, north
// arrow and legend below.
constexpr int kMargin = 20;
struct CanvasLayout {
  int rows = 0, cols = 0;
  int map_cols = 0;  ///< [px] the map's width on the canvas
  int bottom = 0;    ///< [px] the band under the map: scale bar, north arrow, legend
  int bar_x = 0, bar_top = kMargin, bar_h = 0, bar_w = 20;  ///< colour bar [px]
};

CanvasLayout LayOut(const cv::Mat& map_image, std::size_t legend_lines) {
  constexpr int kLegendWidth = 110;
  CanvasLayout layout;
  layout.map_cols = map_image.cols;
  layout.bottom = 50 + 20 * static_cast<int>(legend_lines);
  layout.bar_h = std::max(100, map_image.rows);
  layout.rows = std::max(map_image.rows, layout.bar_h + 20) + 2 * kMargin + layout.bottom;
  layout.cols = map_image.cols + 2 * kMargin + kLegendWidth;
  layout.bar_x = kMargin * 2 + map_image.cols;
  return layout;
}

// The colour bar in metres with its ticks, and the extremes beyond its ends.
void DrawColourBar(cv::Mat* canvas, const CanvasLayout& l, const ColourRange& colours) {
  const int bar_x = l.bar_x, bar_top = l.bar_top, bar_h = l.bar_h, bar_w = l.bar_w;
  const float z_min = colours.z_min, z_max = colours.z_max;
  // The colour map once (applyColorMap builds its table on every call: one call per row of the
  // bar took most of a publication's dem.png).
  cv::Mat ramp(256, 1, CV_8U), ramp_rgb;
  for (int v = 0; v < 256; ++v) ramp.at<unsigned char>(v, 0) = static_cast<unsigned char>(v);
  cv::applyColorMap(ramp, ramp_rgb, cv::COLORMAP_TURBO);
  for (int i = 0; i < bar_h; ++i) {
    const cv::Vec3b c = ramp_rgb.at<cv::Vec3b>(255 - 255 * i / std::max(1, bar_h - 1), 0);
    cv::line(*canvas, {bar_x, bar_top + i}, {bar_x + bar_w, bar_top + i}, cv::Scalar(c), 1);
  }
  const double range = z_max - z_min;
  const double tick = NiceBelow(range / 4.0);
  for (double v = std::ceil(z_min / tick) * tick; v <= z_max + 1e-9; v += tick) {
    const int y = bar_top + static_cast<int>((z_max - v) / range * (bar_h - 1));
    cv::line(*canvas, {bar_x + bar_w, y}, {bar_x + bar_w + 5, y}, kText, 1);
    cv::putText(*canvas, TickLabel(v, tick), {bar_x + bar_w + 8, y + 5}, cv::FONT_HERSHEY_SIMPLEX,
                0.45, kText, 1, cv::LINE_AA);
  }
  cv::putText(*canvas, "m", {bar_x, bar_top + bar_h + 15}, cv::FONT_HERSHEY_SIMPLEX, 0.45, kText, 1,
              cv::LINE_AA);
  // Heights beyond the bar's range: the extreme, at the end it is clipped to.
  if (colours.clipped_high) {
    cv::putText(*canvas, "max " + TickLabel(colours.z_highest, tick), {bar_x - 4, bar_top - 6},
                cv::FONT_HERSHEY_SIMPLEX, 0.4, kText, 1, cv::LINE_AA);
  }
  if (colours.clipped_low) {
    cv::putText(*canvas, "min " + TickLabel(colours.z_lowest, tick),
                {bar_x - 4, bar_top + bar_h + 30}, cv::FONT_HERSHEY_SIMPLEX, 0.4, kText, 1,
                cv::LINE_AA);
  }
}

// Under the map: a scale bar of a nice length (`px_per_m` canvas pixels per metre), the north
// arrow, and one legend line per labelled trajectory.
void DrawScaleBarAndLegend(cv::Mat* canvas, const CanvasLayout& l, double px_per_m,
                           const std::vector<LegendLine>& legend) {
  const double bar_m = NiceBelow(l.map_cols / px_per_m / 4.0);
  const int bar_px = static_cast<int>(std::lround(bar_m * px_per_m));
  const int sy = canvas->rows - l.bottom + 10;
  cv::rectangle(*canvas, cv::Rect(kMargin, sy - 5, bar_px, 6), kText, cv::FILLED);
  cv::putText(*canvas, TickLabel(bar_m, bar_m) + " m", {kMargin + bar_px + 8, sy + 2},
              cv::FONT_HERSHEY_SIMPLEX, 0.5, kText, 1, cv::LINE_AA);
  const int nx = kMargin + l.map_cols - 10;
  cv::arrowedLine(*canvas, {nx, sy + 8}, {nx, sy - 18}, kText, 2, cv::LINE_AA, 0, 0.35);
  cv::putText(*canvas, "N", {nx - 24, sy + 2}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kText, 1,
              cv::LINE_AA);
  int ly = sy + 30;
  for (const LegendLine& line : legend) {
    cv::line(*canvas, {kMargin, ly - 4}, {kMargin + 30, ly - 4}, cv::Scalar(0, 0, 0),
             line.width + 2, cv::LINE_AA);
    cv::line(*canvas, {kMargin, ly - 4}, {kMargin + 30, ly - 4}, line.colour, line.width,
             cv::LINE_AA);
    cv::putText(*canvas, line.label, {kMargin + 38, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kText, 1,
                cv::LINE_AA);
    ly += 20;
  }
}

// terrain.png's classes, worst first: a pixel of several cells shows the worst of them.
constexpr float kRankHazard = -2.0f;
constexpr float kRankUncertain = -1.0f;
const cv::Vec3b kHazardColour(0, 0, 140);        // dark red (BGR)
const cv::Vec3b kUncertainColour(200, 60, 200);  // purple
const cv::Vec3b kUnknownColour(215, 215, 215);   // grey: heights, but no layers

// Red (barely passable) through yellow to green (benign), for traversability in (0, 1].
cv::Vec3b TraversabilityColour(float t) {
  const float c = std::clamp(t, 0.0f, 1.0f);
  const auto red = static_cast<uchar>(c < 0.5f ? 255.0f : 255.0f * (1.0f - c) * 2.0f);
  const auto green = static_cast<uchar>(c < 0.5f ? 255.0f * c * 2.0f : 255.0f);
  return cv::Vec3b(0, green, red);
}

// The traversability bar and the classes' swatches right of the map.
void DrawTraversabilityBar(cv::Mat* canvas, const CanvasLayout& l) {
  const int bar_x = l.bar_x, bar_top = l.bar_top, bar_h = l.bar_h, bar_w = l.bar_w;
  for (int i = 0; i < bar_h; ++i) {
    const float t = 1.0f - static_cast<float>(i) / static_cast<float>(std::max(1, bar_h - 1));
    cv::line(*canvas, {bar_x, bar_top + i}, {bar_x + bar_w, bar_top + i},
             cv::Scalar(TraversabilityColour(std::max(t, 0.01f))), 1);
  }
  for (double v : {0.0, 0.5, 1.0}) {
    const int y = bar_top + static_cast<int>((1.0 - v) * (bar_h - 1));
    cv::line(*canvas, {bar_x + bar_w, y}, {bar_x + bar_w + 5, y}, kText, 1);
    cv::putText(*canvas, TickLabel(v, 0.5), {bar_x + bar_w + 8, y + 5}, cv::FONT_HERSHEY_SIMPLEX,
                0.45, kText, 1, cv::LINE_AA);
  }
  int y = bar_top + bar_h + 12;
  for (const auto& [label, colour] :
       {std::pair{"hazard", kHazardColour}, std::pair{"uncertain", kUncertainColour},
        std::pair{"unknown", kUnknownColour}}) {
    cv::rectangle(*canvas, cv::Rect(bar_x, y, 12, 12), cv::Scalar(colour), cv::FILLED);
    cv::rectangle(*canvas, cv::Rect(bar_x, y, 12, 12), kText, 1);
    cv::putText(*canvas, label, {bar_x + 16, y + 11}, cv::FONT_HERSHEY_SIMPLEX, 0.4, kText, 1,
                cv::LINE_AA);
    y += 18;
  }
}

// The map drawn, framed and annotated on a canvas (the bar's side left to `draw_bar`), written.
template <typename DrawBar>
void ComposeAndWrite(const std::filesystem::path& path, cv::Mat map_image, const DemLayers& layers,
                     const PreviewGrid& grid, double pixel_m,
                     const std::vector<PreviewTrajectory>& trajectories, DrawBar draw_bar,
                     int extra_bar_rows) {
  // Upscale small maps so the annotations stay legible.
  const int zoom = std::max(1, 600 / std::max(grid.height.cols, grid.height.rows));
  if (zoom > 1) cv::resize(map_image, map_image, {}, zoom, zoom, cv::INTER_NEAREST);
  const std::vector<LegendLine> legend =
      DrawTrajectories(&map_image, layers, grid, zoom, trajectories);
  CanvasLayout layout = LayOut(map_image, legend.size());
  layout.rows = std::max(layout.rows, layout.bar_h + extra_bar_rows + 2 * kMargin + layout.bottom);
  cv::Mat canvas(layout.rows, layout.cols, CV_8UC3, kBackground);
  map_image.copyTo(canvas(cv::Rect(kMargin, kMargin, map_image.cols, map_image.rows)));
  cv::rectangle(canvas, cv::Rect(kMargin - 1, kMargin - 1, map_image.cols + 2, map_image.rows + 2),
                kText, 1);
  draw_bar(&canvas, layout);
  DrawScaleBarAndLegend(&canvas, layout, zoom / pixel_m, legend);
  EncodeAndWrite(path, canvas);
}

void WriteNoData(const std::filesystem::path& path) {
  cv::Mat image(120, 320, CV_8UC3, kBackground);
  cv::putText(image, "no data", {110, 65}, cv::FONT_HERSHEY_SIMPLEX, 0.8, kText, 2);
  EncodeAndWrite(path, image);
}

}  // namespace

void WriteDemPreview(const std::filesystem::path& path, const dem::ElevationMap& map,
                     const std::vector<Eigen::Vector3d>& trajectory_world,
                     const MapPreviewOptions& options) {
  std::vector<PreviewTrajectory> trajectories;
  if (!trajectory_world.empty()) trajectories.push_back({"", {255, 255, 255}, trajectory_world});
  WriteDemPreview(path, map, trajectories, options);
}

void WriteDemPreview(const std::filesystem::path& path, const dem::ElevationMap& map,
                     const std::vector<PreviewTrajectory>& trajectories,
                     const MapPreviewOptions& options) {
  DemLayers layers;
  try {
    layers = RasteriseDem(map);
  } catch (const IoError& e) {
    throw IoError(path.string() + ": " + e.what());
  }
  WriteDemPreview(path, layers, trajectories, options);
}

void WriteDemPreview(const std::filesystem::path& path, const DemLayers& layers,
                     const std::vector<PreviewTrajectory>& trajectories,
                     const MapPreviewOptions& options) {
  if (layers.valid_cells == 0 || !(layers.cell_size_m > 0.0)) return WriteNoData(path);
  PreviewGrid grid = PreviewBounds(layers, trajectories, options.max_map_px);
  Rasterise(layers, &grid);
  const ColourRange colours = ColourRangeOf(grid.height, options.colour_quantile);
  const double pixel_m = layers.cell_size_m * static_cast<double>(grid.step);
  ComposeAndWrite(
      path, ShadedRelief(grid.height, colours, pixel_m, options), layers, grid, pixel_m,
      trajectories,
      [&colours](cv::Mat* canvas, const CanvasLayout& l) { DrawColourBar(canvas, l, colours); }, 0);
}

void WriteTerrainPreview(const std::filesystem::path& path, const DemLayers& layers,
                         const terrain::TerrainLayers& terrain,
                         const std::vector<PreviewTrajectory>& trajectories,
                         const MapPreviewOptions& options) {
  if (terrain.width != layers.width || terrain.height != layers.height ||
      terrain.traversability.size() != layers.elevation_m.size()) {
    throw std::invalid_argument("WriteTerrainPreview: the layers are not on the DEM's grid");
  }
  if (layers.valid_cells == 0 || !(layers.cell_size_m > 0.0)) return WriteNoData(path);
  PreviewGrid grid = PreviewBounds(layers, trajectories, options.max_map_px);
  Rasterise(layers, &grid);
  // Each pixel shows the worst class of its cells: hazard, uncertain, then the lowest
  // traversability.
  cv::Mat rank(grid.height.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (int r = 0; r < layers.height; ++r) {
    const int row = static_cast<int>((grid.hi.y - (layers.max.y - r)) / grid.step);
    for (int c = 0; c < layers.width; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * layers.width + c;
      const float t = terrain.traversability[i];
      if (std::isnan(t)) continue;
      const float value = terrain.uncertain[i] > 0.0f ? kRankUncertain : t > 0.0f ? t : kRankHazard;
      float& px = rank.at<float>(row, static_cast<int>((layers.min.x + c - grid.lo.x) / grid.step));
      px = std::isnan(px) ? value : std::min(px, value);
    }
  }
  const double pixel_m = layers.cell_size_m * static_cast<double>(grid.step);
  const cv::Mat shade = ShadeFactor(grid.height, pixel_m, options);
  cv::Mat map_image(grid.height.size(), CV_8UC3, kBackground);
  for (int r = 0; r < map_image.rows; ++r) {
    for (int c = 0; c < map_image.cols; ++c) {
      const double f = shade.at<double>(r, c);
      const float v = rank.at<float>(r, c);
      if (std::isnan(f)) continue;
      const cv::Vec3b colour = std::isnan(v)         ? kUnknownColour
                               : v == kRankHazard    ? kHazardColour
                               : v == kRankUncertain ? kUncertainColour
                                                     : TraversabilityColour(v);
      map_image.at<cv::Vec3b>(r, c) = Shaded(colour, f);
    }
  }
  ComposeAndWrite(path, map_image, layers, grid, pixel_m, trajectories, DrawTraversabilityBar, 70);
}

}  // namespace rovermap::io
