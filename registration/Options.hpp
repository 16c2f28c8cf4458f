#pragma once

namespace rovermap::registration {

/// What the points sample: orientation consistency uses tangents for curves and
/// normals for surfaces (Zhang 1994, §4.2).
enum class Geometry { kSurface, kCurve };
/// Non-symmetric matches source -> target only; symmetric also target -> source.
enum class Criterion { kNonSymmetric, kSymmetric };
/// Closed-form motion solver for point-to-point pairs (Zhang 1994, Appendix A/B).
enum class Solver { kSvd, kDualQuaternion };
/// Residual minimised each iteration. Point-to-point is the paper; point-to-plane
/// (linearised, needs target normals) slides along smooth terrain much faster.
/// kAuto follows the geometry: point-to-plane for surfaces, point-to-point for curves
/// (a curve has no normal to project on); see EffectiveResidual.
enum class Residual { kAuto, kPointToPoint, kPointToPlane };
/// Stopping test. kRelative is the paper's 1 % test on r and t; kAbsolute stops when
/// the step is below fixed tolerances in metres and degrees (docs/design.md §1, "Known
/// weakness").
enum class Convergence { kRelative, kAbsolute };
/// Acceleration of the iterates (docs/design.md §1, "Known weakness"): Anderson extrapolation of
/// the pose with an energy safeguard (AA-ICP, Pavlov et al. 2018), or none (the paper).
/// kAuto: Anderson for point-to-point, which creeps; none for point-to-plane, whose
/// Gauss-Newton steps it only disturbed: more iterations, many extrapolations rejected
/// (docs/matcher.md, "Where the defaults differ from the paper, and why").
enum class Acceleration { kAuto, kNone, kAnderson };

/// Options of the iterative point matcher. Defaults are for dense stereo / range data;
/// every field is a config key under `registration.`.
struct RegistrationOptions {
  Geometry geometry = Geometry::kSurface;
  Criterion criterion = Criterion::kNonSymmetric;
  Solver solver = Solver::kSvd;
  Residual residual = Residual::kAuto;

  /// Zhang's D: the distance at which registration counts as good [m].
  /// 0 = derive from the data (median nearest-neighbour spacing of the target).
  double reference_distance_m = 0.0;
  /// Initial Dmax = dmax_initial_factor * D (the paper uses 20).
  double dmax_initial_factor = 20.0;
  /// Bins of the distance histogram used in the "poor registration" branch.
  int histogram_bins = 20;
  /// The valley after the highest peak is used only if its count is at most this
  /// fraction of the peak's count (the paper's 60 %).
  double histogram_valley_ratio = 0.6;

  int max_iterations = 100;
  Convergence convergence = Convergence::kAbsolute;
  /// kRelative: ||r_new - r|| / ||r_new|| and ||t_new - t|| / ||t_new|| below this.
  double relative_tolerance = 0.01;
  /// kAbsolute: translation step below this [m]; 0 = D / 100.
  double translation_tolerance_m = 0.0;
  /// kAbsolute: rotation step below this [deg].
  double rotation_tolerance_deg = 0.001;

  Acceleration acceleration = Acceleration::kAuto;
  /// Past steps Anderson combines (m) [count].
  int anderson_depth = 5;

  /// Θ: reject pairs whose normals (surfaces) or tangents (curves) differ by more
  /// than this angle [deg]; 0 = off. Signs are ignored (|cos|).
  double orientation_threshold_deg = 45.0;
  /// How reliable each orientation is widens Θ for that pair: a pair is rejected only when
  /// its angle exceeds Θ + this many times the pair's expected orientation error,
  /// √2 · min(sa, sb), each s from the scatter of the neighbours the tangent or normal was
  /// fitted to (CloudGeometry: NormalSpread, EstimateTangents) [count of σ]; 0 = the plain
  /// test (the paper). Noisy tangents otherwise reject good pairs at random.
  double orientation_spread_sigmas = 1.5;
  /// The staged orientation test: when the source's orientations must be estimated (PCA normals: no
  /// normals given), the first `coarse_iterations` run on the coarse subset (every `coarse_step`-th
  /// sampled point) as with coarse_to_fine, and the test is kept for the fine stage only if it
  /// rejected at least `orientation_min_rejected` of the pairs found in the last coarse iteration.
  /// Clean scans then need source normals for the coarse subset only. Sources with given normals
  /// (stereo) are left as they were. With coarse_to_fine the test is staged the same way whatever
  /// the normals.
  bool staged_orientation_test = true;
  /// [ratio]; 0 = the staged test is always kept.
  double orientation_min_rejected = 0.006;
  /// When the staged test is dropped (the coarse stage found the pairs clean), the fine stage
  /// and the final pairs use every k-th sampled point only [count]; 1 = the whole sample.
  /// Clean pairs need fewer points for the same accuracy: on the bunny scans every 4th of the
  /// 15 000 gave errors as small as the whole sample (every 5th did not); a pair whose
  /// coarse stage still finds false matches (terrain with outliers) keeps the whole sample.
  int clean_sample_step = 4;
  /// Neighbours used for PCA surface normals when the cloud has none [count].
  int normal_neighbors = 10;

  /// Source points matched: one per voxel of edge sample_voxel_factor · D (any member,
  /// VoxelChoice::kAnyMember, not one chosen by position or order), so dense patches do not outvote
  /// sparse ones and the cost follows the covered area, not the point count [× D]; 0 = every point.
  double sample_voxel_factor = 1.0;
  /// At most this many of those sampled points are matched, taken evenly through the input
  /// order (every k-th) [count]; 0 = no limit.
  int max_sample_points = 15000;

  /// Coarse to fine (on top of the voxel sample, Zhang 1994 §4.5): the first
  /// `coarse_iterations` use every `coarse_step`-th source point; skipped when that subset
  /// would have fewer than 500 points (nothing to save, and too few for a good estimate).
  bool coarse_to_fine = false;
  int coarse_iterations = 5;
  int coarse_step = 10;

  /// Weight pairs by 1 / tr(R Λx Rᵀ + Λy) and gate them by the squared Mahalanobis
  /// distance instead of the Euclidean Dmax (needs per-point covariances).
  bool use_uncertainty = false;
  /// χ² gate on the squared Mahalanobis distance (3 dof, 95 %: 7.81).
  double mahalanobis_gate = 7.81;
  /// With use_uncertainty: the initial estimate's own uncertainty, 1σ, added to each pair's
  /// covariance in the Mahalanobis gate (a rotation σ moves a point by σ·range) and shrunk to
  /// three times each step as the loop goes on, so that pairs the seed's error displaced are
  /// not gated out before they have pulled. The mapper sets both per frame from its odometry
  /// model; `rovermap register` takes them as given [deg], [m]. 0 = the sensor's gate alone.
  double seed_rotation_sigma_deg = 0.0;
  double seed_translation_sigma_m = 0.0;

  /// Fewer pairs than this after gating ends the loop with a failure status [count].
  int min_pairs = 6;

  /// Skip the k-d tree search of a query point that moved less than half the gap between its
  /// closest and second closest points since its last search: its closest point cannot have
  /// changed, so the result is the same either way (IterationTrace::searches counts the
  /// searches). Off only to compare with the plain search (tests, bench_register).
  bool reuse_closest_points = true;
};

/// The residual the matcher minimises: `residual`, or with kAuto the one the geometry
/// supports (point-to-plane needs surface normals; curves have tangents only).
inline Residual EffectiveResidual(const RegistrationOptions& options) {
  if (options.residual != Residual::kAuto) return options.residual;
  return options.geometry == Geometry::kCurve ? Residual::kPointToPoint : Residual::kPointToPlane;
}

}  // namespace rovermap::registration
