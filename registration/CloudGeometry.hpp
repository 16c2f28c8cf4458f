#pragma once

#include <Eigen/Core>
#include <vector>

#include "registration/KdTree.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::registration {

/// Unit surface normals by PCA of the k nearest neighbours (the eigenvector of the
/// smallest eigenvalue of their covariance). Sign is arbitrary (the matcher compares
/// |cos|). Points with fewer than 3 neighbours get a zero vector (no orientation).
std::vector<Eigen::Vector3d> EstimateNormals(const std::vector<Eigen::Vector3d>& points,
                                             const KdTree& tree, int k);

/// The same for the points listed in `which` only (the matcher needs normals of the points it
/// samples and matches, often a small part of the cloud). `normals` is resized to the cloud's
/// size; other entries are left as they are. With `spreads`, also each normal's expected
/// angular error [rad] from the scatter of its neighbours (see NormalSpread), resized alike.
void EstimateNormalsAt(const std::vector<Eigen::Vector3d>& points, const KdTree& tree, int k,
                       const std::vector<std::size_t>& which, std::vector<Eigen::Vector3d>* normals,
                       std::vector<double>* spreads = nullptr);

/// Expected angular error [rad] of a PCA normal fitted to `k` points whose scatter matrix has
/// the eigenvalues l0 <= l1 <= l2: with noise of variance l0/k along the normal and the points
/// spread l1/k, l2/k along the plane, each tilt of the fitted plane has the variance
/// (l0/k) / (k · lj/k); the two tilts add: sqrt(l0 (1/l1 + 1/l2) / k).
double NormalSpread(double l0, double l1, double l2, std::size_t k);

/// Unit tangents of curves from the neighbours along each chain (central differences,
/// one-sided at chain ends). Without chain ids all points form one chain. Isolated points
/// get a zero vector (no orientation). With `spreads`, also each tangent's expected angular
/// error [rad]: a central difference d = p[i+1] − p[i−1] of points with per-axis noise σ
/// turns by 2σ/|d| (rms over both perpendicular axes), and σ² is estimated from the middle
/// point's offset e⊥ from the chord (E|e⊥|² = 3σ²), averaged over the five chords around i;
/// on a noise-free curve e⊥ is the sagitta (curvature · |d|²/8), so a finely sampled curve
/// keeps a small spread. Chain ends and isolated points get the spread of their neighbours'
/// estimate, or 0 (trusted) without one.
std::vector<Eigen::Vector3d> EstimateTangents(const PointCloud& cloud,
                                              std::vector<double>* spreads = nullptr);

/// Median nearest-neighbour spacing [m] over at most `max_samples` evenly spaced points
/// (Zhang's D when not given). Duplicates (zero spacing) are skipped.
/// @return 0 if the set has fewer than 2 distinct points.
double MedianNeighborSpacing(const std::vector<Eigen::Vector3d>& points, const KdTree& tree,
                             std::size_t max_samples = 5000);

}  // namespace rovermap::registration
