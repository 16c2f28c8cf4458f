// Open3D peers: open3d::pipelines::registration::RegistrationICP, point-to-point and
// point-to-plane (KDTreeFlann built inside RegistrationICP; correspondences and normals use
// OpenMP with omp_get_max_threads() threads).

#include <open3d/Open3DConfig.h>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>
#include <open3d/utility/Logging.h>

#include <chrono>
#include <string>

#include "bench/Peers.hpp"

namespace rovermap::bench {
namespace {

namespace o3g = open3d::geometry;
namespace o3r = open3d::pipelines::registration;
namespace o3u = open3d::utility;

class Open3dIcp final : public PeerMethod {
 public:
  Open3dIcp(const Points& source, const Points& target, bool point_to_plane)
      : source_(source), target_(target), point_to_plane_(point_to_plane) {}

  std::string Name() const override {
    return point_to_plane_ ? "Open3D ICP point-to-plane" : "Open3D ICP point-to-point";
  }

  PeerResult Run(const Eigen::Isometry3d& T_init, const PeerParams& params) override {
    // Fresh copy without normals, made before the timer: normal estimation is timed.
    o3g::PointCloud target = target_;
    const o3r::ICPConvergenceCriteria criteria(1e-6, 1e-6, params.max_iterations);
    PeerResult out;
    const auto t0 = std::chrono::steady_clock::now();
    o3r::RegistrationResult result;
    if (point_to_plane_) {
      target.EstimateNormals(o3g::KDTreeSearchParamKNN(10));
      result = o3r::RegistrationICP(source_, target, params.max_correspondence_m,
                                    T_init.matrix(), o3r::TransformationEstimationPointToPlane(),
                                    criteria);
    } else {
      result = o3r::RegistrationICP(source_, target, params.max_correspondence_m,
                                    T_init.matrix(),
                                    o3r::TransformationEstimationPointToPoint(false), criteria);
    }
    const auto t1 = std::chrono::steady_clock::now();
    out.time_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    out.T_target_source.matrix() = result.transformation_;
    return out;
  }

  // RegistrationICP does not return its iteration count; it logs one debug line per
  // iteration ("ICP Iteration #i: ..."), so run once more with the debug log captured.
  int CountIterations(const Eigen::Isometry3d& T_init, const PeerParams& params) override {
    int count = 0;
    o3u::Logger& logger = o3u::Logger::GetInstance();
    logger.SetPrintFunction([&count](const std::string& message) {
      if (message.find("ICP Iteration #") != std::string::npos) ++count;
    });
    const o3u::VerbosityLevel previous = logger.GetVerbosityLevel();
    logger.SetVerbosityLevel(o3u::VerbosityLevel::Debug);
    Run(T_init, params);
    logger.SetVerbosityLevel(previous);
    logger.ResetPrintFunction();
    return count;
  }

 private:
  o3g::PointCloud source_;
  o3g::PointCloud target_;
  bool point_to_plane_;
};

}  // namespace

std::unique_ptr<PeerMethod> MakeOpen3dPointToPoint(const Points& source, const Points& target) {
  return std::make_unique<Open3dIcp>(source, target, false);
}

std::unique_ptr<PeerMethod> MakeOpen3dPointToPlane(const Points& source, const Points& target) {
  return std::make_unique<Open3dIcp>(source, target, true);
}

std::string Open3dVersion() { return OPEN3D_VERSION; }

}  // namespace rovermap::bench
