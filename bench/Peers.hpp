#pragma once
// Peer ICP implementations (PCL, Open3D) for bench_register and bench_drift, compiled only
// with -DROVERMAP_BENCH_PEERS=ON. Each peer gets the clouds in its own format, converted before
// the timer starts (as rovermap gets its PointCloud), and times everything from there to
// the result: tree building, normal estimation (point-to-plane), the ICP loop.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

namespace rovermap::bench {

/// Parameters shared by every peer (the gate is the same for every method of a pair).
struct PeerParams {
  double max_correspondence_m = 0.0;  ///< fixed correspondence gate [m]
  int max_iterations = 100;
  int normals_knn = 10;  ///< Open3D point-to-plane: neighbours of the target's normal estimate
};

struct PeerResult {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  double time_ms = 0.0;   ///< timed region only
  int iterations = -1;    ///< -1: not reported by this run (see CountIterations)
  std::string status;     ///< the peer's own convergence state, short
  double fitness = -1.0;  ///< Open3D: share of source points with a pair at the end (-1: n/a)
};

/// One peer method bound to one pair of clouds (converted once, reused for every run).
class PeerMethod {
 public:
  virtual ~PeerMethod() = default;
  virtual std::string Name() const = 0;
  /// One timed registration from `T_init`.
  virtual PeerResult Run(const Eigen::Isometry3d& T_init, const PeerParams& params) = 0;
  /// Iterations of a registration from `T_init` (untimed; may run it again with logging).
  virtual int CountIterations(const Eigen::Isometry3d& T_init, const PeerParams& params) = 0;
};

using Points = std::vector<Eigen::Vector3d>;

/// PCL 1.13 pcl::IterativeClosestPoint<PointXYZ, PointXYZ> (point-to-point, float, single
/// thread).
std::unique_ptr<PeerMethod> MakePclIcp(const Points& source, const Points& target);

/// Open3D 0.16 RegistrationICP, point-to-point (OpenMP).
std::unique_ptr<PeerMethod> MakeOpen3dPointToPoint(const Points& source, const Points& target);

/// Open3D 0.16 RegistrationICP, point-to-plane; target normals estimated (KNN
/// PeerParams::normals_knn) inside the timed region.
std::unique_ptr<PeerMethod> MakeOpen3dPointToPlane(const Points& source, const Points& target);

/// Open3D 0.16 RegistrationGeneralizedICP (Segal et al. 2009) with its defaults (ε = 1e-3,
/// L2 loss): both clouds' covariances estimated by Open3D from their 20 nearest neighbours
/// inside the timed region, as the call does for clouds without normals or covariances.
std::unique_ptr<PeerMethod> MakeOpen3dGeneralizedIcp(const Points& source, const Points& target);

/// Library versions for the report header.
std::string PclVersion();
std::string Open3dVersion();

}  // namespace rovermap::bench
