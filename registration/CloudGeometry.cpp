#include "registration/CloudGeometry.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace rovermap::registration {

namespace {

// PCA normal of point i from its k nearest neighbours (zero when the neighbourhood is
// degenerate) and its expected angular error in `spread` (NormalSpread); `indices` and
// `dists` are caller buffers of k entries.
Eigen::Vector3d PcaNormal(const std::vector<Eigen::Vector3d>& points, const KdTree& tree,
                          std::size_t i, std::size_t k, std::size_t* indices, double* dists,
                          double* spread) {
  *spread = 0.0;
  const std::size_t found = tree.FindKNearest(points[i], k, indices, dists);
  if (found < 3) return Eigen::Vector3d::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < found; ++j) mean += points[indices[j]];
  mean /= static_cast<double>(found);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < found; ++j) {
    const Eigen::Vector3d d = points[indices[j]] - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);  // closed form for 3×3: several times faster than iterating
  // A degenerate neighbourhood (all coincident or collinear) has no defined normal.
  const Eigen::Vector3d& l = eig.eigenvalues();
  if (l(1) <= 1e-12 * std::max(1.0, l(2))) return Eigen::Vector3d::Zero();
  *spread = NormalSpread(std::max(l(0), 0.0), l(1), l(2), found);
  return eig.eigenvectors().col(0).normalized();
}

}  // namespace

double NormalSpread(double l0, double l1, double l2, std::size_t k) {
  if (!(l1 > 0.0) || !(l2 > 0.0) || k == 0) return 0.0;
  return std::sqrt(l0 * (1.0 / l1 + 1.0 / l2) / static_cast<double>(k));
}

void EstimateNormalsAt(const std::vector<Eigen::Vector3d>& points, const KdTree& tree, int k,
                       const std::vector<std::size_t>& which, std::vector<Eigen::Vector3d>* normals,
                       std::vector<double>* spreads) {
  normals->resize(points.size(), Eigen::Vector3d::Zero());
  if (spreads) spreads->resize(points.size(), 0.0);
  const auto n = static_cast<long>(which.size());
  const auto k_size = static_cast<std::size_t>(std::max(k, 0));
#pragma omp parallel if (n > 256)
  {
    // Per-thread neighbour buffers: no allocation per point.
    std::vector<std::size_t> indices(k_size);
    std::vector<double> dists(k_size);
#pragma omp for schedule(dynamic, 256)
    for (long q = 0; q < n; ++q) {
      const std::size_t i = which[static_cast<std::size_t>(q)];
      double spread = 0.0;
      (*normals)[i] = PcaNormal(points, tree, i, k_size, indices.data(), dists.data(), &spread);
      if (spreads) (*spreads)[i] = spread;
    }
  }
}

std::vector<Eigen::Vector3d> EstimateNormals(const std::vector<Eigen::Vector3d>& points,
                                             const KdTree& tree, int k) {
  std::vector<std::size_t> all(points.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  std::vector<Eigen::Vector3d> normals;
  EstimateNormalsAt(points, tree, k, all, &normals);
  return normals;
}

std::vector<Eigen::Vector3d> EstimateTangents(const PointCloud& cloud,
                                              std::vector<double>* spreads) {
  const auto& p = cloud.points;
  const std::size_t n = p.size();
  std::vector<Eigen::Vector3d> tangents(n, Eigen::Vector3d::Zero());
  auto same_chain = [&](std::size_t a, std::size_t b) {
    return !cloud.HasChains() || cloud.chain_ids[a] == cloud.chain_ids[b];
  };
  // Per interior point: |d|² of its chord and |e⊥|², the middle point's offset from it.
  std::vector<double> chord_sq(n, 0.0), offset_sq(n, -1.0);  // -1: no chord (chain end)
  for (std::size_t i = 0; i < n; ++i) {
    const bool has_prev = i > 0 && same_chain(i - 1, i);
    const bool has_next = i + 1 < n && same_chain(i, i + 1);
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    if (has_prev && has_next) {
      d = p[i + 1] - p[i - 1];
      const double len = d.norm();
      if (len > 0.0) {
        const Eigen::Vector3d e = p[i] - 0.5 * (p[i + 1] + p[i - 1]);
        const Eigen::Vector3d u = d / len;
        chord_sq[i] = len * len;
        offset_sq[i] = (e - e.dot(u) * u).squaredNorm();
      }
    } else if (has_next) {
      d = p[i + 1] - p[i];
    } else if (has_prev) {
      d = p[i] - p[i - 1];
    }
    const double len = d.norm();
    if (len > 0.0) tangents[i] = d / len;
    if (!has_prev || !has_next) chord_sq[i] = len * len;
  }
  if (!spreads) return tangents;
  spreads->assign(n, 0.0);
  constexpr std::size_t kHalfWindow = 2;  // five chords: a steadier σ² than one offset
  for (std::size_t i = 0; i < n; ++i) {
    if (!(chord_sq[i] > 0.0)) continue;
    double sum = 0.0;
    int count = 0;
    const std::size_t first = i >= kHalfWindow ? i - kHalfWindow : 0;
    for (std::size_t j = first; j <= std::min(n - 1, i + kHalfWindow); ++j) {
      if (offset_sq[j] < 0.0 || !same_chain(i, j)) continue;
      sum += offset_sq[j];
      ++count;
    }
    if (count == 0) continue;
    const double sigma_sq = sum / count / 3.0;  // E|e⊥|² = 3σ²
    (*spreads)[i] = 2.0 * std::sqrt(sigma_sq / chord_sq[i]);
  }
  return tangents;
}

double MedianNeighborSpacing(const std::vector<Eigen::Vector3d>& points, const KdTree& tree,
                             std::size_t max_samples) {
  if (points.size() < 2) return 0.0;
  const std::size_t step =
      std::max<std::size_t>(1, points.size() / std::max<std::size_t>(1, max_samples));
  const auto samples = static_cast<long>((points.size() + step - 1) / step);
  // Per sample: the distance to the nearest other point, NaN if only duplicates are near.
  std::vector<double> spacing(static_cast<std::size_t>(samples), std::nan(""));
#pragma omp parallel for schedule(static) if (samples > 512)
  for (long s = 0; s < samples; ++s) {
    // The point itself and its nearest neighbour (a 2-NN search prunes sooner than a 4-NN);
    // a few more only when that one is an exact duplicate, so that duplicates do not hide the
    // real spacing.
    std::size_t indices[4];
    double dists[4];
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(s) * step];
    std::size_t found = tree.FindKNearest(p, 2, indices, dists);
    if (found == 2 && !(dists[1] > 0.0)) found = tree.FindKNearest(p, 4, indices, dists);
    for (std::size_t j = 0; j < found; ++j) {
      if (dists[j] > 0.0) {
        spacing[static_cast<std::size_t>(s)] = std::sqrt(dists[j]);
        break;
      }
    }
  }
  spacing.erase(
      std::remove_if(spacing.begin(), spacing.end(), [](double d) { return std::isnan(d); }),
      spacing.end());
  if (spacing.empty()) return 0.0;
  auto mid = spacing.begin() + static_cast<long>(spacing.size() / 2);
  std::nth_element(spacing.begin(), mid, spacing.end());
  return *mid;
}

}  // namespace rovermap::registration
