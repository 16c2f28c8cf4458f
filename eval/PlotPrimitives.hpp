#pragma once
// Plot primitives shared by the PNG figures (eval --plot, replay's drift.png): axes with nice
// ticks, polylines, legends, a colour palette, and the atomic PNG writer. OpenCV drawing.

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

namespace rovermap::eval::plot {

extern const cv::Scalar kBlack, kGrey, kWhite;
constexpr auto kFont = cv::FONT_HERSHEY_SIMPLEX;

/// The k-th colour of the palette (BGR: orange, blue, green, red, purple, brown; cycles).
cv::Scalar Colour(std::size_t k);

/// `value` with `precision` significant digits, "0" for |value| < 1e-12.
std::string Format(double value, int precision = 3);

/// 1, 2 or 5 × 10^n, giving about six ticks over `range`.
double NiceStep(double range);

/// A plotting area: data [x0, x1] × [y0, y1] onto the pixel rectangle `area` (y up).
struct Axes {
  cv::Rect area;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  cv::Point Map(double x, double y) const;
};

/// Frame, ticks and labels of `a`.
void DrawAxes(cv::Mat& img, const Axes& a, const std::string& x_label, const std::string& y_label);
/// The polyline through (xs[k], ys[k]).
void DrawLine(cv::Mat& img, const Axes& a, const std::vector<double>& xs,
              const std::vector<double>& ys, const cv::Scalar& colour, int thickness);
/// One line of legend per item, from `at` downwards, on a framed, mostly opaque white box.
void DrawLegend(cv::Mat& img, const std::vector<std::pair<std::string, cv::Scalar>>& items,
                cv::Point at);
/// How far below `at.y - 20` a legend of `items` entries reaches [px]: a plot whose legend sits
/// at its area's top (at.y = area.y + 20) keeps its data below this to leave the legend clear.
int LegendDepth(std::size_t items);
/// The factor by which a panel of `height` px raises its top value so that its data stays below
/// a legend of `items` entries.
double LegendHeadroom(int height, std::size_t items);
/// Encodes `img` as PNG and writes it atomically. @throw io::IoError naming `path`.
void WritePng(const std::filesystem::path& path, const cv::Mat& img);

}  // namespace rovermap::eval::plot
