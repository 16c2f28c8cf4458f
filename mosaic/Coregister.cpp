#include "mosaic/Coregister.hpp"

#include <cmath>

#include "mosaic/Fusion.hpp"
#include "registration/Icp.hpp"

namespace rovermap::mosaic::detail {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

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

// The window's usable cells as points relative to `origin`, each with a covariance: the
// cell's footprint (uniform over its edge: s²/12) horizontally, σ² vertically.
registration::PointCloud CellsAsPoints(const std::vector<float>& z, const std::vector<float>& sigma,
                                       const OutputGrid& grid, const Window& window,
                                       const Eigen::Vector3d& origin) {
  registration::PointCloud cloud;
  const double s = grid.cell_size_m();
  const double horizontal = s * s / 12.0;
  for (int row = 0; row < window.height; ++row) {
    for (int col = 0; col < window.width; ++col) {
      const std::size_t c = static_cast<std::size_t>(row) * window.width + col;
      if (!Usable(z[c], sigma[c])) continue;
      const Eigen::Vector2d xy = grid.CellCentre(window.col0 + col, window.row0 + row);
      cloud.points.emplace_back(xy.x() - origin.x(), xy.y() - origin.y(), z[c] - origin.z());
      const double v = std::max(static_cast<double>(sigma[c]), kMinStddevM);
      cloud.covariances.push_back(Eigen::Vector3d(horizontal, horizontal, v * v).asDiagonal());
    }
  }
  return cloud;
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
  const registration::IndexedCloud source_cloud(
      CellsAsPoints(source.elevation_m, source.stddev_m, grid, window, origin), reg);
  const registration::IndexedCloud target_cloud(
      CellsAsPoints(target.elevation_m, target.stddev_m, grid, window, origin), reg);
  const registration::RegistrationResult result =
      registration::Register(source_cloud, target_cloud, Eigen::Isometry3d::Identity(), reg);
  report.inlier_ratio = result.inlier_ratio;
  report.iterations = result.iterations;
  const bool usable = result.status == registration::RegistrationStatus::kConverged ||
                      result.status == registration::RegistrationStatus::kMaxIterations;
  if (!usable) {
    report.status = std::string("failed: ") + registration::ToString(result.status) +
                    (result.message.empty() ? "" : " (" + result.message + ")");
    return report;
  }

  Correction correction = input.correction;
  correction.T = result.T_target_source;
  correction.origin = origin;
  SetCorrection(&input, grid.srs, correction);
  report.applied = true;
  report.status = "registered";
  report.translation_m = result.T_target_source.translation();
  const Eigen::AngleAxisd rotation(result.T_target_source.linear());
  report.rotation_deg = rotation.axis() * rotation.angle() * kRadToDeg;

  const Agreement corrected =
      Compare(WarpInput(input, grid, window), target, options.disagreement_sigma);
  report.disagreement_after = corrected.disagreeing;
  report.rms_after_m = corrected.rms_m;
  return report;
}

}  // namespace rovermap::mosaic::detail
