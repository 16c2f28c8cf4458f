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
/// size; other entries are left as they are.
void EstimateNormalsAt(const std::vector<Eigen::Vector3d>& points, const KdTree& tree, int k,
                       const std::vector<std::size_t>& which, std::vector<Eigen::Vector3d>* normals);

/// Unit tangents of curves from the neighbours along each chain (central differences,
/// one-sided at chain ends). Without chain ids all points form one chain. Isolated points
/// get a zero vector (no orientation).
std::vector<Eigen::Vector3d> EstimateTangents(const PointCloud& cloud);

/// Median nearest-neighbour spacing [m] over at most `max_samples` evenly spaced points
/// (Zhang's D when not given). Duplicates (zero spacing) are skipped.
/// @return 0 if the set has fewer than 2 distinct points.
double MedianNeighborSpacing(const std::vector<Eigen::Vector3d>& points, const KdTree& tree,
                             std::size_t max_samples = 5000);

}  // namespace rovermap::registration
