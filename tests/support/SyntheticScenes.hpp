#pragma once
// Synthetic scenes with known motion for the matcher's tests and benchmarks: rover-like
// terrain surfaces and 3-D curves, with noise, outliers and partial overlap.

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "registration/PointCloud.hpp"

namespace rovermap::testing {

/// Smooth rolling terrain with a few rocks [m].
inline double TerrainHeight(double x, double y) {
  double z = 0.30 * std::sin(0.7 * x) * std::cos(0.5 * y) + 0.10 * std::sin(2.3 * x + 1.0) * std::sin(1.7 * y);
  const double rocks[][4] = {{2.0, 1.5, 0.25, 0.15}, {4.5, 3.8, 0.35, 0.20}, {6.5, 1.2, 0.20, 0.12},
                             {3.2, 4.9, 0.30, 0.18}, {7.4, 4.2, 0.25, 0.15}};
  for (const auto& r : rocks) {
    const double d2 = (x - r[0]) * (x - r[0]) + (y - r[1]) * (y - r[1]);
    z += r[3] * std::exp(-d2 / (2.0 * r[2] * r[2]));
  }
  return z;
}

struct SceneOptions {
  double spacing_m = 0.05;        ///< grid spacing of the samples
  double noise_m = 0.005;         ///< isotropic Gaussian noise σ
  double outlier_fraction = 0.15; ///< points replaced by uniform outliers
  /// Range-dependent noise (stereo-like): σ along the view ray grows as
  /// noise_m · (range / 3 m)², the sensor at `sensor_position` of each frame.
  bool range_noise = false;
  unsigned seed = 1;
};

struct ScenePair {
  registration::PointCloud source;  ///< in the source frame
  registration::PointCloud target;  ///< in the target (= world) frame
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();  ///< ground truth
};

/// A rover-like motion: ~0.6 m forward, 4° yaw, small roll and pitch.
inline Eigen::Isometry3d RoverMotion() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(4.0 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(1.5 * M_PI / 180, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(-1.0 * M_PI / 180, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.6, 0.15, 0.03);
  return T;
}

namespace detail {

// Samples the terrain over [x0, x0+w] × [y0, y0+h] (world), maps into a frame with
// T_frame_world, adds noise (covariance recorded) and outliers.
inline registration::PointCloud SampleTerrain(double x0, double y0, double w, double h,
                                              const Eigen::Isometry3d& T_frame_world,
                                              const Eigen::Vector3d& sensor_world,
                                              const SceneOptions& o, std::mt19937& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  registration::PointCloud cloud;
  for (double x = x0; x <= x0 + w; x += o.spacing_m) {
    for (double y = y0; y <= y0 + h; y += o.spacing_m) {
      Eigen::Vector3d p(x, y, TerrainHeight(x, y));
      Eigen::Matrix3d cov = o.noise_m * o.noise_m * Eigen::Matrix3d::Identity();
      if (o.range_noise) {
        const Eigen::Vector3d ray = p - sensor_world;
        const double range = ray.norm();
        const Eigen::Vector3d dir = ray / range;
        const double s_along = o.noise_m * (range / 3.0) * (range / 3.0);
        const double s_across = o.noise_m * 0.3;
        cov = s_across * s_across * Eigen::Matrix3d::Identity() +
              (s_along * s_along - s_across * s_across) * dir * dir.transpose();
      }
      const Eigen::LLT<Eigen::Matrix3d> llt(cov);
      p += llt.matrixL() * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
      if (u01(rng) < o.outlier_fraction) {
        p = Eigen::Vector3d(x0 + w * u01(rng), y0 + h * u01(rng), -0.5 + 1.5 * u01(rng));
      }
      const Eigen::Matrix3d r = T_frame_world.linear();
      cloud.points.push_back(T_frame_world * p);
      cloud.covariances.push_back(r * cov * r.transpose());
    }
  }
  return cloud;
}

}  // namespace detail

/// Two overlapping terrain patches (8 m × 6 m each, about 80 % overlap) seen from two
/// rover poses related by `T_target_source`; the grids are offset by half a cell so that
/// no sample has an exact counterpart.
inline ScenePair MakeTerrainPair(const SceneOptions& o,
                                 const Eigen::Isometry3d& T_target_source = RoverMotion()) {
  std::mt19937 rng(o.seed);
  ScenePair pair;
  pair.T_target_source = T_target_source;
  const Eigen::Vector3d sensor_target(-1.0, 3.0, 1.5);
  pair.target = detail::SampleTerrain(0.0, 0.0, 8.0, 6.0, Eigen::Isometry3d::Identity(),
                                      sensor_target, o, rng);
  const Eigen::Vector3d sensor_source = T_target_source * sensor_target;
  pair.source = detail::SampleTerrain(1.0 + 0.5 * o.spacing_m, 0.3 + 0.5 * o.spacing_m, 8.0, 6.0,
                                      T_target_source.inverse(), sensor_source, o, rng);
  return pair;
}

/// Chains of a 3-D curve (a trefoil knot, 1 m across, and a helix), sampled every
/// `o.spacing_m` along the parameter, source chains shifted by half a sample.
inline ScenePair MakeCurvePair(const SceneOptions& o, const Eigen::Isometry3d& T_target_source) {
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  ScenePair pair;
  pair.T_target_source = T_target_source;
  auto curve = [](int chain, double s) -> Eigen::Vector3d {
    if (chain == 0)
      return 0.3 * Eigen::Vector3d(std::sin(s) + 2 * std::sin(2 * s), std::cos(s) - 2 * std::cos(2 * s),
                                   -std::sin(3 * s));
    return Eigen::Vector3d(1.5 + 0.3 * std::cos(s), 0.3 * std::sin(s), 0.1 * s);
  };
  const Eigen::Isometry3d T_source_target = T_target_source.inverse();
  for (int side = 0; side < 2; ++side) {
    registration::PointCloud& cloud = side == 0 ? pair.target : pair.source;
    const double offset = side == 0 ? 0.0 : 0.5;
    // Partial overlap: each side misses a different part of each curve.
    const double s0 = side == 0 ? 0.0 : 0.6, s1 = side == 0 ? 2 * M_PI - 0.6 : 2 * M_PI;
    for (int chain = 0; chain < 2; ++chain) {
      const double ds = o.spacing_m;
      for (double s = s0 + offset * ds; s <= s1; s += ds) {
        Eigen::Vector3d p = curve(chain, s) + o.noise_m * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
        if (u01(rng) < o.outlier_fraction)
          p = Eigen::Vector3d(-1.0 + 3.0 * u01(rng), -1.0 + 2.0 * u01(rng), -0.5 + 1.5 * u01(rng));
        cloud.points.push_back(side == 0 ? p : T_source_target * p);
        cloud.chain_ids.push_back(chain);
        cloud.covariances.push_back(o.noise_m * o.noise_m * Eigen::Matrix3d::Identity());
      }
    }
  }
  return pair;
}

/// Rotation error [deg] (angle of R_a R_bᵀ) and translation error ‖t_a − t_b‖ [m].
inline std::pair<double, double> PoseError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::Isometry3d d = a.inverse() * b;
  return {Eigen::AngleAxisd(d.linear()).angle() * 180.0 / M_PI, d.translation().norm()};
}

/// T with its rotation turned by `angle_deg` about `axis` (R' = ΔR·R) and its translation
/// moved by `offset_m` along a fixed direction (t' = t + δ): "angle and offset off".
inline Eigen::Isometry3d Perturb(const Eigen::Isometry3d& T, double angle_deg, double offset_m,
                                 Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 3)) {
  Eigen::Isometry3d out = T;
  out.linear() = Eigen::AngleAxisd(angle_deg * M_PI / 180, axis.normalized()).toRotationMatrix() *
                 T.linear();
  out.translation() = T.translation() + offset_m * Eigen::Vector3d(2, -1, 1).normalized();
  return out;
}

}  // namespace rovermap::testing
