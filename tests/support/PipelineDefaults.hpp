#pragma once
// The pipeline's options as `rovermap replay` gets them without a config file.

#include "config/Config.hpp"
#include "mapper/Mapper.hpp"

namespace rovermap::testing {

inline mapper::PipelineOptions PipelineDefaults() {
  const config::Config c;
  return {c.mapper, c.registration, c.stereo, c.dem, c.octomap, c.terrain};
}

/// The same without the OctoMap, for tests that compare trajectories or the DEM only.
inline mapper::PipelineOptions PipelineDefaultsWithoutOctoMap() {
  mapper::PipelineOptions options = PipelineDefaults();
  options.octomap.enabled = false;
  return options;
}

}  // namespace rovermap::testing
