#include "core/Units.hpp"
#include "sim/DeadReckoning.hpp"

#include <cmath>

#include "sim/Terrain.hpp"  // HashNormal

namespace rovermap::sim {
namespace {
using core::kDegToRad;
constexpr std::uint64_t kSaltDeadReckoning = 7000;
}  // namespace

std::vector<io::StampedPose> DeadReckoningFromTruth(const std::vector<io::StampedPose>& truth,
                                                    const DeadReckoningModel& model) {
  std::vector<io::StampedPose> out;
  out.reserve(truth.size());
  for (std::size_t k = 0; k < truth.size(); ++k) {
    io::StampedPose pose;
    pose.timestamp = truth[k].timestamp;
    if (k == 0) {
      pose.T_world_body = truth[0].T_world_body;
    } else {
      const Eigen::Isometry3d step = truth[k - 1].T_world_body.inverse() * truth[k].T_world_body;
      const double length_m = step.translation().norm();
      const double heading_error_rad =
          (model.heading_bias_deg_per_m * length_m +
           model.heading_noise_deg * HashNormal(model.seed, kSaltDeadReckoning, k, 0)) *
          kDegToRad;
      Eigen::Isometry3d biased = step;
      biased.linear() =
          step.linear() * Eigen::AngleAxisd(heading_error_rad, Eigen::Vector3d::UnitZ()).matrix();
      for (int a = 0; a < 3; ++a) {
        biased.translation()(a) =
            step.translation()(a) * (1.0 + model.scale_error) +
            model.translation_noise_m * HashNormal(model.seed, kSaltDeadReckoning, k, 1 + a);
      }
      pose.T_world_body = out.back().T_world_body * biased;
    }
    out.push_back(pose);
  }
  return out;
}

}  // namespace rovermap::sim
