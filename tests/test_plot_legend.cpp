// The figures' legends (eval --plot, replay's drift.png): they sit at the top left of a panel,
// so the panel leaves headroom above its data, and their text is drawn on a box that keeps any
// curve still passing under it from crossing the text.
#include <gtest/gtest.h>

#include <vector>

#include "eval/PlotPrimitives.hpp"

namespace plot = rovermap::eval::plot;

namespace {

// Pixels of `img` inside `rect` that are not white: what a curve left there.
int InkIn(const cv::Mat& img, const cv::Rect& rect) {
  int ink = 0;
  for (int y = rect.y; y < rect.y + rect.height; ++y)
    for (int x = rect.x; x < rect.x + rect.width; ++x)
      ink += img.at<cv::Vec3b>(y, x) != cv::Vec3b(255, 255, 255);
  return ink;
}

}  // namespace

// A series whose peak lies under the legend's corner (the drift panel's frame-12 spike): with
// the headroom, every pixel of the curve stays below the legend's box.
TEST(PlotLegend, HeadroomKeepsThePeakBelowTheLegend) {
  const cv::Rect area(80, 60, 800, 250);
  const std::vector<double> xs = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  const std::vector<double> ys = {0.0, 0.3, 0.5, 1.0, 0.4, 0.2, 0.3, 0.1, 0.2, 0.3, 0.2};
  for (const std::size_t items : {1u, 2u, 4u}) {
    const double top = 1.1 * plot::LegendHeadroom(area.height, items);
    const plot::Axes axes{area, 0.0, 10.0, 0.0, top};
    cv::Mat img(400, 920, CV_8UC3, plot::kWhite);
    plot::DrawLine(img, axes, xs, ys, plot::Colour(1), 2);
    // The band the legend's box covers: from the area's top to its depth.
    const cv::Rect legend_band(area.x, area.y, area.width, plot::LegendDepth(items) - 6);
    EXPECT_EQ(InkIn(img, legend_band), 0) << items << " legend entries";
    // Without the headroom the same peak runs into the band.
    const plot::Axes tight{area, 0.0, 10.0, 0.0, 1.1};
    cv::Mat tight_img(400, 920, CV_8UC3, plot::kWhite);
    plot::DrawLine(tight_img, tight, xs, ys, plot::Colour(1), 2);
    EXPECT_GT(InkIn(tight_img, legend_band), 0) << items << " legend entries";
  }
  // A panel too small for its legend still gets a finite, bounded headroom.
  EXPECT_DOUBLE_EQ(plot::LegendHeadroom(60, 4), 1.5);
}

// A curve drawn before the legend shows only faintly under its box, and the box is framed.
TEST(PlotLegend, BoxCoversWhatRunsUnderTheText) {
  cv::Mat img(200, 600, CV_8UC3, plot::kWhite);
  const cv::Point at(95, 80);
  // A black horizontal line through the legend's first text row, right of its colour swatch.
  cv::line(img, {0, at.y + 3}, {599, at.y + 3}, plot::kBlack, 3);
  plot::DrawLegend(img, {{"x", plot::Colour(0)}, {"y", plot::Colour(1)}}, at);
  // Just right of the short labels, still inside the box: the line is 80 % washed out.
  int baseline = 0;
  const int text_width = cv::getTextSize("x", plot::kFont, 0.5, 1, &baseline).width;
  const cv::Vec3b under = img.at<cv::Vec3b>(at.y + 3, at.x + 38 + text_width + 5);
  EXPECT_GE(under[0], 0.8 * 255 - 1);
  // Outside the box the line is untouched.
  EXPECT_EQ(img.at<cv::Vec3b>(at.y + 3, 20), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(img.at<cv::Vec3b>(at.y + 3, 590), cv::Vec3b(0, 0, 0));
  // The frame: grey pixels left of the swatch.
  const cv::Vec3b frame = img.at<cv::Vec3b>(at.y, at.x - 8);
  EXPECT_EQ(frame, cv::Vec3b(170, 170, 170));
  // No items, no box.
  cv::Mat empty(50, 50, CV_8UC3, plot::kWhite);
  plot::DrawLegend(empty, {}, {10, 20});
  EXPECT_EQ(cv::countNonZero(empty.reshape(1) != 255), 0);
}
