#include "mosaic/Coregister.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

#include "core/Units.hpp"
#include "mosaic/Fusion.hpp"
#include "registration/Icp.hpp"

namespace rovermap::mosaic::detail {
namespace {

using core::kRadToDeg;
// Source cells this close to the target's edge are left out of the registration [cells].
constexpr int kEdgeCells = 2;
// The same on the coarse levels [blocks]: 2 blocks of 4 cells left nothing of a thin overlap.
constexpr int kEdgeBlocks = 1;
// Matching rounds (see Coregister), until a round moves less than these (× the level's factor).
constexpr int kMaxRounds = 8;
constexpr int kMaxCoarseRounds = 4;
constexpr double kRoundTranslationM = 5e-4;
constexpr double kRoundRotationDeg = 1e-3;
// A round whose RMS over the overlap rises above the lowest so far slid on a weak match (on a
// small overlap, later rounds turned 35° and 45° more) and is undone; on the finest level a rise
// below this ratio is the noise of resampling, and the rounds go on refining (a 20 cm shift
// under 2 cm of noise: 19.1 cm when the first rise stopped them, 20.3 cm with them).
constexpr double kMaxRiseRatio = 1.1;
// Coarse to fine: cells merged into blocks of 4 × 4, then 2 × 2, then the grid itself. Far
// from a rover the DEM's cells are sparse; a small overlap there left 93 points with a full
// 5 × 5 neighbourhood (of 1026 overlap cells) and the match turned 3 deg the wrong way.
constexpr std::array<int, 3> kLevels = {4, 2, 1};

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

// A height grid to match on: the window's cells, or blocks of `factor` × `factor` of them.
struct MatchGrid {
  std::vector<float> z;
  std::vector<float> sigma;
  std::vector<Eigen::Vector2f> offset;  // [m] of the block's data from the block's centre
  Window window;                        // width and height in blocks
  double cell_m = 0.0;                  // [m] block edge
  bool partial_normals = false;         // normals of neighbourhoods with holes (GridNormal)
  Eigen::Vector2d first_centre{0, 0};   // output CRS centre of block (0, 0)
};

// Per block, the inverse-variance mean height of its cells with data, at their weighted centre,
// and their RMS σ (neighbouring cells' errors are correlated: averaging does not shrink them).
MatchGrid Coarsen(const std::vector<float>& z, const std::vector<float>& sigma,
                  const OutputGrid& grid, const Window& window, int factor) {
  MatchGrid g;
  const double s = grid.cell_size_m();
  g.cell_m = s * factor;
  g.partial_normals = factor > 1;
  g.window.width = (window.width + factor - 1) / factor;
  g.window.height = (window.height + factor - 1) / factor;
  g.first_centre = grid.CellCentre(window.col0, window.row0) +
                   Eigen::Vector2d(0.5 * (factor - 1) * s, -0.5 * (factor - 1) * s);
  const std::size_t n = g.window.cells();
  g.z.assign(n, std::numeric_limits<float>::quiet_NaN());
  g.sigma.assign(n, std::numeric_limits<float>::quiet_NaN());
  g.offset.assign(n, Eigen::Vector2f::Zero());
  for (int br = 0; br < g.window.height; ++br) {
    for (int bc = 0; bc < g.window.width; ++bc) {
      double sum_w = 0.0, sum_wz = 0.0, sum_var = 0.0;
      Eigen::Vector2d sum_wxy(0, 0);
      int cells = 0;
      for (int r = br * factor; r < std::min((br + 1) * factor, window.height); ++r) {
        for (int c = bc * factor; c < std::min((bc + 1) * factor, window.width); ++c) {
          const std::size_t k = static_cast<std::size_t>(r) * window.width + c;
          if (!Usable(z[k], sigma[k])) continue;
          const double v = std::max(static_cast<double>(sigma[k]), kMinStddevM);
          const double w = 1.0 / (v * v);
          sum_w += w;
          sum_wz += w * z[k];
          sum_var += v * v;
          sum_wxy += w * Eigen::Vector2d((c - bc * factor - 0.5 * (factor - 1)) * s,
                                         -(r - br * factor - 0.5 * (factor - 1)) * s);
          ++cells;
        }
      }
      if (cells == 0) continue;
      const std::size_t b = static_cast<std::size_t>(br) * g.window.width + bc;
      g.z[b] = static_cast<float>(sum_wz / sum_w);
      g.sigma[b] = static_cast<float>(std::sqrt(sum_var / cells));
      g.offset[b] = (sum_wxy / sum_w).cast<float>();
    }
  }
  return g;
}

// The surface normal of cell (col, row) from the least-squares slopes of its 5 x 5
// neighbourhood (central weights: the cell's own height does not enter, and a quadratic surface
// gives its exact slope). PCA normals of 10 neighbours are noisier: with 2 cm of height noise on
// 25 cm cells they biased a 20 cm shift by 2 cm (errors in the normals correlate with the
// residuals), these by a few millimetres. With `partial`, a neighbourhood with holes is fitted
// by a plane through the cells it has, if they spread in both directions (coarse levels: a
// sparse overlap far from the rover has few complete neighbourhoods); else nullopt unless all
// 25 cells hold data.
std::optional<Eigen::Vector3d> GridNormal(const std::vector<float>& z, const Window& window,
                                          double cell, int col, int row, bool partial) {
  constexpr int kHalf = 2;
  // A partial neighbourhood's scatter in each direction, at least this share of a full one's.
  constexpr double kMinSpread = 0.3;
  if (col < kHalf || row < kHalf || col + kHalf >= window.width || row + kHalf >= window.height)
    return std::nullopt;
  double gx = 0.0;  // Σ dx·z, dx in cells, east
  double gy = 0.0;  // Σ dy·z, dy in cells, north (rows run south)
  Eigen::Matrix3d normal_eq = Eigen::Matrix3d::Zero();  // of z = a + b·dx + c·dy
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  int n = 0;
  for (int dr = -kHalf; dr <= kHalf; ++dr) {
    for (int dc = -kHalf; dc <= kHalf; ++dc) {
      const float v = z[static_cast<std::size_t>(row + dr) * window.width + col + dc];
      if (!std::isfinite(v)) {
        if (!partial) return std::nullopt;
        continue;
      }
      gx += dc * static_cast<double>(v);
      gy += -dr * static_cast<double>(v);
      const Eigen::Vector3d a(1.0, dc, -dr);
      normal_eq += a * a.transpose();
      rhs += a * static_cast<double>(v);
      ++n;
    }
  }
  double slope_x = 0.0;
  double slope_y = 0.0;
  if (n == 25) {
    // Σ dx² over the 5 x 5 window = 5 · (4 + 1 + 0 + 1 + 4) = 50 cells².
    const double sum_sq = 50.0 * cell * cell;
    slope_x = gx * cell / sum_sq;
    slope_y = gy * cell / sum_sq;
  } else {
    // The scatter of the cells about their mean, against a full window's 50 cells².
    const Eigen::Matrix2d scatter =
        normal_eq.bottomRightCorner<2, 2>() -
        normal_eq.block<2, 1>(1, 0) * normal_eq.block<1, 2>(0, 1) / std::max(n, 1);
    if (n < 6 || Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvalues()(0) <
                     kMinSpread * 50.0)
      return std::nullopt;
    const Eigen::Vector3d fit = normal_eq.ldlt().solve(rhs);
    slope_x = fit(1) / cell;
    slope_y = fit(2) / cell;
  }
  return Eigen::Vector3d(-slope_x, -slope_y, 1.0).normalized();
}

// The grid's usable cells with a grid normal as points relative to `origin` (those `keep`
// leaves out excepted), each with a covariance: the cell's footprint (uniform over its edge:
// s²/12) horizontally, σ² vertically.
registration::PointCloud CellsAsPoints(const MatchGrid& g, const std::vector<unsigned char>& keep,
                                       const Eigen::Vector3d& origin) {
  registration::PointCloud cloud;
  const double horizontal = g.cell_m * g.cell_m / 12.0;
  for (int row = 0; row < g.window.height; ++row) {
    for (int col = 0; col < g.window.width; ++col) {
      const std::size_t c = static_cast<std::size_t>(row) * g.window.width + col;
      if (!Usable(g.z[c], g.sigma[c]) || (!keep.empty() && keep[c] == 0)) continue;
      const std::optional<Eigen::Vector3d> normal =
          GridNormal(g.z, g.window, g.cell_m, col, row, g.partial_normals);
      if (!normal) continue;
      const Eigen::Vector2d xy = g.first_centre + Eigen::Vector2d(col * g.cell_m, -row * g.cell_m) +
                                 g.offset[c].cast<double>();
      cloud.points.emplace_back(xy.x() - origin.x(), xy.y() - origin.y(), g.z[c] - origin.z());
      cloud.normals.push_back(*normal);
      const double v = std::max(static_cast<double>(g.sigma[c]), kMinStddevM);
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
std::vector<unsigned char> InsideTarget(const MatchGrid& target, int margin) {
  const Window& window = target.window;
  std::vector<unsigned char> inside(window.cells(), 0);
  for (std::size_t c = 0; c < inside.size(); ++c)
    inside[c] = Usable(target.z[c], target.sigma[c]) ? 1 : 0;
  const auto w = static_cast<std::size_t>(window.width);
  for (int row = 0; row < window.height; ++row)
    ErodeLine(&inside, row * w, 1, window.width, margin);
  for (int col = 0; col < window.width; ++col) ErodeLine(&inside, col, w, window.height, margin);
  return inside;
}

// The information of a point-to-plane match of `cloud` (relative to the rotation origin) for a
// left perturbation [r, t]: Σ J Jᵀ / (2 nᵀΣn), J = [p × n, n], both DEMs taken as noisy as
// this one. From the overlap's geometry, not the matcher's final pairs: on noise-free DEMs
// the matcher ends on too few pairs, without information, after a good step.
Matrix6d OverlapInformation(const registration::PointCloud& cloud, double* extent_m) {
  Matrix6d information = Matrix6d::Zero();
  *extent_m = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d& p = cloud.points[i];
    const Eigen::Vector3d& n = cloud.normals[i];
    Eigen::Matrix<double, 6, 1> j;
    j << p.cross(n), n;
    information += j * j.transpose() / (2.0 * n.dot(cloud.covariances[i] * n));
    *extent_m = std::max(*extent_m, p.norm());
  }
  return information;
}

// The step T with its unconstrained part removed: T = (Exp(r), t) on the left, as the
// information's parameterisation, projected by `constraint`.
Eigen::Isometry3d ConstrainedStep(const Eigen::Isometry3d& T, const Constraint& constraint) {
  const Eigen::AngleAxisd aa(T.linear());
  Eigen::Matrix<double, 6, 1> delta;
  delta << aa.angle() * aa.axis(), T.translation();
  delta = constraint.projector * delta;
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const double angle = delta.head<3>().norm();
  if (angle > 0.0)
    out.linear() = Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix();
  out.translation() = delta.tail<3>();
  return out;
}

// T = (Exp(r), t) with its roll and pitch weighed against their prior σ (the inputs' own
// attitude, from gravity): the most likely correction given the match's information and that
// prior, c' = (I + P)⁻¹ I c = c − (I + P)⁻¹ P c. A small overlap constrains the tilt poorly
// and a tilt carries far: on a small overlap the match alone found a tilt in a traverse whose
// DEM had none (docs/mosaic.md, "Co-registration").
Eigen::Isometry3d WeighTilt(const Eigen::Isometry3d& T, const Matrix6d& information,
                            double tilt_sigma_deg) {
  const Eigen::AngleAxisd aa(T.linear());
  Eigen::Matrix<double, 6, 1> c;
  c << aa.angle() * aa.axis(), T.translation();
  const double sigma = std::max(tilt_sigma_deg / kRadToDeg, 1e-6);
  Matrix6d prior = Matrix6d::Zero();
  prior(0, 0) = prior(1, 1) = 1.0 / (sigma * sigma);
  // A ridge keeps I + P invertible where the match constrains nothing (those steps are zero).
  Matrix6d sum = information + prior;
  sum.diagonal().array() += 1e-12 * sum.diagonal().maxCoeff();
  c -= sum.ldlt().solve(prior * c);
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const double angle = c.head<3>().norm();
  if (angle > 0.0) out.linear() = Eigen::AngleAxisd(angle, c.head<3>() / angle).toRotationMatrix();
  out.translation() = c.tail<3>();
  return out;
}

// "0.102" (metres to the millimetre, or finer below a centimetre).
std::string Figure(double value, int digits) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

}  // namespace

Constraint ConstrainDirections(const Matrix6d& information, double extent_m,
                               double min_information) {
  Constraint out;
  // Scaled coordinates δs = δ / s, s = (1/extent ×3, 1 ×3): rotations in metres of arc.
  Eigen::Matrix<double, 6, 1> s = Eigen::Matrix<double, 6, 1>::Ones();
  s.head<3>().setConstant(1.0 / std::max(extent_m, 1e-9));
  if (!information.allFinite()) return out;
  const Matrix6d scaled = s.asDiagonal() * information * s.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(scaled);
  const Eigen::Matrix<double, 6, 1> lambda = eig.eigenvalues();  // ascending
  if (!(lambda(5) > 0.0)) return out;
  out.conditioning = std::max(0.0, lambda(0)) / lambda(5);
  Matrix6d projector_scaled = Matrix6d::Zero();
  unsigned named = 0;
  for (int i = 5; i >= 0; --i) {
    const Eigen::Matrix<double, 6, 1> v = eig.eigenvectors().col(i);
    if (lambda(i) >= min_information * lambda(5)) {
      projector_scaled += v * v.transpose();
      continue;
    }
    // Named by its largest component not already named.
    int best = -1;
    for (int a = 0; a < 6; ++a) {
      if ((named & (1u << a)) == 0 && (best < 0 || std::abs(v(a)) > std::abs(v(best)))) best = a;
    }
    named |= 1u << best;
  }
  out.unconstrained = named;
  out.projector = s.asDiagonal() * projector_scaled * s.cwiseInverse().asDiagonal();
  return out;
}

std::string JudgeCorrection(unsigned unconstrained, double rms_before_m, double rms_after_m,
                            double shift_m, double rotation_deg, const MosaicOptions& options) {
  std::string why;
  auto add = [&why](const std::string& text) { why += (why.empty() ? "" : "; ") + text; };
  if ((unconstrained & kHorizontal) != 0) {
    add("ill-conditioned: " + registration::DirectionNames(unconstrained & kHorizontal) +
        " not constrained by the overlap");
  }
  if (!(rms_after_m < options.min_improvement * rms_before_m)) {
    add("disagreement only " + Figure(rms_before_m, 4) + " -> " + Figure(rms_after_m, 4) +
        " m RMS (needs < " + Figure(options.min_improvement, 2) + "x)");
  }
  if (!(shift_m <= options.max_correction_m)) {
    add("correction " + Figure(shift_m, 2) + " m exceeds mosaic.max_correction_m " +
        Figure(options.max_correction_m, 2));
  }
  if (!(rotation_deg <= options.max_correction_deg)) {
    add("correction " + Figure(rotation_deg, 2) + " deg exceeds mosaic.max_correction_deg " +
        Figure(options.max_correction_deg, 2));
  }
  return why;
}

InputReport Coregister(std::vector<Input>& inputs, std::size_t index, const OutputGrid& grid,
                       const MosaicOptions& options,
                       const registration::RegistrationOptions& registration) {
  Input& input = inputs[index];
  InputReport report;
  report.file = input.file.string();
  const Window window = grid.Cover(input.min_out, input.max_out);
  if (window.cells() == 0) {
    report.status = "no_overlap";
    report.reason = "its footprint is outside the grid";
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
    report.reason = std::to_string(initial.cells) + " overlap cells, fewer than " +
                    "mosaic.min_overlap_cells " + std::to_string(options.min_overlap_cells);
    return report;
  }
  report.overlaps = true;

  // Local coordinates about the overlap's centre at its mean height: rotations turn the overlap
  // about itself (not about a footprint centre metres away, which couples them with shifts),
  // and `extent_m` is the overlap's size.
  Eigen::Vector3d sum(0, 0, 0);
  for (int row = 0; row < window.height; ++row) {
    for (int col = 0; col < window.width; ++col) {
      const std::size_t c = static_cast<std::size_t>(row) * window.width + col;
      if (Usable(source.elevation_m[c], source.stddev_m[c]) &&
          Usable(target.elevation_m[c], target.stddev_m[c])) {
        const Eigen::Vector2d xy = grid.CellCentre(window.col0 + col, window.row0 + row);
        sum += Eigen::Vector3d(xy.x(), xy.y(), target.elevation_m[c]);
      }
    }
  }
  const Eigen::Vector3d origin = sum / static_cast<double>(initial.cells);

  registration::RegistrationOptions reg = registration;
  reg.residual = registration::Residual::kPointToPlane;
  reg.use_uncertainty = true;

  // Rounds of matching, coarse to fine, each on the source resampled with the correction so
  // far. The matcher pairs closest points within Dmax; once the source has moved off the
  // target's lattice by a fraction of a cell, the pairs Dmax keeps depend on the slope, which
  // biased a 20 cm shift by 1.5 cm in one round. Resampled, the source sits on the lattice
  // again and the next round only has the remainder to find. Each step keeps only the
  // directions the overlap constrains, its tilt weighed against tilt_sigma_deg; a round that
  // raises the RMS over the overlap (or leaves fewer than min_overlap_cells) is undone and
  // ends its level: it must not undo the ones before it. The last kept correction is judged.
  const Correction original = input.correction;
  Correction correction = input.correction;
  correction.origin = origin;
  Correction kept = correction;
  Correction correction_found = correction;
  Agreement kept_agreement = initial;
  double lowest_rms_m = initial.rms_m;
  Constraint kept_constraint;
  bool kept_any = false;
  Agreement last_agreement = initial;
  Constraint last_constraint;
  Constraint constraint;
  bool matched = false;
  std::string failure;
  WarpedLayers moved = source;
  WarpedLayers kept_moved = source;
  for (const int factor : kLevels) {
    const MatchGrid target_grid =
        Coarsen(target.elevation_m, target.stddev_m, grid, window, factor);
    const std::vector<unsigned char> inside =
        InsideTarget(target_grid, factor == 1 ? kEdgeCells : kEdgeBlocks);
    const registration::IndexedCloud target_cloud(CellsAsPoints(target_grid, {}, origin), reg);
    const int rounds = factor == 1 ? kMaxRounds : kMaxCoarseRounds;
    bool converged = false;
    for (int round = 0; round < rounds && !converged; ++round) {
      const registration::IndexedCloud source_cloud(
          CellsAsPoints(Coarsen(moved.elevation_m, moved.stddev_m, grid, window, factor), inside,
                        origin),
          reg);
      double extent_m = 0.0;
      const Matrix6d information = OverlapInformation(source_cloud.cloud(), &extent_m);
      // Started at the median height difference: traverses disagree by decimetres vertically,
      // and the uncertainty-weighted match gates pairs by their covariances (a 10 cm offset on
      // cells of 2 cm σ would reject every pair).
      Eigen::Isometry3d T_init = Eigen::Isometry3d::Identity();
      T_init.translation().z() = -MedianDifference(moved, target);
      const registration::RegistrationResult result =
          registration::Register(source_cloud, target_cloud, T_init, reg);
      // Too few pairs after a step is the estimate of that step (noise-free DEMs: the step
      // moves the source off the lattice, beyond the Dmax of the vertical residuals before it).
      const bool usable = result.status == registration::RegistrationStatus::kConverged ||
                          result.status == registration::RegistrationStatus::kMaxIterations ||
                          (result.status == registration::RegistrationStatus::kTooFewPairs &&
                           result.iterations >= 1);
      if (!usable) {
        if (!matched) {
          failure = std::string(registration::ToString(result.status)) +
                    (result.message.empty() ? "" : " (" + result.message + ")");
        }
        break;
      }
      const Constraint found = ConstrainDirections(information, extent_m, options.min_information);
      constraint = found;
      matched = true;
      report.inlier_ratio = result.inlier_ratio;
      report.iterations += result.iterations;
      const Eigen::Isometry3d step = ConstrainedStep(result.T_target_source, constraint);
      correction.T = WeighTilt(step * correction.T, information, options.tilt_sigma_deg);
      correction_found = correction;
      SetCorrection(&input, grid.srs, correction);
      moved = WarpInput(input, grid, window);
      last_agreement = Compare(moved, target, options.disagreement_sigma);
      last_constraint = constraint;
      if (last_agreement.cells < static_cast<std::size_t>(options.min_overlap_cells) ||
          last_agreement.rms_m > (factor == 1 ? kMaxRiseRatio : 1.0) * lowest_rms_m) {
        // A round that slid on a weak match: back to the last good one, on to the next level.
        correction = kept;
        moved = kept_moved;
        break;
      }
      lowest_rms_m = std::min(lowest_rms_m, last_agreement.rms_m);
      kept = correction;
      kept_moved = moved;
      kept_agreement = last_agreement;
      kept_constraint = constraint;
      kept_any = true;
      const double step_deg = Eigen::AngleAxisd(step.linear()).angle() * kRadToDeg;
      converged = step.translation().norm() < kRoundTranslationM * factor &&
                  step_deg < kRoundRotationDeg * factor;
    }
  }
  if (!matched) {
    SetCorrection(&input, grid.srs, original);
    report.status = "failed: " + failure;
    report.reason = "the matcher found no correction: " + failure;
    return report;
  }

  if (!kept_any) {  // none kept: the last one found is judged, the reason shows how far it was
    kept = correction_found;
    kept_agreement = last_agreement;
    kept_constraint = last_constraint;
  }
  report.translation_m = kept.T.translation();
  const Eigen::AngleAxisd rotation(kept.T.linear());
  report.rotation_deg = rotation.axis() * rotation.angle() * kRadToDeg;
  report.origin_m = origin;
  report.conditioning = kept_constraint.conditioning;
  report.unconstrained = registration::DirectionNames(kept_constraint.unconstrained);
  report.disagreement_after = kept_agreement.disagreeing;
  report.rms_after_m = kept_agreement.rms_m;
  report.reason =
      JudgeCorrection(kept_constraint.unconstrained, initial.rms_m, kept_agreement.rms_m,
                      report.translation_m.norm(), rotation.angle() * kRadToDeg, options);
  if (!report.reason.empty()) {
    SetCorrection(&input, grid.srs, original);
    report.status = "refused";
    return report;
  }
  SetCorrection(&input, grid.srs, kept);
  report.applied = true;
  report.status = "registered";
  return report;
}

}  // namespace rovermap::mosaic::detail
