#include "eval/EvalPlots.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::eval {
namespace {

const cv::Scalar kBlack(0, 0, 0), kGrey(170, 170, 170), kWhite(255, 255, 255);
// Estimate colours (BGR): orange, blue, green, red, purple, brown.
const cv::Scalar kPalette[] = {{20, 120, 240}, {200, 110, 30}, {60, 160, 40},
                               {40, 40, 210},  {160, 60, 150}, {40, 90, 140}};
constexpr auto kFont = cv::FONT_HERSHEY_SIMPLEX;

cv::Scalar Colour(std::size_t k) { return kPalette[k % (sizeof(kPalette) / sizeof(kPalette[0]))]; }

std::string Format(double value, int precision = 3) {
  if (std::abs(value) < 1e-12) value = 0.0;  // no "-0" or "1e-14" at a zero tick
  std::ostringstream s;
  s << std::setprecision(precision) << value;
  return s.str();
}

// A tick value with as many decimals as the step needs ("1000", "0.25").
std::string TickLabel(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << (std::abs(value) < 1e-9 * step ? 0.0 : value);
  return s.str();
}

// 1, 2 or 5 × 10^n, giving about six ticks over `range`.
double NiceStep(double range) {
  const double raw = std::max(range, 1e-9) / 6.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * magnitude >= raw) return m * magnitude;
  return 10.0 * magnitude;
}

// A plotting area: data [x0, x1] × [y0, y1] onto the pixel rectangle `area` (y up).
struct Axes {
  cv::Rect area;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  cv::Point Map(double x, double y) const {
    return {
        area.x + static_cast<int>(std::lround((x - x0) / (x1 - x0) * area.width)),
        area.y + area.height - static_cast<int>(std::lround((y - y0) / (y1 - y0) * area.height))};
  }
};

void DrawAxes(cv::Mat& img, const Axes& a, const std::string& x_label, const std::string& y_label) {
  cv::rectangle(img, a.area, kGrey, 1);
  const double x_step = NiceStep(a.x1 - a.x0), y_step = NiceStep(a.y1 - a.y0);
  for (double x = std::ceil(a.x0 / x_step) * x_step; x <= a.x1 + 1e-9 * x_step; x += x_step) {
    const cv::Point p = a.Map(x, a.y0);
    cv::line(img, p, p + cv::Point(0, 5), kBlack, 1);
    cv::putText(img, TickLabel(x, x_step), p + cv::Point(-14, 22), kFont, 0.45, kBlack, 1,
                cv::LINE_AA);
  }
  for (double y = std::ceil(a.y0 / y_step) * y_step; y <= a.y1 + 1e-9 * y_step; y += y_step) {
    const cv::Point p = a.Map(a.x0, y);
    cv::line(img, p, p - cv::Point(5, 0), kBlack, 1);
    cv::putText(img, TickLabel(y, y_step), p + cv::Point(-60, 5), kFont, 0.45, kBlack, 1,
                cv::LINE_AA);
  }
  cv::putText(img, x_label, {a.area.x + a.area.width / 2 - 40, a.area.y + a.area.height + 45},
              kFont, 0.55, kBlack, 1, cv::LINE_AA);
  cv::putText(img, y_label, {8, a.area.y - 12}, kFont, 0.55, kBlack, 1, cv::LINE_AA);
}

void DrawLine(cv::Mat& img, const Axes& a, const std::vector<double>& xs,
              const std::vector<double>& ys, const cv::Scalar& colour, int thickness) {
  std::vector<cv::Point> points;
  points.reserve(xs.size());
  for (std::size_t k = 0; k < xs.size(); ++k) points.push_back(a.Map(xs[k], ys[k]));
  cv::polylines(img, points, false, colour, thickness, cv::LINE_AA);
}

void DrawLegend(cv::Mat& img, const std::vector<std::pair<std::string, cv::Scalar>>& items,
                cv::Point at) {
  for (const auto& [label, colour] : items) {
    cv::line(img, at, at + cv::Point(30, 0), colour, 3, cv::LINE_AA);
    cv::putText(img, label, at + cv::Point(38, 5), kFont, 0.5, kBlack, 1, cv::LINE_AA);
    at.y += 22;
  }
}

void WritePng(const std::filesystem::path& path, const cv::Mat& img) {
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png)) throw io::IoError(path.string() + ": PNG encoding failed");
  io::WriteFileAtomically(path,
                          std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

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
  Axes axes{cv::Rect(80, 60, 800, 450), 0.0, x1, 0.0, y1 * 1.05};
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
  for (int r = 0; r < c.height; ++r)
    for (int col = 0; col < c.width; ++col) {
      const float e = c.error_m[static_cast<std::size_t>(r) * c.width + col];
      if (std::isfinite(e)) grid.at<cv::Vec3b>(r, col) = colour_of(e);
    }
  if (!c.north_row_first) cv::flip(grid, grid, 0);  // draw north up
  const double scale = std::min(700.0 / c.width, 700.0 / c.height);
  cv::Mat map;
  cv::resize(grid, map,
             cv::Size(std::max(1, static_cast<int>(c.width * scale)),
                      std::max(1, static_cast<int>(c.height * scale))),
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
  cv::putText(img, "DEM - reference [m], " + Format(c.cell_size_m) + " m cells, grey: not compared",
              {20, 25}, kFont, 0.5, kBlack, 1, cv::LINE_AA);
  cv::putText(img,
              "rmse " + Format(c.rmse_m) + " m, bias " + Format(c.bias_m) + " m, p95 " +
                  Format(c.p95_abs_m) + " m, coverage " + Format(c.coverage),
              {20, 48}, kFont, 0.5, kBlack, 1, cv::LINE_AA);
  WritePng(path, img);
}

}  // namespace rovermap::eval
