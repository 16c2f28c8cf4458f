#include "registration/Icp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/Units.hpp"
#include "registration/Anderson.hpp"
#include "registration/CloudGeometry.hpp"
#include "registration/MotionSolver.hpp"
#include "registration/VoxelGrid.hpp"

namespace rovermap::registration {
namespace {

using core::kDegToRad;
using core::kRadToDeg;
// The seed gate's spread after a step: this many times the step (SeedGate, GateAndWeight).
constexpr double kSeedGateStepFactor = 3.0;
// While the seed gate is open, a query searches at least this many σ of its displacement.
constexpr double kSeedGateSearchSigmas = 3.0;

bool NeedsOrientations(const RegistrationOptions& o) {
  return o.orientation_threshold_deg > 0.0 || EffectiveResidual(o) == Residual::kPointToPlane;
}

// A pair between source point `source_index` and target point `target_index`.
struct Match {
  std::size_t source_index = 0;
  std::size_t target_index = 0;
  double distance = 0.0;  // ‖T x − y‖ [m]
  bool backward = false;  // found by a target -> source query (symmetric criterion)
};

// Orientation consistency (Zhang 1994, §4.2): the angle between matched tangents or normals
// cannot exceed the rotation left to find, Θ. A noisy orientation is off by its own error
// too, so Θ is widened by `spread_sigmas` times the pair's expected error (0 = the paper's
// plain test). That error is taken as √2 times the smaller of the two expected errors, and at
// most the median of the sampled points' (`spread_cap`): the two ends of a true pair sample
// the same piece of curve or surface with the same noise, so their spreads agree and are
// typical of the data, while an end whose neighbourhood is no clean sample (an outlier, whose
// PCA normal is fitted to scattered points) has a large spread of its own that must not buy
// the pair a pass. On the terrain pair with outliers the root-sum-square of the two let the
// outliers through, and the smaller one alone let pairs of two outliers through
// (docs/matcher.md, "Where the defaults differ from the paper, and why").
struct OrientationTest {
  bool enabled = false;
  double min_abs_cos = 0.0;  // cos Θ
  double threshold_rad = 0.0;
  double spread_sigmas = 0.0;
  double spread_cap = std::numeric_limits<double>::infinity();  // [rad]

  explicit OrientationTest(const RegistrationOptions& o)
      : enabled(o.orientation_threshold_deg > 0.0),
        min_abs_cos(enabled ? std::cos(o.orientation_threshold_deg * kDegToRad) : 0.0),
        threshold_rad(o.orientation_threshold_deg * kDegToRad),
        spread_sigmas(o.orientation_spread_sigmas) {}

  // `a` (already rotated into b's frame) and `b` with their expected errors [rad]. Signs are
  // ignored (|cos|); an unknown (zero) orientation cannot be tested: the pair is kept.
  bool Consistent(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double spread_a,
                  double spread_b) const {
    if (a.isZero() || b.isZero()) return true;
    const double abs_cos = std::abs(a.dot(b));
    if (abs_cos >= min_abs_cos) return true;
    if (!(spread_sigmas > 0.0)) return false;
    const double spread = std::min({spread_a, spread_b, spread_cap});
    const double limit = threshold_rad + spread_sigmas * M_SQRT2 * spread;
    if (limit >= 0.5 * M_PI) return true;  // the orientations say nothing at this noise
    return std::acos(std::min(abs_cos, 1.0)) <= limit;
  }
};

// The median expected orientation error of the sampled points of both clouds [rad] (0 when
// none is known): what a pair of clean samples of these data is typically off by.
double MedianSpread(const IndexedCloud& source, const std::vector<std::size_t>& source_sample,
                    const IndexedCloud& target, const std::vector<std::size_t>& target_sample) {
  std::vector<double> spreads;
  spreads.reserve(source_sample.size() + target_sample.size());
  for (const std::size_t i : source_sample)
    if (!source.orientation(i).isZero()) spreads.push_back(source.orientation_spread(i));
  for (const std::size_t i : target_sample)
    if (!target.orientation(i).isZero()) spreads.push_back(target.orientation_spread(i));
  if (spreads.empty()) return 0.0;
  const auto mid = spreads.begin() + static_cast<long>(spreads.size() / 2);
  std::nth_element(spreads.begin(), mid, spreads.end());
  return *mid;
}

// How far the current estimate may still be from the solution, 1σ, as a left perturbation
// about the target's origin: at first the seed's uncertainty, then what the last step says is
// left (SeedGate). Zero: the gate is the sensor's alone.
struct PoseSpread {
  double rotation_var_rad2 = 0.0;
  double translation_var_m2 = 0.0;

  bool Open() const { return rotation_var_rad2 > 0.0 || translation_var_m2 > 0.0; }
  /// Covariance of the displacement of the point p (target frame): δr × p + δt.
  Eigen::Matrix3d At(const Eigen::Vector3d& p) const {
    return rotation_var_rad2 * (p.squaredNorm() * Eigen::Matrix3d::Identity() - p * p.transpose()) +
           translation_var_m2 * Eigen::Matrix3d::Identity();
  }
  /// The search radius for p: Dmax, widened to this many σ of p's displacement. Not bounded
  /// by the initial Dmax: that bound cut off the far points that hold the heading, and a
  /// biased seed's ATE on KITTI grew (docs/benchmarks.md, "Figures behind the matcher's code").
  double Radius(const Eigen::Vector3d& p, double dmax, double sigmas) const {
    if (!Open()) return dmax;
    return std::max(dmax,
                    sigmas * std::sqrt(rotation_var_rad2 * p.squaredNorm() + translation_var_m2));
  }
};

// What the last search of one query point found: where the point was, its closest point
// (the next search's warm start) and a lower bound on every other point's distance. Late
// iterations move the points by far less than the gap between their closest and second
// closest points, and then the closest point cannot have changed (Lookup): most of a
// frame's searches are skipped with the same result.
struct QueryMemo {
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  double others_sq = 0.0;       // every point but `closest` was at least this far [m²]
  std::size_t closest = kNone;  // found within the bound of that search, or kNone
  std::size_t hint = kNone;     // the last closest point found, kept across misses
  bool valid = false;

  // The closest point strictly within `radius` of p, as KdTree::FindClosest finds it;
  // `*searched` says whether the tree was searched.
  Neighbor Lookup(const KdTree& tree, const std::vector<Eigen::Vector3d>& to,
                  const Eigen::Vector3d& p, double radius, bool reuse, bool* searched) {
    *searched = false;
    if (valid && reuse) {
      // Every other point is now at least √others_sq − δ away (triangle inequality); a small
      // relative margin keeps rounding from deciding a near tie.
      const double moved = (p - at).norm();
      const double others = (std::sqrt(others_sq) - moved) * (1.0 - 1e-9);
      if (closest == kNone) {
        if (radius <= others) return Neighbor{};  // nothing can be within the bound
      } else {
        const double d_sq = (to[closest] - p).squaredNorm();
        if (std::sqrt(d_sq) < others) {
          if (d_sq < radius * radius) return Neighbor{true, closest, d_sq};
          return Neighbor{};
        }
      }
    }
    *searched = true;
    const Neighbor nb = tree.FindClosest(p, radius, hint, &others_sq);
    at = p;
    closest = nb.found ? nb.index : kNone;
    if (nb.found) hint = nb.index;
    valid = true;
    return nb;
  }
};

// Closest points in `to` of every `step`-th `from` point listed in `queries`, mapped by
// T_to_from, within `dmax`, then the orientation test (Zhang 1994, §4.1 and §4.2).
// `memos` holds, per entry of `queries`, what its last search found (QueryMemo, updated here);
// the result does not depend on it; `*searches` counts the tree searches. With `need_orientations`
// the matched `to` points' orientations are made available (the queried `from` points' must
// already be, for the orientation test). Returns how many pairs the orientation test rejected.
std::size_t MatchDirection(const IndexedCloud& from, const IndexedCloud& to,
                           const Eigen::Isometry3d& T_to_from, double dmax,
                           const PoseSpread& spread, const OrientationTest& orientation_test,
                           const std::vector<std::size_t>& queries, std::size_t step, bool backward,
                           bool need_orientations, bool reuse, std::vector<QueryMemo>* memos,
                           std::vector<Match>* out, std::size_t* searches) {
  const auto& pts = from.cloud().points;
  const long count = static_cast<long>((queries.size() + step - 1) / step);
  std::vector<Match> local(static_cast<std::size_t>(count));
  std::vector<char> valid(static_cast<std::size_t>(count), 0);
  const KdTree& tree = to.tree();  // built here, outside the parallel loop, if not yet
  // Here source_index is the `from` point and target_index the `to` point.
  // A parallel region costs more than a few hundred queries (curves: 200 points); a coarse
  // iteration's 1 500 queries already gain from it.
  std::size_t searched_total = 0;
#pragma omp parallel for schedule(dynamic, 128) if (count > 256) reduction(+ : searched_total)
  for (long q = 0; q < count; ++q) {
    const std::size_t i = queries[static_cast<std::size_t>(q) * step];
    const Eigen::Vector3d p = T_to_from * pts[i];
    bool searched = false;
    const Neighbor nb = (*memos)[static_cast<std::size_t>(q) * step].Lookup(
        tree, to.cloud().points, p, spread.Radius(p, dmax, kSeedGateSearchSigmas), reuse,
        &searched);
    searched_total += searched;
    if (!nb.found) continue;
    local[static_cast<std::size_t>(q)] =
        Match{i, nb.index, std::sqrt(nb.squared_distance), backward};
    valid[static_cast<std::size_t>(q)] = 1;
  }
  if (searches != nullptr) *searches += searched_total;
  std::size_t found = 0;
  for (std::size_t k = 0; k < local.size(); ++k)
    if (valid[k]) local[found++] = local[k];
  local.resize(found);
  if (need_orientations) {
    std::vector<std::size_t> matched(found);
    for (std::size_t k = 0; k < found; ++k) matched[k] = local[k].target_index;
    to.RequireOrientations(matched);
  }
  const Eigen::Matrix3d rotation = T_to_from.linear();
  std::size_t rejected = 0;
  for (Match m : local) {
    if (orientation_test.enabled &&
        !orientation_test.Consistent(
            rotation * from.orientation(m.source_index), to.orientation(m.target_index),
            from.orientation_spread(m.source_index), to.orientation_spread(m.target_index))) {
      ++rejected;
      continue;
    }
    if (backward) std::swap(m.source_index, m.target_index);
    out->push_back(m);
  }
  return rejected;
}

// Every `step`-th of `indices`: the points a coarse iteration queries (and their memos).
template <typename T>
std::vector<T> EveryKth(const std::vector<T>& indices, std::size_t step) {
  std::vector<T> kept;
  kept.reserve((indices.size() + step - 1) / step);
  for (std::size_t k = 0; k < indices.size(); k += step) kept.push_back(indices[k]);
  return kept;
}

// R C Rᵀ for a symmetric C, its upper triangle computed and mirrored: the gate and the weights
// are a visible share of a stereo replay's CPU (docs/benchmarks.md, "Figures behind the
// matcher's code").
inline Eigen::Matrix3d SymmetricSandwich(const Eigen::Matrix3d& R, const Eigen::Matrix3d& C) {
  const Eigen::Matrix3d RC = R * C;
  Eigen::Matrix3d out;
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      out(i, j) = RC.row(i).dot(R.row(j));
      out(j, i) = out(i, j);
    }
  }
  return out;
}

// dᵀ G⁻¹ d for a symmetric positive-definite G, by its adjugate (six cofactors) and determinant:
// no inverse formed. +inf when G is not positive definite (det ≤ 0), so that no gate passes it.
inline double MahalanobisSquared(const Eigen::Matrix3d& G, const Eigen::Vector3d& d) {
  const double a = G(0, 0), b = G(0, 1), c = G(0, 2), e = G(1, 1), f = G(1, 2), g = G(2, 2);
  const double A = e * g - f * f, B = c * f - b * g, C = b * f - c * e;
  const double det = a * A + b * B + c * C;
  if (!(det > 0.0)) return std::numeric_limits<double>::infinity();
  const double D = a * g - c * c, E = b * c - a * f, F = a * e - b * b;
  const double x = d.x(), y = d.y(), z = d.z();
  const double quad = A * x * x + D * y * y + F * z * z + 2.0 * (B * x * y + C * x * z + E * y * z);
  return quad / det;
}

// Combined covariance of a pair's residual, R Λx Rᵀ + Λy (§4.4), plus an isotropic
// `sampling_variance` for the offset between non-coincident samples, which the sensor
// covariance does not describe (without it the gate rejects most pairs of data sampled
// coarser than its noise).
inline Eigen::Matrix3d PairCovariance(const PointCloud& source, const PointCloud& target,
                                      const Match& m, const Eigen::Matrix3d& rotation,
                                      double sampling_variance) {
  return SymmetricSandwich(rotation, source.covariances[m.source_index]) +
         target.covariances[m.target_index] + sampling_variance * Eigen::Matrix3d::Identity();
}

// Unit normal of a point-to-plane pair: the target's, or the rotated source's for a
// backward (target -> source) pair. Zero when unknown.
Eigen::Vector3d PairNormal(const IndexedCloud& source, const IndexedCloud& target, const Match& m,
                           const Eigen::Matrix3d& rotation) {
  return m.backward ? Eigen::Vector3d(rotation * source.orientation(m.source_index))
                    : target.orientation(m.target_index);
}

// Step d: a pair is kept within Dmax, or with use_uncertainty within the χ² gate on the
// squared Mahalanobis distance dᵀ(R Λx Rᵀ + Λy + Λpose)⁻¹ d (§4.4) instead. Λpose spreads the
// pose's own uncertainty to the point p (δr × p + δt): without it the gate, unlike Dmax, is
// anchored to the seed from the first iteration, and a seed a degree off in heading gates out
// exactly the far points that would turn it back (without it, most of a biased seed's heading
// error stayed in KITTI's registered increments: docs/benchmarks.md, "Figures behind the
// matcher's code").
// A kept pair's §4.4 weight comes from the same R Λx Rᵀ + Λy: 1 / tr(· + sampling) for
// point-to-point, and for point-to-plane the inverse variance of the residual along the normal,
// 1 / nᵀ(R Λx Rᵀ + Λy)n. Returns the weight (0 for a pair that carries nothing along its
// normal), or a negative number when the pair fails the gate.
double GateAndWeight(const IndexedCloud& source, const IndexedCloud& target, const Match& m,
                     const Eigen::Isometry3d& T, double sampling_variance, const PoseSpread& spread,
                     const RegistrationOptions& options) {
  const Eigen::Vector3d p = T * source.cloud().points[m.source_index];
  const Eigen::Vector3d d = p - target.cloud().points[m.target_index];
  const Eigen::Matrix3d pair = PairCovariance(source.cloud(), target.cloud(), m, T.linear(), 0.0);
  Eigen::Matrix3d gate = pair;
  gate.diagonal().array() += sampling_variance;
  if (spread.Open()) gate += spread.At(p);
  if (!(MahalanobisSquared(gate, d) <= options.mahalanobis_gate)) return -1.0;
  if (EffectiveResidual(options) == Residual::kPointToPlane) {
    const Eigen::Vector3d n = PairNormal(source, target, m, T.linear());
    const double var = n.dot(pair * n);
    return var > 0.0 ? 1.0 / var : 0.0;
  }
  return 1.0 / (pair.trace() + 3.0 * sampling_variance);
}

// Step d over all pairs: keeps, in order, those that pass the gate, and their weights (1 without
// use_uncertainty). The tests run in parallel, the compaction not.
void KeepWithinGate(const IndexedCloud& source, const IndexedCloud& target,
                    const Eigen::Isometry3d& T, double dmax, double sampling_variance,
                    const PoseSpread& spread, const RegistrationOptions& options,
                    std::vector<Match>* matches, std::vector<double>* weights) {
  if (!options.use_uncertainty) {  // a distance test: one pass, nothing to run in parallel
    matches->erase(std::remove_if(matches->begin(), matches->end(),
                                  [dmax](const Match& m) { return !(m.distance <= dmax); }),
                   matches->end());
    weights->assign(matches->size(), 1.0);
    return;
  }
  const auto count = static_cast<long>(matches->size());
  weights->resize(matches->size());
#pragma omp parallel for schedule(static) if (count > 2048)
  for (long k = 0; k < count; ++k) {
    const auto i = static_cast<std::size_t>(k);
    (*weights)[i] =
        GateAndWeight(source, target, (*matches)[i], T, sampling_variance, spread, options);
  }
  std::size_t kept = 0;
  for (std::size_t k = 0; k < matches->size(); ++k) {
    if (!((*weights)[k] >= 0.0)) continue;
    (*matches)[kept] = (*matches)[k];
    (*weights)[kept] = (*weights)[k];
    ++kept;
  }
  matches->resize(kept);
  weights->resize(kept);
}

// The pose of [rotation vector (rad), translation (m)]: a left update in the point-to-plane
// step, and the space Anderson extrapolates in.
Eigen::Isometry3d PoseFromParameters(const Eigen::Matrix<double, 6, 1>& x) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double angle = x.head<3>().norm();
  if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, x.head<3>() / angle).toRotationMatrix();
  T.translation() = x.tail<3>();
  return T;
}

// One Gauss-Newton step of the point-to-plane residual nᵀ(T x − y) for a left
// perturbation (ω, v): J = [p × n, n]. On a plane the normal equations are singular in x, y and
// yaw; the step is taken only in the eigen-directions of JᵀJ above 1e-9 of the largest (a
// truncated pseudo-inverse), so that the data's noise does not push the pose along the null
// directions (a tiny damping did: the iterate wandered and never met the stopping test).
bool PointToPlaneStep(const IndexedCloud& source, const IndexedCloud& target,
                      const std::vector<Match>& matches, const std::vector<double>& weights,
                      Eigen::Isometry3d* T) {
  Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
  const Eigen::Matrix3d rotation = T->linear();
  std::size_t used = 0;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    const Match& m = matches[k];
    const Eigen::Vector3d n = PairNormal(source, target, m, rotation);
    if (n.isZero() || !(weights[k] > 0.0)) continue;
    const Eigen::Vector3d p = *T * source.cloud().points[m.source_index];
    const double e = n.dot(p - target.cloud().points[m.target_index]);
    Eigen::Matrix<double, 6, 1> j;
    j << p.cross(n), n;
    h += weights[k] * j * j.transpose();
    g += weights[k] * j * e;
    ++used;
  }
  if (used < 6 || !h.allFinite() || !g.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(h);
  const auto& lambda = eig.eigenvalues();  // ascending
  if (!(lambda(5) > 0.0)) return false;
  Eigen::Matrix<double, 6, 1> delta = Eigen::Matrix<double, 6, 1>::Zero();
  for (int i = 0; i < 6; ++i) {
    if (lambda(i) <= 1e-9 * lambda(5)) continue;
    const auto v = eig.eigenvectors().col(i);
    delta -= v * (v.dot(g) / lambda(i));
  }
  if (!delta.allFinite()) return false;
  *T = PoseFromParameters(delta) * *T;
  return true;
}

Eigen::Vector3d RotationVector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

// The inverse of PoseFromParameters (rotation angle below π).
AndersonAccelerator::Vector6 PoseParameters(const Eigen::Isometry3d& T) {
  AndersonAccelerator::Vector6 x;
  x << RotationVector(T.linear()), T.translation();
  return x;
}

// Mean truncated quadratic energy at bound tau: found pairs add min(d², τ²), queries without
// a pair τ². Comparable between two poses when evaluated at the same τ (no larger than the
// bounds the distances were searched with).
double TruncatedEnergy(const std::vector<double>& distances, std::size_t queries, double tau) {
  if (queries == 0) return 0.0;
  const double tau_sq = tau * tau;
  double e = static_cast<double>(queries - std::min(queries, distances.size())) * tau_sq;
  for (const double d : distances) e += std::min(d * d, tau_sq);
  return e / static_cast<double>(queries);
}

bool RelativeConverged(const Eigen::Isometry3d& T_old, const Eigen::Isometry3d& T_new,
                       double tolerance, double translation_guard_m) {
  // Zhang 1994, §4.3 step 3f, with an absolute guard for near-zero motion.
  const Eigen::Vector3d r_old = RotationVector(T_old.linear());
  const Eigen::Vector3d r_new = RotationVector(T_new.linear());
  const double dr = (r_new - r_old).norm();
  const double dt = (T_new.translation() - T_old.translation()).norm();
  const bool r_ok = dr < tolerance * r_new.norm() || dr < 1e-7;
  const bool t_ok = dt < tolerance * T_new.translation().norm() || dt < translation_guard_m;
  return r_ok && t_ok;
}

// At most `max_points` of `indices` (0 = all), taken evenly through their order: for a stereo
// frame in image order this thins every part of the image alike, unlike a coarser voxel grid,
// which keeps far, noisy points and drops the dense near field.
std::vector<std::size_t> Decimate(std::vector<std::size_t> indices, int max_points) {
  if (max_points <= 0 || indices.size() <= static_cast<std::size_t>(max_points)) return indices;
  const double stride = static_cast<double>(indices.size()) / max_points;
  std::vector<std::size_t> kept(static_cast<std::size_t>(max_points));
  for (std::size_t k = 0; k < kept.size(); ++k)
    kept[k] = indices[static_cast<std::size_t>(static_cast<double>(k) * stride)];
  return kept;
}

// The information a point-to-plane pair's normal error alone adds (noise_information): a
// normal tilted by δn (⊥ n) adds δnᵀj to the row, and on featureless ground that is all the
// information the in-plane directions get. δn's covariance is taken from how far the pair's two
// normals disagree (half the outer product of their difference in the tangent plane): the
// ground's shape is common to both frames, their noise and sensor-fixed artefacts (range bins,
// pixel locking: they moved with the sensor) are not. Without a source normal, from the
// target's own expected error (spread²/2 per axis).
Eigen::Matrix<double, 6, 6> NormalNoise(const IndexedCloud& source, const IndexedCloud& target,
                                        const Match& m, const Eigen::Matrix3d& rotation,
                                        const Eigen::Matrix<double, 3, 6>& j,
                                        bool floor_from_pairs) {
  const Eigen::Vector3d& nrm = target.orientation(m.target_index);
  const Eigen::Matrix3d tangent = Eigen::Matrix3d::Identity() - nrm * nrm.transpose();
  const Eigen::Vector3d source_normal =
      floor_from_pairs ? Eigen::Vector3d(rotation * source.orientation(m.source_index))
                       : Eigen::Vector3d::Zero();
  Eigen::Matrix3d tilt;
  if (!source_normal.isZero()) {
    const Eigen::Vector3d diff =
        tangent * (source_normal.dot(nrm) < 0.0 ? -source_normal : source_normal);
    tilt = 0.5 * diff * diff.transpose();
  } else {
    const double spread = target.orientation_spread(m.target_index);
    tilt = 0.5 * spread * spread * tangent;
  }
  return j.transpose() * tilt * j;
}

// The information of the final pairs (and its noise floor) into the result, with the
// covariance its inverse; without per-point covariances the residual variance is estimated
// from the fit. False when there are too few pairs for that.
bool SetInformation(Eigen::Matrix<double, 6, 6> info, Eigen::Matrix<double, 6, 6> floor,
                    std::size_t n, double sum_sq, bool plane, bool use_uncertainty,
                    RegistrationResult* result) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  const double dof = plane ? static_cast<double>(n) - 6.0 : 3.0 * static_cast<double>(n) - 6.0;
  if (n < 3 || dof <= 0.0) return false;
  if (!use_uncertainty) {
    info /= std::max(sum_sq / dof, 1e-24);
    floor /= std::max(sum_sq / dof, 1e-24);
  }
  result->information = info;
  result->noise_information = floor;
  const Eigen::FullPivLU<Mat6> lu(info);
  if (lu.isInvertible()) result->covariance = lu.inverse();
  return true;
}

// The extent (farthest matched source point from the sensor, at T) and the conditioning:
// smallest over largest eigenvalue of the information with rotations scaled to metres there.
void SetConditioning(const IndexedCloud& source, const std::vector<Match>& matches,
                     const Eigen::Isometry3d& T, const Eigen::Matrix<double, 6, 6>& info,
                     RegistrationResult* result) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  double extent = 0.0;
  for (const Match& m : matches)
    extent = std::max(extent, (T * source.cloud().points[m.source_index] - T.translation()).norm());
  result->extent_m = extent;
  Mat6 s = Mat6::Identity();
  s.topLeftCorner<3, 3>() *= 1.0 / std::max(extent, 1e-9);
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(s * info * s);
  const auto ev = eig.eigenvalues();
  result->conditioning = ev(5) > 0.0 ? std::max(0.0, ev(0)) / ev(5) : 0.0;
}

// Information of the estimate from the final pairs (see RegistrationResult).
void ComputeInformation(const IndexedCloud& source, const IndexedCloud& target,
                        const std::vector<Match>& matches, const Eigen::Isometry3d& T,
                        double sampling_variance, const RegistrationOptions& options,
                        RegistrationResult* result) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  Mat6 info = Mat6::Zero();
  Mat6 floor = Mat6::Zero();  // what the normals' own errors would give (noise_information)
  const Eigen::Matrix3d rotation = T.linear();
  const bool plane = EffectiveResidual(options) == Residual::kPointToPlane;
  // The floor needs normals fitted to the points by PCA at both ends (EstimatesOrientations):
  // given normals are either exact (a simulator's) or, from a stereo image's neighbouring
  // pixels, so noisy that textured ground's in-plane information is barely above their floor
  // where registration still clearly beats dead reckoning (docs/replay.md, "Known limits").
  const bool floor_from_pairs = target.EstimatesOrientations() && source.EstimatesOrientations();
  const bool has_floor = target.EstimatesOrientations();
  double sum_sq = 0.0;
  std::size_t n = 0;
  for (const Match& m : matches) {
    if (m.backward) continue;
    const Eigen::Vector3d p = T * source.cloud().points[m.source_index];
    const Eigen::Vector3d d = p - target.cloud().points[m.target_index];
    Eigen::Matrix<double, 3, 6> j;
    j.leftCols<3>() << 0, p.z(), -p.y(), -p.z(), 0, p.x(), p.y(), -p.x(), 0;  // −[p]×
    j.rightCols<3>().setIdentity();
    if (plane) {
      const Eigen::Vector3d& nrm = target.orientation(m.target_index);
      if (nrm.isZero()) continue;
      const Eigen::Matrix<double, 1, 6> jp = nrm.transpose() * j;
      const double e = nrm.dot(d);
      const Mat6 noise =
          has_floor ? NormalNoise(source, target, m, rotation, j, floor_from_pairs) : Mat6::Zero();
      if (options.use_uncertainty) {
        const double var =
            nrm.dot(PairCovariance(source.cloud(), target.cloud(), m, rotation, 0.0) * nrm);
        if (var > 0.0) {
          info += jp.transpose() * jp / var;
          floor += noise / var;
        }
      } else {
        info += jp.transpose() * jp;
        floor += noise;
      }
      sum_sq += e * e;
    } else if (options.use_uncertainty) {
      const Eigen::Matrix3d cov =
          PairCovariance(source.cloud(), target.cloud(), m, rotation, sampling_variance);
      info += j.transpose() * cov.inverse() * j;
      sum_sq += d.squaredNorm();
    } else {
      info += j.transpose() * j;
      sum_sq += d.squaredNorm();
    }
    ++n;
  }
  if (!SetInformation(info, floor, n, sum_sq, plane, options.use_uncertainty, result)) return;
  SetConditioning(source, matches, T, result->information, result);
}

// Register's preconditions; false with the status and message set when one fails.
bool CheckInputs(const IndexedCloud& source, const IndexedCloud& target,
                 const RegistrationOptions& options, RegistrationResult* result) {
  auto fail = [&](RegistrationStatus status, std::string message) {
    result->status = status;
    result->message = std::move(message);
    return false;
  };
  if (source.cloud().size() < 3 || target.cloud().size() < 3) {
    return fail(RegistrationStatus::kTooFewPoints, "need at least 3 points in each cloud (source " +
                                                       std::to_string(source.cloud().size()) +
                                                       ", target " +
                                                       std::to_string(target.cloud().size()) + ")");
  }
  if (options.use_uncertainty &&
      (!source.cloud().HasCovariances() || !target.cloud().HasCovariances())) {
    return fail(RegistrationStatus::kInvalidInput,
                "use_uncertainty needs per-point covariances in both clouds");
  }
  if (options.geometry == Geometry::kCurve &&
      EffectiveResidual(options) == Residual::kPointToPlane) {
    return fail(RegistrationStatus::kInvalidInput,
                "point_to_plane needs surface normals; curves have tangents only");
  }
  if (NeedsOrientations(options) && (!target.HasOrientations() || !source.HasOrientations())) {
    return fail(RegistrationStatus::kInvalidInput,
                "clouds were indexed without orientations the options need");
  }
  return true;
}

bool Accelerates(const RegistrationOptions& o) {
  return o.acceleration == Acceleration::kAnderson ||
         (o.acceleration == Acceleration::kAuto && EffectiveResidual(o) == Residual::kPointToPoint);
}

// The iterative matching of §4.3, one named step a member: what one iteration hands to the
// next (T, Dmax, the seed gate's spread, the query memos, the acceleration's history) lives
// here, so Register reads as the paper's steps a to f.
class MatchingLoop {
 public:
  MatchingLoop(const IndexedCloud& source, const IndexedCloud& target,
               const RegistrationOptions& options, const Eigen::Isometry3d& T_init)
      : source_(source),
        target_(target),
        options_(options),
        symmetric_(options.criterion == Criterion::kSymmetric),
        need_orientations_(NeedsOrientations(options)),
        orientation_test_(options),
        accelerate_(Accelerates(options)),
        anderson_(accelerate_ ? options.anderson_depth : 0),
        T_(T_init),
        T_plain_(T_init) {}

  double dmax() const { return dmax_; }
  bool Coarse(int it) const { return use_coarse_ && it <= options_.coarse_iterations; }

  // D and the initial Dmax = 20 D (§4.3), the seed gate, the sample and the orientation test's
  // staging. False (status set) when D cannot be derived.
  bool Prepare(RegistrationResult* result) {
    d_ref_ =
        options_.reference_distance_m > 0.0 ? options_.reference_distance_m : target_.spacing();
    result->reference_distance_m = d_ref_;
    if (!(d_ref_ > 0.0)) {
      result->status = RegistrationStatus::kTooFewPoints;
      result->message = "cannot derive the reference distance D: target points coincide";
      return false;
    }
    dmax_ = options_.dmax_initial_factor * d_ref_;
    spread_.rotation_var_rad2 = std::pow(options_.seed_rotation_sigma_deg * kDegToRad, 2);
    spread_.translation_var_m2 = std::pow(options_.seed_translation_sigma_m, 2);
    // Per-axis variance of the offset between two independent samplings of spacing D.
    sampling_variance_ = d_ref_ * d_ref_ / 12.0;
    translation_tol_ =
        options_.translation_tolerance_m > 0.0 ? options_.translation_tolerance_m : d_ref_ / 100.0;
    // The source points that are matched: one per voxel of edge sample_voxel_factor · D,
    // then at most max_sample_points of those, evenly through the input order.
    const double voxel_m =
        options_.sample_voxel_factor > 0.0 ? options_.sample_voxel_factor * d_ref_ : 0.0;
    source_sample_ =
        Decimate(VoxelSample(source_.cloud().points, voxel_m), options_.max_sample_points);
    if (symmetric_)
      target_sample_ =
          Decimate(VoxelSample(target_.cloud().points, voxel_m), options_.max_sample_points);
    result->sample_points = source_sample_.size();
    PlanStages();
    // One memo per sampled point, not per point: a KITTI frame's 260 000 memos were 15 MB to
    // clear per direction and frame, and a one-shot registration's page faults.
    forward_memos_.assign(source_sample_.size(), QueryMemo());
    backward_memos_.assign(symmetric_ ? target_sample_.size() : 0, QueryMemo());
    return true;
  }

  // A new stage (coarse subset or the whole sample) is a new objective: no history, no
  // unverified extrapolation; and the staged orientation test is dropped or widened.
  void BeginStage(bool coarse, RegistrationResult* result) {
    const std::size_t step = coarse ? static_cast<std::size_t>(options_.coarse_step) : 1;
    if (step == previous_step_) return;
    anderson_.Reset();
    if (extrapolated_) T_ = T_plain_;
    extrapolated_ = false;
    if (!staged_test_ || coarse || !orientation_test_.enabled) return;
    if (coarse_rejected_fraction_ < options_.orientation_min_rejected) {
      orientation_test_.enabled = false;
      if (options_.clean_sample_step > 1) {
        const auto clean_step = static_cast<std::size_t>(options_.clean_sample_step);
        source_sample_ = EveryKth(source_sample_, clean_step);
        target_sample_ = EveryKth(target_sample_, clean_step);
        forward_memos_ = EveryKth(forward_memos_, clean_step);
        backward_memos_ = EveryKth(backward_memos_, clean_step);
        result->sample_points = source_sample_.size();
      }
    } else {
      RequireQueried(1);
    }
  }

  // a. Closest points at T; an extrapolated T must not raise the energy over the previous
  // pose's at the current bound, or the plain iterate is matched instead.
  IterationTrace MatchClosestPoints(int it, bool coarse) {
    const std::size_t step = coarse ? static_cast<std::size_t>(options_.coarse_step) : 1;
    IterationTrace trace;
    trace.iteration = it;
    std::size_t queries = MatchAtT(step, &trace);
    bool rejected = false;
    if (extrapolated_ && TruncatedEnergy(distances_, queries, dmax_) >
                             TruncatedEnergy(previous_distances_, previous_queries_, dmax_)) {
      T_ = T_plain_;
      anderson_.Reset();
      rejected = true;
      MatchAtT(step, &trace);
    }
    trace.accelerated = extrapolated_ && !rejected;
    trace.extrapolation_rejected = rejected;
    extrapolated_ = false;                              // T is checked now (or plain)
    if (accelerate_) previous_distances_ = distances_;  // only the safeguard reads them
    previous_queries_ = queries;
    previous_step_ = step;
    trace.queries = rejected ? 2 * queries : queries;  // a rejected extrapolation matched twice
    trace.pairs_found = distances_.size();
    if (coarse)
      coarse_rejected_fraction_ = static_cast<double>(trace.pairs_rejected_by_orientation) /
                                  static_cast<double>(std::max<std::size_t>(
                                      1, trace.pairs_rejected_by_orientation + distances_.size()));
    return trace;
  }

  // b, c. The statistics of the distances set the next Dmax (§4.3, DmaxSchedule).
  void AdaptDmax(IterationTrace* trace) {
    const DmaxUpdate update = UpdateDmax(distances_, d_ref_, dmax_, options_.histogram_bins,
                                         options_.histogram_valley_ratio);
    dmax_ = update.dmax_m;
    trace->mean_m = update.mean_m;
    trace->stddev_m = update.stddev_m;
    trace->dmax_m = dmax_;
    trace->branch = update.branch;
  }

  // d. The pairs within the new Dmax or the gate, and their weights; symmetric: each
  // direction's term normalised by its own pair count. Returns how many are kept.
  std::size_t GatePairs(IterationTrace* trace) {
    KeepWithinGate(source_, target_, T_, dmax_, sampling_variance_, spread_, options_, &matches_,
                   &weights_);
    const std::size_t kept = matches_.size();
    std::size_t forward = 0;
    for (const Match& m : matches_) forward += !m.backward;
    const std::size_t backward = kept - forward;
    double sum_sq = 0.0;
    for (std::size_t k = 0; k < kept; ++k) {
      const Match& m = matches_[k];
      sum_sq += m.distance * m.distance;
      if (symmetric_) weights_[k] /= static_cast<double>(m.backward ? backward : forward);
    }
    trace->pairs_kept = kept;
    trace->rms_m = kept > 0 ? std::sqrt(sum_sq / static_cast<double>(kept)) : 0.0;
    return kept;
  }

  // e. The motion that best aligns the kept pairs, from the original source points.
  bool SolveMotion(Eigen::Isometry3d* T_new) {
    *T_new = T_;
    if (EffectiveResidual(options_) == Residual::kPointToPlane)
      return PointToPlaneStep(source_, target_, matches_, weights_, T_new);
    pairs_.clear();
    for (std::size_t k = 0; k < matches_.size(); ++k)
      pairs_.push_back({source_.cloud().points[matches_[k].source_index],
                        target_.cloud().points[matches_[k].target_index], weights_[k]});
    const MotionEstimate est = options_.solver == Solver::kDualQuaternion
                                   ? SolveMotionDualQuaternion(pairs_)
                                   : SolveMotionSvd(pairs_);
    *T_new = est.T_target_source;
    return est.valid;
  }

  // f. Takes the plain step T_new (recorded in the trace) and says whether to stop: the step
  // is below the tolerances, or the iterates cycle. The seed gate closes as the steps shrink.
  bool Settle(const Eigen::Isometry3d& T_new, bool coarse, IterationTrace* trace,
              RegistrationResult* result) {
    trace->step_translation_m = (T_new.translation() - T_.translation()).norm();
    trace->step_rotation_deg =
        Eigen::AngleAxisd(T_new.linear() * T_.linear().transpose()).angle() * kRadToDeg;
    result->trace.push_back(*trace);
    const bool small_step =
        options_.convergence == Convergence::kRelative
            ? RelativeConverged(T_, T_new, options_.relative_tolerance, d_ref_ * 1e-4)
            : trace->step_translation_m < translation_tol_ &&
                  trace->step_rotation_deg < options_.rotation_tolerance_deg;
    const bool cycling = !small_step && Cycling(T_new);
    // What is left of the seed's uncertainty is at most a few times this step: the gate closes
    // as the estimate settles, and is the sensor's alone once it has.
    spread_.rotation_var_rad2 =
        std::min(spread_.rotation_var_rad2,
                 std::pow(kSeedGateStepFactor * trace->step_rotation_deg * kDegToRad, 2));
    spread_.translation_var_m2 = std::min(
        spread_.translation_var_m2, std::pow(kSeedGateStepFactor * trace->step_translation_m, 2));
    if (recent_.size() == kCycleMemory) recent_.erase(recent_.begin());
    recent_.push_back(T_);  // the iterate before this one: comparing with it is the step test
    T_prev_ = T_;
    T_ = T_new;
    result->iterations = trace->iteration;
    // In the coarse stage a small step only means the subset has settled: go on to all points.
    return (small_step || cycling) && !coarse;
  }

  // Anderson's extrapolation from the plain step (checked at the next matching).
  void Extrapolate() {
    const AndersonAccelerator::Vector6 g = PoseParameters(T_);
    const AndersonAccelerator::Vector6 next = anderson_.Next(PoseParameters(T_prev_), g);
    extrapolated_ = next != g;
    if (extrapolated_) {
      T_plain_ = T_;
      T_ = PoseFromParameters(next);
    }
  }

  // The estimate (never an unchecked extrapolation), its final pairs, inliers, RMS and
  // information.
  void Finish(RegistrationResult* result) {
    if (extrapolated_) T_ = T_plain_;
    result->converged = result->status == RegistrationStatus::kConverged;
    result->T_target_source = T_;
    result->dmax_m = dmax_;
    matches_.clear();
    MatchDirection(source_, target_, T_, dmax_, PoseSpread(), orientation_test_, source_sample_, 1,
                   false, need_orientations_, options_.reuse_closest_points, &forward_memos_,
                   &matches_, nullptr);
    KeepWithinGate(source_, target_, T_, dmax_, sampling_variance_, PoseSpread(), options_,
                   &matches_, &weights_);
    const std::size_t kept = matches_.size();
    double sum_sq = 0.0;
    for (const Match& m : matches_) sum_sq += m.distance * m.distance;
    result->inliers = kept;
    result->inlier_ratio = source_sample_.empty() ? 0.0
                                                  : static_cast<double>(kept) /
                                                        static_cast<double>(source_sample_.size());
    result->rms_m = kept > 0 ? std::sqrt(sum_sq / static_cast<double>(kept)) : 0.0;
    ComputeInformation(source_, target_, matches_, T_, sampling_variance_, options_, result);
  }

 private:
  // Iterates a cycle may span (see Cycling).
  static constexpr std::size_t kCycleMemory = 8;

  // The orientation test needs the queried points' own orientations. Staged, it is first run
  // on the coarse subset only, and kept for the fine stage only if it rejected enough of the
  // coarse pairs (`orientation_min_rejected`): on clean scans it removes next to nothing, and
  // the source's PCA normals over the whole sample were most of its cost. A source with given
  // normals (stereo) pays nothing for the test and gets no coarse stage from it: coarse to
  // fine moved each stereo frame's stopping point and raised the simulated stereo replay's ATE
  // (docs/matcher.md, "Where the defaults differ from the paper, and why"). A coarse stage on
  // every 5th point saved KITTI registration time at the same accuracy, but broke a frame of a
  // biased seed and ran the simulated cloud traverse to the iteration limit: not adopted
  // (docs/matcher.md, "What a registration costs").
  // Dropped, it also thins the fine stage (clean_sample_step): pairs the coarse stage found
  // clean give the same accuracy from a quarter of the sample, and the fine queries and the
  // target normals they need were most of what was left.
  // Coarse to fine (§4.5) pays where queries are many; a coarse subset of a few dozen points
  // (a 200-point curve: 20) makes a poor estimate and saves nothing.
  void PlanStages() {
    constexpr std::size_t kMinCoarseQueries = 500;
    const bool stage_test = options_.staged_orientation_test && orientation_test_.enabled &&
                            source_.EstimatesOrientations();
    use_coarse_ =
        (options_.coarse_to_fine || stage_test) && options_.coarse_iterations > 0 &&
        options_.coarse_step > 1 &&
        source_sample_.size() / static_cast<std::size_t>(options_.coarse_step) >= kMinCoarseQueries;
    staged_test_ = orientation_test_.enabled && use_coarse_ && options_.staged_orientation_test;
    if (orientation_test_.enabled)
      RequireQueried(staged_test_ ? static_cast<std::size_t>(options_.coarse_step) : 1);
  }

  void RequireQueried(std::size_t step) {
    const std::vector<std::size_t> s = step > 1 ? EveryKth(source_sample_, step) : source_sample_;
    const std::vector<std::size_t> t = step > 1 ? EveryKth(target_sample_, step) : target_sample_;
    source_.RequireOrientations(s);
    target_.RequireOrientations(t);
    orientation_test_.spread_cap = MedianSpread(source_, s, target_, t);
  }

  // One matching at T (both ways for the symmetric criterion): fills matches_ and distances_,
  // adds to the trace's searches and orientation rejections; returns the queries made.
  std::size_t MatchAtT(std::size_t step, IterationTrace* trace) {
    matches_.clear();
    std::size_t searches = 0;
    trace->pairs_rejected_by_orientation = MatchDirection(
        source_, target_, T_, dmax_, spread_, orientation_test_, source_sample_, step, false,
        need_orientations_, options_.reuse_closest_points, &forward_memos_, &matches_, &searches);
    std::size_t n = (source_sample_.size() + step - 1) / step;
    if (symmetric_) {
      trace->pairs_rejected_by_orientation +=
          MatchDirection(target_, source_, T_.inverse(), dmax_, spread_, orientation_test_,
                         target_sample_, step, true, need_orientations_,
                         options_.reuse_closest_points, &backward_memos_, &matches_, &searches);
      n += (target_sample_.size() + step - 1) / step;
    }
    trace->searches += searches;
    distances_.clear();
    for (const Match& m : matches_) distances_.push_back(m.distance);
    return n;
  }

  // A cycle: the pairs flip between a few sets and the plain iterate comes back to within the
  // stopping tolerances of one of the last few (seen on stereo frames: period 2 to 7, steps of
  // 0.005° that never went below the rotation tolerance, so every such frame ran to
  // max_iterations). The estimate cannot get better than that.
  bool Cycling(const Eigen::Isometry3d& T_new) const {
    if (options_.convergence != Convergence::kAbsolute) return false;
    bool cycling = false;
    for (const Eigen::Isometry3d& earlier : recent_) {
      cycling |=
          (T_new.translation() - earlier.translation()).norm() < translation_tol_ &&
          Eigen::AngleAxisd(T_new.linear() * earlier.linear().transpose()).angle() * kRadToDeg <
              options_.rotation_tolerance_deg;
    }
    return cycling;
  }

  const IndexedCloud& source_;
  const IndexedCloud& target_;
  const RegistrationOptions& options_;
  const bool symmetric_;
  const bool need_orientations_;
  OrientationTest orientation_test_;
  const bool accelerate_;
  AndersonAccelerator anderson_;

  double d_ref_ = 0.0;              // D [m]
  double dmax_ = 0.0;               // [m]
  double sampling_variance_ = 0.0;  // [m²]
  double translation_tol_ = 0.0;    // [m]
  PoseSpread spread_;               // the seed's uncertainty, shrunk step by step (SeedGate)
  bool use_coarse_ = false;
  bool staged_test_ = false;
  double coarse_rejected_fraction_ = 0.0;  // of the pairs found, in the last coarse iteration
  std::vector<std::size_t> source_sample_, target_sample_;
  std::vector<QueryMemo> forward_memos_, backward_memos_;

  Eigen::Isometry3d T_;
  Eigen::Isometry3d T_plain_;  // the plain iterate behind an extrapolated T_ (the fallback)
  Eigen::Isometry3d T_prev_ = Eigen::Isometry3d::Identity();  // the iterate before T_
  bool extrapolated_ = false;  // T_ is an extrapolation the safeguard has not checked yet
  std::vector<double> previous_distances_;  // the previous pose's, for the safeguard
  std::size_t previous_queries_ = 0, previous_step_ = 0;
  std::vector<Eigen::Isometry3d> recent_;

  std::vector<Match> matches_;
  std::vector<double> distances_, weights_;
  std::vector<WeightedPair> pairs_;
};

}  // namespace

const char* ToString(RegistrationStatus status) {
  switch (status) {
    case RegistrationStatus::kConverged:
      return "converged";
    case RegistrationStatus::kMaxIterations:
      return "max_iterations";
    case RegistrationStatus::kTooFewPoints:
      return "too_few_points";
    case RegistrationStatus::kTooFewPairs:
      return "too_few_pairs";
    case RegistrationStatus::kSolverFailed:
      return "solver_failed";
    case RegistrationStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

IndexedCloud::IndexedCloud(PointCloud cloud, const RegistrationOptions& options)
    : cloud_(std::move(cloud)), normal_neighbors_(options.normal_neighbors) {
  if (!NeedsOrientations(options)) return;
  if (options.geometry == Geometry::kCurve) {
    orientations_ = EstimateTangents(cloud_, &spreads_);
  } else if (cloud_.HasNormals()) {
    orientations_ = cloud_.normals;
  } else {
    orientations_.assign(cloud_.size(), Eigen::Vector3d::Zero());
    spreads_.assign(cloud_.size(), 0.0);
    known_.assign(cloud_.size(), 0);
  }
}

void IndexedCloud::RequireOrientations(const std::vector<std::size_t>& indices) const {
  if (known_.empty()) return;
  const std::lock_guard<std::mutex> lock(orientation_mutex_);
  std::vector<std::size_t> missing;
  for (const std::size_t i : indices) {
    if (i < known_.size() && !known_[i]) {
      known_[i] = 1;
      missing.push_back(i);
    }
  }
  if (!missing.empty())
    EstimateNormalsAt(cloud_.points, tree(), normal_neighbors_, missing, &orientations_, &spreads_);
}

const KdTree& IndexedCloud::tree() const {
  std::call_once(tree_once_, [this] { tree_ = std::make_unique<KdTree>(cloud_.points); });
  return *tree_;
}

IndexedCloud::IndexedCloud(PointCloud cloud, const RegistrationOptions& options, double spacing_m)
    : IndexedCloud(std::move(cloud), options) {
  if (spacing_m > 0.0 && std::isfinite(spacing_m)) given_spacing_ = spacing_m;
}

double IndexedCloud::spacing() const {
  if (given_spacing_ > 0.0) return given_spacing_;
  std::call_once(spacing_once_,
                 [this] { spacing_ = MedianNeighborSpacing(cloud_.points, tree()); });
  return spacing_;
}

RegistrationResult Register(const PointCloud& source, const PointCloud& target,
                            const Eigen::Isometry3d& T_init, const RegistrationOptions& options) {
  const IndexedCloud s(source, options), t(target, options);
  return Register(s, t, T_init, options);
}

RegistrationResult Register(const IndexedCloud& source, const IndexedCloud& target,
                            const Eigen::Isometry3d& T_init, const RegistrationOptions& options) {
  RegistrationResult result;
  result.T_target_source = T_init;
  if (!CheckInputs(source, target, options, &result)) return result;
  MatchingLoop loop(source, target, options, T_init);
  if (!loop.Prepare(&result)) return result;  // D, the initial Dmax and the sample (§4.3)
  result.status = RegistrationStatus::kMaxIterations;
  for (int it = 1; it <= options.max_iterations; ++it) {
    const bool coarse = loop.Coarse(it);
    loop.BeginStage(coarse, &result);
    // a. Closest points within Dmax, both ways for the symmetric criterion (§4.1, §4.2).
    IterationTrace trace = loop.MatchClosestPoints(it, coarse);
    // b, c. Statistics of the distances and the new Dmax.
    loop.AdaptDmax(&trace);
    // d. Discard pairs beyond Dmax, or outside the Mahalanobis gate (§4.4); weights.
    const std::size_t kept = loop.GatePairs(&trace);
    if (kept < static_cast<std::size_t>(std::max(3, options.min_pairs))) {
      result.trace.push_back(trace);
      result.status = RegistrationStatus::kTooFewPairs;
      result.message = "only " + std::to_string(kept) +
                       " pairs within Dmax = " + std::to_string(loop.dmax()) + " m at iteration " +
                       std::to_string(it);
      break;
    }
    // e. Least-squares motion from the ORIGINAL source points (replaces T, §4.3 step 3e).
    Eigen::Isometry3d T_new;
    if (!loop.SolveMotion(&T_new)) {
      result.trace.push_back(trace);
      result.status = RegistrationStatus::kSolverFailed;
      result.message = "motion solve failed at iteration " + std::to_string(it);
      break;
    }
    // f. Stopping test on the plain step, then the extrapolation from it.
    if (loop.Settle(T_new, coarse, &trace, &result)) {
      result.status = RegistrationStatus::kConverged;
      break;
    }
    loop.Extrapolate();
  }
  loop.Finish(&result);  // final pairs at the final estimate: inliers, RMS, information
  return result;
}

}  // namespace rovermap::registration
