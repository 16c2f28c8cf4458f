#pragma once
// Internal to mosaic/: inverse-variance fusion of the inputs warped onto one window.

#include <cmath>
#include <cstddef>
#include <vector>

#include "mosaic/Warp.hpp"

namespace rovermap::mosaic::detail {

/// Smallest σ a cell is weighed with [m]: a σ of 0 would take an infinite weight.
constexpr double kMinStddevM = 1e-6;

/// The fused bands of a window (NaN where no input has data).
struct FusedLayers {
  std::vector<float> elevation_m;
  std::vector<float> stddev_m;
  std::vector<float> count;
  std::vector<float> disagreement;
  std::size_t valid_cells = 0;
};

/// Per cell, with w_i = 1/σ_i²: z = Σ w_i z_i / Σ w_i, σ = (Σ w_i)^-1/2, counts summed. The sums
/// are associative (a fused cell is the input (z, σ) with the same Σ w_i and Σ w_i z_i), so a
/// mosaic of partial mosaics is the mosaic of all inputs up to float rounding.
class CellFusion {
 public:
  explicit CellFusion(std::size_t cells);
  /// Adds one input's layers (kept for the disagreement count of Finish).
  void Add(WarpedLayers layers);
  /// The fused bands. Disagreement: the inputs with |z_i − z| > disagreement_sigma ·
  /// sqrt(σ_i² + σ²), plus the disagreement an input mosaic carries.
  FusedLayers Finish(double disagreement_sigma) const;

 private:
  std::size_t cells_;
  std::vector<double> weight_;        // Σ 1/σ_i² [1/m²]
  std::vector<double> weighted_sum_;  // Σ z_i/σ_i² [1/m]
  std::vector<double> count_;         // Σ count_i
  std::vector<double> carried_;       // Σ disagreement of input mosaics
  std::vector<WarpedLayers> inputs_;
};

/// Whether an input's cell can be fused: finite height and σ.
inline bool Usable(float z, float sigma) { return std::isfinite(z) && std::isfinite(sigma); }

}  // namespace rovermap::mosaic::detail
