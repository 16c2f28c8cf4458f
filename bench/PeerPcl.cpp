// PCL peer: pcl::IterativeClosestPoint<PointXYZ, PointXYZ> (float, point-to-point SVD,
// correspondences by a FLANN k-d tree built inside align(), single-threaded in PCL 1.13).

#include <pcl/pcl_config.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>

#include <chrono>

#include "bench/Peers.hpp"

namespace rovermap::bench {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// Exposes the iteration count, which PCL keeps protected.
class CountingIcp : public pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> {
 public:
  int iterations() const { return nr_iterations_; }
};

Cloud::Ptr ToPcl(const Points& points) {
  Cloud::Ptr cloud(new Cloud);
  cloud->reserve(points.size());
  for (const Eigen::Vector3d& p : points)
    cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                   static_cast<float>(p.z())));
  return cloud;
}

const char* StateName(pcl::registration::DefaultConvergenceCriteria<float>::ConvergenceState s) {
  using C = pcl::registration::DefaultConvergenceCriteria<float>;
  switch (s) {
    case C::CONVERGENCE_CRITERIA_NOT_CONVERGED: return "not_converged";
    case C::CONVERGENCE_CRITERIA_ITERATIONS: return "max_iterations";
    case C::CONVERGENCE_CRITERIA_TRANSFORM: return "conv(transform)";
    case C::CONVERGENCE_CRITERIA_ABS_MSE: return "conv(abs_mse)";
    case C::CONVERGENCE_CRITERIA_REL_MSE: return "conv(rel_mse)";
    case C::CONVERGENCE_CRITERIA_NO_CORRESPONDENCES: return "no_correspondences";
    case C::CONVERGENCE_CRITERIA_FAILURE_AFTER_MAX_ITERATIONS: return "fail_max_iterations";
  }
  return "?";
}

class PclIcp final : public PeerMethod {
 public:
  PclIcp(const Points& source, const Points& target)
      : source_(ToPcl(source)), target_(ToPcl(target)) {}

  std::string Name() const override { return "PCL ICP point-to-point"; }

  PeerResult Run(const Eigen::Isometry3d& T_init, const PeerParams& params) override {
    const Eigen::Matrix4f guess = T_init.matrix().cast<float>();
    Cloud aligned;
    PeerResult out;
    const auto t0 = std::chrono::steady_clock::now();
    {
      CountingIcp icp;  // fresh object: the target tree is rebuilt inside align()
      icp.setInputSource(source_);
      icp.setInputTarget(target_);
      icp.setMaxCorrespondenceDistance(params.max_correspondence_m);
      icp.setMaximumIterations(params.max_iterations);
      icp.setTransformationEpsilon(1e-10);  // squared translation step [m^2]; rotation 1 - 1e-10
      icp.setEuclideanFitnessEpsilon(1e-12);  // relative MSE change: effectively off
      icp.align(aligned, guess);
      const auto t1 = std::chrono::steady_clock::now();
      out.time_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
      out.T_target_source.matrix() = icp.getFinalTransformation().cast<double>();
      out.iterations = icp.iterations();
      out.status = StateName(icp.getConvergeCriteria()->getConvergenceState());
    }
    // Re-orthonormalise the float rotation before comparing.
    const Eigen::Quaterniond q(out.T_target_source.linear());
    out.T_target_source.linear() = q.normalized().toRotationMatrix();
    return out;
  }

  int CountIterations(const Eigen::Isometry3d& T_init, const PeerParams& params) override {
    return Run(T_init, params).iterations;
  }

 private:
  Cloud::Ptr source_, target_;
};

}  // namespace

std::unique_ptr<PeerMethod> MakePclIcp(const Points& source, const Points& target) {
  return std::make_unique<PclIcp>(source, target);
}

std::string PclVersion() { return PCL_VERSION_PRETTY; }

}  // namespace rovermap::bench
