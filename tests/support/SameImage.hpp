#pragma once
// Pixel-for-pixel equality of two images, for the frame sources' tests.

#include <opencv2/core.hpp>

namespace rovermap::testing {

inline bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

}  // namespace rovermap::testing
