// Open3D peers: open3d::pipelines::registration::RegistrationICP, point-to-point and
// point-to-plane, and RegistrationGeneralizedICP (KDTreeFlann built inside RegistrationICP;
// correspondences, normals and covariances use OpenMP with omp_get_max_threads() threads).

#include <open3d/Open3DConfig.h>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/GeneralizedICP.h>
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

enum class Kind { kPointToPoint, kPointToPlane, kGeneralized };

class Open3dIcp final : public PeerMethod {
 public:
  Open3dIcp(const Points& source, const Points& target, Kind kind)
      : source_(source), target_(target), kind_(kind) {}

  std::string Name() const override {
    switch (kind_) {
      case Kind::kPointToPoint: return "Open3D ICP point-to-point";
      case Kind::kPointToPlane: return "Open3D ICP point-to-plane";
      case Kind::kGeneralized: return "Open3D Generalized-ICP";
    }
    return "Open3D";
  }

  PeerResult Run(const Eigen::Isometry3d& T_init, const PeerParams& params) override {
    // Fresh copy without normals, made before the timer: normal estimation is timed.
    o3g::PointCloud target = target_;
    const o3r::ICPConvergenceCriteria criteria(1e-6, 1e-6, params.max_iterations);
    PeerResult out;
    const auto t0 = std::chrono::steady_clock::now();
    o3r::RegistrationResult result;
    if (kind_ == Kind::kPointToPlane) {
      target.EstimateNormals(o3g::KDTreeSearchParamKNN(params.normals_knn));
      result = o3r::RegistrationICP(source_, target, params.max_correspondence_m,
                                    T_init.matrix(), o3r::TransformationEstimationPointToPlane(),
                                    criteria);
    } else if (kind_ == Kind::kGeneralized) {
      // Neither cloud has normals or covariances: the call estimates both clouds' covariances
      // (20 nearest neighbours, Segal et al.'s recipe) before its ICP loop.
      result = o3r::RegistrationGeneralizedICP(source_, target, params.max_correspondence_m,
                                               T_init.matrix(),
                                               o3r::TransformationEstimationForGeneralizedICP(),
                                               criteria);
    } else {
      result = o3r::RegistrationICP(source_, target, params.max_correspondence_m,
                                    T_init.matrix(),
                                    o3r::TransformationEstimationPointToPoint(false), criteria);
    }
    const auto t1 = std::chrono::steady_clock::now();
    out.time_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    out.T_target_source.matrix() = result.transformation_;
    out.fitness = result.fitness_;
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
  Kind kind_;
};

}  // namespace

std::unique_ptr<PeerMethod> MakeOpen3dPointToPoint(const Points& source, const Points& target) {
  return std::make_unique<Open3dIcp>(source, target, Kind::kPointToPoint);
}

std::unique_ptr<PeerMethod> MakeOpen3dPointToPlane(const Points& source, const Points& target) {
  return std::make_unique<Open3dIcp>(source, target, Kind::kPointToPlane);
}

std::unique_ptr<PeerMethod> MakeOpen3dGeneralizedIcp(const Points& source, const Points& target) {
  return std::make_unique<Open3dIcp>(source, target, Kind::kGeneralized);
}

std::string Open3dVersion() { return OPEN3D_VERSION; }

}  // namespace rovermap::bench
