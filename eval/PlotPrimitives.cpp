#include "eval/PlotPrimitives.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/TickLabel.hpp"

namespace rovermap::eval::plot {

const cv::Scalar kBlack(0, 0, 0), kGrey(170, 170, 170), kWhite(255, 255, 255);

namespace {

// Estimate colours (BGR): orange, blue, green, red, purple, brown.
const cv::Scalar kPalette[] = {{20, 120, 240}, {200, 110, 30}, {60, 160, 40},
                               {40, 40, 210},  {160, 60, 150}, {40, 90, 140}};

// Legend geometry [px]: one row per entry; the box starts above the first row's line and ends
// below the last row's text; panels place the first row 20 px below their top.
constexpr int kLegendRow = 22, kLegendBoxAbove = 13, kLegendBoxBelow = 4, kLegendOffset = 20;
constexpr int kLegendMargin = 6;  // between the box and the data under it

}  // namespace

cv::Scalar Colour(std::size_t k) { return kPalette[k % (sizeof(kPalette) / sizeof(kPalette[0]))]; }

std::string Format(double value, int precision) {
  if (std::abs(value) < 1e-12) value = 0.0;  // no "-0" or "1e-14" at a zero tick
  std::ostringstream s;
  s << std::setprecision(precision) << value;
  return s.str();
}

double NiceStep(double range) {
  const double raw = std::max(range, 1e-9) / 6.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * magnitude >= raw) return m * magnitude;
  return 10.0 * magnitude;
}

cv::Point Axes::Map(double x, double y) const {
  return {area.x + static_cast<int>(std::lround((x - x0) / (x1 - x0) * area.width)),
          area.y + area.height - static_cast<int>(std::lround((y - y0) / (y1 - y0) * area.height))};
}

void DrawAxes(cv::Mat& img, const Axes& a, const std::string& x_label, const std::string& y_label) {
  cv::rectangle(img, a.area, kGrey, 1);
  const double x_step = NiceStep(a.x1 - a.x0), y_step = NiceStep(a.y1 - a.y0);
  for (double x = std::ceil(a.x0 / x_step) * x_step; x <= a.x1 + 1e-9 * x_step; x += x_step) {
    const cv::Point p = a.Map(x, a.y0);
    cv::line(img, p, p + cv::Point(0, 5), kBlack, 1);
    cv::putText(img, io::TickLabel(x, x_step), p + cv::Point(-14, 22), kFont, 0.45, kBlack, 1,
                cv::LINE_AA);
  }
  for (double y = std::ceil(a.y0 / y_step) * y_step; y <= a.y1 + 1e-9 * y_step; y += y_step) {
    const cv::Point p = a.Map(a.x0, y);
    cv::line(img, p, p - cv::Point(5, 0), kBlack, 1);
    cv::putText(img, io::TickLabel(y, y_step), p + cv::Point(-60, 5), kFont, 0.45, kBlack, 1,
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
  if (items.empty()) return;
  // A framed, mostly opaque box behind the entries: a curve that runs through the legend's
  // corner no longer crosses its text, and still shows faintly through.
  int text_width = 0;
  for (const auto& item : items) {
    int baseline = 0;
    text_width = std::max(text_width, cv::getTextSize(item.first, kFont, 0.5, 1, &baseline).width);
  }
  const cv::Rect box = cv::Rect(at.x - 8, at.y - kLegendBoxAbove, 38 + text_width + 16,
                                kLegendRow * static_cast<int>(items.size()) + kLegendBoxBelow) &
                       cv::Rect(0, 0, img.cols, img.rows);
  if (!box.empty()) {
    cv::Mat region = img(box);
    const cv::Mat white(region.size(), region.type(), kWhite);
    cv::addWeighted(white, 0.8, region, 0.2, 0.0, region);
    cv::rectangle(img, box, kGrey, 1);
  }
  for (const auto& [label, colour] : items) {
    cv::line(img, at, at + cv::Point(30, 0), colour, 3, cv::LINE_AA);
    cv::putText(img, label, at + cv::Point(38, 5), kFont, 0.5, kBlack, 1, cv::LINE_AA);
    at.y += kLegendRow;
  }
}

int LegendDepth(std::size_t items) {
  return kLegendOffset - kLegendBoxAbove + kLegendRow * static_cast<int>(items) + kLegendBoxBelow +
         kLegendMargin;
}

double LegendHeadroom(int height, std::size_t items) {
  const int free = height - LegendDepth(items);
  return free > height / 3 ? static_cast<double>(height) / free : 1.5;
}

void WritePng(const std::filesystem::path& path, const cv::Mat& img) {
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png)) throw io::IoError(path.string() + ": PNG encoding failed");
  io::WriteFileAtomically(path,
                          std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

}  // namespace rovermap::eval::plot
