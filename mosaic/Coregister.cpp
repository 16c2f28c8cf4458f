#include "mosaic/Coregister.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "mosaic/Fusion.hpp"
#include "registration/Icp.hpp"

namespace rovermap::mosaic::detail {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
// Source cells this close to the target's edge are left out of the registration [cells].
constexpr int kEdgeCells = 2;
// Matching rounds (see Coregister), until a round moves less than these.
constexpr int kMaxRounds = 8;
constexpr double kRoundTranslationM = 5e-4;
constexpr double kRoundRotationDeg = 1e-3;

// Height differences of `source` against `target` over the cells both cover.
struct Agreement {
  std::size_t cells = 0;
  std::size_t disagreeing = 0;
  double rms_m = 0.0;
};

Agreement Compare(const WarpedLayers& source, const FusedLayers& target, double k) {
  Agreement a;
  double sum_sq = 0.0;
  for (std::size_t c = 0; c < source.elevation_m.size(); ++c) {
    if (!Usable(source.elevation_m[c], source.stddev_m[c]) ||
        !Usable(target.elevation_m[c], target.stddev_m[c])) {
      continue;
    }
    const double dz = static_cast<double>(source.elevation_m[c]) - target.elevation_m[c];
    const double s = source.stddev_m[c];
    const double t = target.stddev_m[c];
    ++a.cells;
    sum_sq += dz * dz;
    if (std::abs(dz) > k * std::sqrt(s * s + t * t)) ++a.disagreeing;
  }
  if (a.cells > 0) a.rms_m = std::sqrt(sum_sq / static_cast<double>(a.cells));
  return a;
}

// The surface normal of cell (col, row) from the least-squares slopes of its 5 x 5
// neighbourhood (central weights: the cell's own height does not enter, and a quadratic surface
// gives its exact slope); nullopt unless all 25 cells hold data. PCA normals of 10 neighbours
// are noisier: with 2 cm of height noise on 25 cm cells they biased a 20 cm shift by 2 cm
// (errors in the normals correlate with the residuals), these by a few millimetres.
std::optional<Eigen::Vector3d> GridNormal(const std::vector<float>& z, const Window& window,
                                          double cell, int col, int row) {
  constexpr int kHalf = 2;
  if (col < kHalf || row < kHalf || col + kHalf >= window.width || row + kHalf >= window.height)
    return std::nullopt;
  double gx = 0.0;  // Σ dx·z, dx in cells, east
  double gy = 0.0;  // Σ dy·z, dy in cells, north (rows run south)
  for (int dr = -kHalf; dr <= kHalf; ++dr) {
    for (int dc = -kHalf; dc <= kHalf; ++dc) {
      const float v = z[static_cast<std::size_t>(row + dr) * window.width + col + dc];
      if (!std::isfinite(v)) return std::nullopt;
      gx += dc * static_cast<double>(v);
      gy += -dr * static_cast<double>(v);
    }
  }
  // Σ dx² over the 5 x 5 window = 5 · (4 + 1 + 0 + 1 + 4) = 50 cells².
  const double sum_sq = 50.0 * cell * cell;
  const double slope_x = gx * cell / sum_sq;
  const double slope_y = gy * cell / sum_sq;
  return Eigen::Vector3d(-slope_x, -slope_y, 1.0).normalized();
}

// The window's usable cells with a grid normal as points relative to `origin` (those `keep`
// leaves out excepted), each with a covariance: the cell's footprint (uniform over its edge:
// s²/12) horizontally, σ² vertically.
registration::PointCloud CellsAsPoints(const std::vector<float>& z, const std::vector<float>& sigma,
                                       const std::vector<unsigned char>& keep,
                                       const OutputGrid& grid, const Window& window,
                                       const Eigen::Vector3d& origin) {
  registration::PointCloud cloud;
  const double s = grid.cell_size_m();
  const double horizontal = s * s / 12.0;
  for (int row = 0; row < window.height; ++row) {
    for (int col = 0; col < window.width; ++col) {
      const std::size_t c = static_cast<std::size_t>(row) * window.width + col;
      if (!Usable(z[c], sigma[c]) || (!keep.empty() && keep[c] == 0)) continue;
      const std::optional<Eigen::Vector3d> normal = GridNormal(z, window, s, col, row);
      if (!normal) continue;
      const Eigen::Vector2d xy = grid.CellCentre(window.col0 + col, window.row0 + row);
      cloud.points.emplace_back(xy.x() - origin.x(), xy.y() - origin.y(), z[c] - origin.z());
      cloud.normals.push_back(*normal);
      const double v = std::max(static_cast<double>(sigma[c]), kMinStddevM);
      cloud.covariances.push_back(Eigen::Vector3d(horizontal, horizontal, v * v).asDiagonal());
    }
  }
  return cloud;
}

// Median of source − target height over the cells both cover (0 if none).
double MedianDifference(const WarpedLayers& source, const FusedLayers& target) {
  std::vector<double> dz;
  for (std::size_t c = 0; c < source.elevation_m.size(); ++c) {
    if (Usable(source.elevation_m[c], source.stddev_m[c]) &&
        Usable(target.elevation_m[c], target.stddev_m[c])) {
      dz.push_back(static_cast<double>(source.elevation_m[c]) - target.elevation_m[c]);
    }
  }
  if (dz.empty()) return 0.0;
  std::nth_element(dz.begin(), dz.begin() + dz.size() / 2, dz.end());
  return dz[dz.size() / 2];
}

// Keeps (1) the entries of one line (n values `stride` apart from `first`) with more than
// `margin` entries of 1 on both sides, itself included; the others become 0.
void ErodeLine(std::vector<unsigned char>* mask, std::size_t first, std::size_t stride, int n,
               int margin) {
  std::vector<int> before(static_cast<std::size_t>(n), 0);
  int run = 0;
  for (int k = 0; k < n; ++k) {
    run = (*mask)[first + k * stride] != 0 ? run + 1 : 0;
    before[k] = run;
  }
  run = 0;
  for (int k = n - 1; k >= 0; --k) {
    unsigned char& v = (*mask)[first + k * stride];
    run = v != 0 ? run + 1 : 0;
    v = std::min(before[k], run) > margin ? 1 : 0;
  }
}

// The cells whose neighbours within `margin` cells (a square) all hold target data: source
// points there have their true partners in the target. A source point beyond the target's edge
// pairs with edge points instead and pulls the estimate.
std::vector<unsigned char> InsideTarget(const FusedLayers& target, const Window& window,
                                        int margin) {
  std::vector<unsigned char> inside(window.cells(), 0);
  for (std::size_t c = 0; c < inside.size(); ++c)
    inside[c] = Usable(target.elevation_m[c], target.stddev_m[c]) ? 1 : 0;
  const auto w = static_cast<std::size_t>(window.width);
  for (int row = 0; row < window.height; ++row)
    ErodeLine(&inside, row * w, 1, window.width, margin);
  for (int col = 0; col < window.width; ++col) ErodeLine(&inside, col, w, window.height, margin);
  return inside;
}

}  // namespace

InputReport Coregister(std::vector<Input>& inputs, std::size_t index, const OutputGrid& grid,
                       const MosaicOptions& options,
                       const registration::RegistrationOptions& registration) {
  Input& input = inputs[index];
  InputReport report;
  report.file = input.file.string();
  const Window window = grid.Cover(input.min_out, input.max_out);
  if (window.cells() == 0) {
    report.status = "no_overlap";
    return report;
  }
  // The mosaic of the inputs before it, over its footprint.
  CellFusion before(window.cells());
  for (std::size_t j = 0; j < index; ++j) {
    if (Touches(inputs[j], grid, window)) before.Add(WarpInput(inputs[j], grid, window));
  }
  const FusedLayers target = before.Finish(options.disagreement_sigma);
  const WarpedLayers source = WarpInput(input, grid, window);
  const Agreement initial = Compare(source, target, options.disagreement_sigma);
  report.overlap_cells = initial.cells;
  report.disagreement_before = report.disagreement_after = initial.disagreeing;
  report.rms_before_m = report.rms_after_m = initial.rms_m;
  if (initial.cells < static_cast<std::size_t>(options.min_overlap_cells)) {
    report.status = "no_overlap";
    return report;
  }
  report.overlaps = true;

  // Local coordinates: the window's centre and the overlap's mean height keep the numbers small.
  double mean_z = 0.0;
  std::size_t n = 0;
  for (std::size_t c = 0; c < window.cells(); ++c) {
    if (Usable(target.elevation_m[c], target.stddev_m[c])) {
      mean_z += target.elevation_m[c];
      ++n;
    }
  }
  const Eigen::Vector2d centre =
      grid.CellCentre(window.col0 + window.width / 2, window.row0 + window.height / 2);
  const Eigen::Vector3d origin(centre.x(), centre.y(), mean_z / static_cast<double>(n));

  registration::RegistrationOptions reg = registration;
  reg.residual = registration::Residual::kPointToPlane;
  reg.use_uncertainty = true;
  const std::vector<unsigned char> inside = InsideTarget(target, window, kEdgeCells);
  const registration::IndexedCloud target_cloud(
      CellsAsPoints(target.elevation_m, target.stddev_m, {}, grid, window, origin), reg);

  // Rounds of matching, each on the source resampled with the correction so far. The matcher
  // pairs closest points within Dmax; once the source has moved off the target's lattice by a
  // fraction of a cell, the pairs Dmax keeps depend on the slope, which biased a 20 cm shift by
  // 1.5 cm in one round. Resampled, the source sits on the lattice again and the next round
  // only has the remainder to find.
  Correction correction = input.correction;
  correction.origin = origin;
  WarpedLayers moved = source;
  bool converged = false;
  for (int round = 0; round < kMaxRounds && !converged; ++round) {
    const registration::IndexedCloud source_cloud(
        CellsAsPoints(moved.elevation_m, moved.stddev_m, inside, grid, window, origin), reg);
    // Started at the median height difference: traverses disagree by decimetres vertically,
    // and the uncertainty-weighted match gates pairs by their covariances (a 10 cm offset on
    // cells of 2 cm σ would reject every pair).
    Eigen::Isometry3d T_init = Eigen::Isometry3d::Identity();
    T_init.translation().z() = -MedianDifference(moved, target);
    const registration::RegistrationResult result =
        registration::Register(source_cloud, target_cloud, T_init, reg);
    // Too few pairs after a step is the estimate of that step (noise-free DEMs: the step moves
    // the source off the lattice, beyond the Dmax of the vertical residuals before it).
    const bool usable =
        result.status == registration::RegistrationStatus::kConverged ||
        result.status == registration::RegistrationStatus::kMaxIterations ||
        (result.status == registration::RegistrationStatus::kTooFewPairs && result.iterations >= 1);
    if (!usable) {
      if (round == 0) {
        report.status = std::string("failed: ") + registration::ToString(result.status) +
                        (result.message.empty() ? "" : " (" + result.message + ")");
        return report;
      }
      break;
    }
    report.inlier_ratio = result.inlier_ratio;
    report.iterations += result.iterations;
    correction.T = result.T_target_source * correction.T;
    SetCorrection(&input, grid.srs, correction);
    moved = WarpInput(input, grid, window);
    const double step_m = result.T_target_source.translation().norm();
    const double step_deg = Eigen::AngleAxisd(result.T_target_source.linear()).angle() * kRadToDeg;
    converged = step_m < kRoundTranslationM && step_deg < kRoundRotationDeg;
  }
  report.applied = true;
  report.status = "registered";
  report.translation_m = correction.T.translation();
  const Eigen::AngleAxisd rotation(correction.T.linear());
  report.rotation_deg = rotation.axis() * rotation.angle() * kRadToDeg;

  const Agreement corrected = Compare(moved, target, options.disagreement_sigma);
  report.disagreement_after = corrected.disagreeing;
  report.rms_after_m = corrected.rms_m;
  return report;
}

}  // namespace rovermap::mosaic::detail
