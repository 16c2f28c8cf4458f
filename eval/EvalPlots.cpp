#include "eval/EvalPlots.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "eval/PlotPrimitives.hpp"
#include "io/IoError.hpp"

namespace rovermap::eval {
namespace {

using namespace plot;

std::vector<const PlotEntry*> Usable(const std::vector<PlotEntry>& entries) {
  std::vector<const PlotEntry*> usable;
  for (const PlotEntry& e : entries)
    if (e.metrics && e.metrics->status == MetricStatus::kOk) usable.push_back(&e);
  if (usable.empty()) throw std::invalid_argument("trajectory plot: no evaluated estimate");
  return usable;
}

}  // namespace

void WriteTrajectoryPlot(const std::filesystem::path& path, const std::vector<PlotEntry>& entries) {
  const std::vector<const PlotEntry*> usable = Usable(entries);
  // The two axes along which the ground truth extends most.
  const auto& gt = usable.front()->metrics->groundtruth_positions;
  Eigen::Vector3d lo = gt.front(), hi = gt.front();
  for (const auto& p : gt) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3d extent = hi - lo;
  int u = 0, v = 1;
  if (extent[2] > std::min(extent[0], extent[1])) (extent[0] < extent[1] ? u : v) = 2;
  if (u > v) std::swap(u, v);
  double x0 = lo[u], x1 = hi[u], y0 = lo[v], y1 = hi[v];
  for (const PlotEntry* e : usable)
    for (const auto& p : e->metrics->origin_aligned_positions) {
      x0 = std::min(x0, p[u]), x1 = std::max(x1, p[u]);
      y0 = std::min(y0, p[v]), y1 = std::max(y1, p[v]);
    }
  // Equal scale on both axes, 5 % margin.
  const int size = 700;
  const double span = std::max({x1 - x0, y1 - y0, 1e-6}) * 1.1;
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  Axes axes{cv::Rect(80, 60, size, size), cx - span / 2, cx + span / 2, cy - span / 2,
            cy + span / 2};
  cv::Mat img(size + 130, size + 110, CV_8UC3, kWhite);
  const char* names[] = {"x [m]", "y [m]", "z [m]"};
  DrawAxes(img, axes, names[u], names[v]);
  auto draw = [&](const std::vector<Eigen::Vector3d>& positions, const cv::Scalar& colour) {
    std::vector<double> xs, ys;
    for (const auto& p : positions) xs.push_back(p[u]), ys.push_back(p[v]);
    DrawLine(img, axes, xs, ys, colour, 2);
  };
  draw(gt, kBlack);
  std::vector<std::pair<std::string, cv::Scalar>> legend = {{"ground truth", kBlack}};
  for (std::size_t k = 0; k < usable.size(); ++k) {
    draw(usable[k]->metrics->origin_aligned_positions, Colour(k));
    legend.emplace_back(usable[k]->label, Colour(k));
  }
  cv::circle(img, axes.Map(gt.front()[u], gt.front()[v]), 5, kBlack, 2, cv::LINE_AA);
  cv::putText(img, "top view, estimates aligned at the first pose (circle: start)", {80, 25}, kFont,
              0.55, kBlack, 1, cv::LINE_AA);
  DrawLegend(img, legend, {axes.area.x + 15, axes.area.y + 20});
  WritePng(path, img);
}

void WriteErrorPlot(const std::filesystem::path& path, const std::vector<PlotEntry>& entries) {
  const std::vector<const PlotEntry*> usable = Usable(entries);
  double x1 = 1e-6, y1 = 1e-6;
  for (const PlotEntry* e : usable) {
    const TrajectoryMetrics& m = *e->metrics;
    x1 = std::max(x1, m.distance_m.back());
    for (double err : m.ate_origin_error_m) y1 = std::max(y1, err);
    for (double err : m.ate_error_m) y1 = std::max(y1, err);
  }
  // Headroom for the legend at the top, one entry per estimate.
  Axes axes{cv::Rect(80, 60, 800, 450), 0.0, x1, 0.0,
            y1 * 1.05 * LegendHeadroom(450, usable.size())};
  cv::Mat img(580, 920, CV_8UC3, kWhite);
  DrawAxes(img, axes, "distance travelled [m]", "position error [m]");
  std::vector<std::pair<std::string, cv::Scalar>> legend;
  for (std::size_t k = 0; k < usable.size(); ++k) {
    const TrajectoryMetrics& m = *usable[k]->metrics;
    DrawLine(img, axes, m.distance_m, m.ate_origin_error_m, Colour(k), 2);
    DrawLine(img, axes, m.distance_m, m.ate_error_m, Colour(k), 1);
    legend.emplace_back(usable[k]->label + " (ATE origin " + Format(m.ate_origin_m.rmse) +
                            " m, ATE " + Format(m.ate_m.rmse) + " m)",
                        Colour(k));
  }
  cv::putText(img, "error vs distance: thick = aligned at the first pose, thin = SE(3) aligned",
              {80, 25}, kFont, 0.55, kBlack, 1, cv::LINE_AA);
  DrawLegend(img, legend, {axes.area.x + 15, axes.area.y + 20});
  WritePng(path, img);
}

void WriteDemErrorPlot(const std::filesystem::path& path, const DemComparison& c) {
  if (c.cells == 0 || c.width <= 0 || c.height <= 0)
    throw std::invalid_argument("DEM error plot: no compared cell");
  const double limit = std::max(std::isfinite(c.p95_abs_m) ? c.p95_abs_m : 0.0, 1e-3);
  // Blue (below) - white (0) - red (above), grey where not compared.
  cv::Mat grid(c.height, c.width, CV_8UC3, cv::Scalar(200, 200, 200));
  auto colour_of = [&](double e) {
    const double s = std::clamp(e / limit, -1.0, 1.0);
    const auto fade = static_cast<unsigned char>(std::lround(255.0 * (1.0 - std::abs(s))));
    return s >= 0 ? cv::Vec3b(fade, fade, 255) : cv::Vec3b(255, fade, fade);
  };
  int row0 = c.height, row1 = -1, col0 = c.width, col1 = -1;
  for (int r = 0; r < c.height; ++r)
    for (int col = 0; col < c.width; ++col) {
      const float e = c.error_m[static_cast<std::size_t>(r) * c.width + col];
      if (!std::isfinite(e)) continue;
      grid.at<cv::Vec3b>(r, col) = colour_of(e);
      row0 = std::min(row0, r);
      row1 = std::max(row1, r);
      col0 = std::min(col0, col);
      col1 = std::max(col1, col);
    }
  if (row1 < 0) throw std::invalid_argument("DEM error plot: no compared cell");
  // Only the compared area and a margin: a traverse's DEM is a small patch of a site-wide
  // reference, and drawn whole it would be a few pixels.
  const int margin = std::max(2, std::max(row1 - row0, col1 - col0) / 20);
  row0 = std::max(0, row0 - margin);
  col0 = std::max(0, col0 - margin);
  row1 = std::min(c.height - 1, row1 + margin);
  col1 = std::min(c.width - 1, col1 + margin);
  grid = grid(cv::Rect(col0, row0, col1 - col0 + 1, row1 - row0 + 1)).clone();
  if (!c.north_row_first) cv::flip(grid, grid, 0);  // draw north up
  const double scale = std::min(700.0 / grid.cols, 700.0 / grid.rows);
  cv::Mat map;
  cv::resize(grid, map,
             cv::Size(std::max(1, static_cast<int>(grid.cols * scale)),
                      std::max(1, static_cast<int>(grid.rows * scale))),
             0, 0, cv::INTER_NEAREST);
  cv::Mat img(map.rows + 110, map.cols + 160, CV_8UC3, kWhite);
  map.copyTo(img(cv::Rect(20, 60, map.cols, map.rows)));
  // Colour bar.
  const int bar_x = map.cols + 40, bar_h = std::max(map.rows, 100);
  for (int y = 0; y < std::min(bar_h, img.rows - 60); ++y) {
    const double e = limit * (1.0 - 2.0 * y / static_cast<double>(bar_h - 1));
    cv::line(img, {bar_x, 60 + y}, {bar_x + 20, 60 + y}, cv::Scalar(colour_of(e)), 1);
  }
  cv::putText(img, "+" + Format(limit) + " m", {bar_x + 25, 70}, kFont, 0.45, kBlack, 1,
              cv::LINE_AA);
  cv::putText(img, "0", {bar_x + 25, 60 + bar_h / 2 + 5}, kFont, 0.45, kBlack, 1, cv::LINE_AA);
  cv::putText(img, "-" + Format(limit) + " m", {bar_x + 25, 60 + bar_h - 2}, kFont, 0.45, kBlack, 1,
              cv::LINE_AA);
  const std::string within =
      std::isfinite(c.within_2sigma) ? ", " + Format(c.within_2sigma) + " within 2 sigma" : "";
  cv::putText(
      img,
      "DEM - reference [m], " + Format(c.cell_size_m) + " m cells, grey: not compared" + within,
      {20, 25}, kFont, 0.5, kBlack, 1, cv::LINE_AA);
  cv::putText(img,
              "rmse " + Format(c.rmse_m) + " m, bias " + Format(c.bias_m) + " m, p95 " +
                  Format(c.p95_abs_m) + " m, " + Format(c.coverage) + " of the reference mapped",
              {20, 48}, kFont, 0.5, kBlack, 1, cv::LINE_AA);
  WritePng(path, img);
}

}  // namespace rovermap::eval
