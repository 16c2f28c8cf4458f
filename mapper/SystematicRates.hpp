#pragma once
// How much of a registered step's error repeats from step to step (PoseChain's SystematicError,
// the pose graph's relative factors): the rig's calibration turns and scales every step alike.

#include <algorithm>
#include <cmath>

#include "io/RigCalibration.hpp"
#include "io/SensorType.hpp"
#include "mapper/MapperOptions.hpp"

namespace rovermap::mapper {

/// σ of the repeating part per metre of a step, on each axis.
struct SystematicRates {
  double rotation_rad_per_m = 0.0;  ///< [rad/m]
  double translation_ratio = 0.0;   ///< [ratio of the step's length]
};

/// The rig's calibration (`rig`: its mounting's rotation ω turns every step by ω, across it;
/// its scale stretches it, along it) makes the step's translation err by max(σω [rad], σs) of
/// its length on every axis. Stereo frames err by at least mapper.stereo_systematic_* as well
/// (fitted on KITTI: the rig and the matcher's own sub-pixel bias, which no declared rig
/// removes; docs/replay.md, "Known limits"). Never throws.
inline SystematicRates SystematicRatesOf(io::SensorType sensor, const io::RigCalibrationSigma& rig,
                                         const MapperOptions& o) {
  SystematicRates rates;
  rates.translation_ratio = std::max(rig.rotation_deg * M_PI / 180.0, rig.scale);
  if (sensor == io::SensorType::kStereo) {
    rates.translation_ratio = std::max(rates.translation_ratio, o.stereo_systematic_ratio);
    rates.rotation_rad_per_m = o.stereo_systematic_deg_per_m * M_PI / 180.0;
  }
  return rates;
}

}  // namespace rovermap::mapper
