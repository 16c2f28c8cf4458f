#include "mosaic/Fusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rovermap::mosaic::detail {

CellFusion::CellFusion(std::size_t cells)
    : cells_(cells),
      weight_(cells, 0.0),
      weighted_sum_(cells, 0.0),
      count_(cells, 0.0),
      carried_(cells, 0.0) {}

void CellFusion::Add(WarpedLayers layers) {
  for (std::size_t c = 0; c < cells_; ++c) {
    const float z = layers.elevation_m[c];
    const float sigma = layers.stddev_m[c];
    if (!Usable(z, sigma)) continue;
    const double s = std::max(static_cast<double>(sigma), kMinStddevM);
    const double w = 1.0 / (s * s);
    weight_[c] += w;
    weighted_sum_[c] += w * z;
    if (std::isfinite(layers.count[c])) count_[c] += layers.count[c];
    if (!layers.disagreement.empty() && std::isfinite(layers.disagreement[c])) {
      carried_[c] += layers.disagreement[c];
    }
  }
  inputs_.push_back(std::move(layers));
}

FusedLayers CellFusion::Finish(double disagreement_sigma) const {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  FusedLayers out;
  out.elevation_m.assign(cells_, kNaN);
  out.stddev_m.assign(cells_, kNaN);
  out.count.assign(cells_, kNaN);
  out.disagreement.assign(cells_, kNaN);
  for (std::size_t c = 0; c < cells_; ++c) {
    if (weight_[c] <= 0.0) continue;
    const double z = weighted_sum_[c] / weight_[c];
    const double variance = 1.0 / weight_[c];
    double disagreeing = carried_[c];
    for (const WarpedLayers& input : inputs_) {
      const float z_i = input.elevation_m[c];
      const float sigma_i = input.stddev_m[c];
      if (!Usable(z_i, sigma_i)) continue;
      const double s_i = std::max(static_cast<double>(sigma_i), kMinStddevM);
      const double combined = std::sqrt(s_i * s_i + variance);
      if (std::abs(z_i - z) > disagreement_sigma * combined) disagreeing += 1.0;
    }
    out.elevation_m[c] = static_cast<float>(z);
    out.stddev_m[c] = static_cast<float>(std::sqrt(variance));
    out.count[c] = static_cast<float>(count_[c]);
    out.disagreement[c] = static_cast<float>(disagreeing);
    ++out.valid_cells;
  }
  return out;
}

}  // namespace rovermap::mosaic::detail
