#include "service/OutputState.hpp"

namespace rovermap::mapper {

OutputState::OutputState(const Mapper& mapper)
    : results(mapper.results()),
      georeference(mapper.georeference()),
      dem(io::RasteriseDem(mapper.elevation_map())),
      dem_cells_reached(mapper.elevation_map().CellCount()),
      dem_tiles(mapper.elevation_map().TileCount()) {
  write_ot = mapper.options().octomap.write_ot;
  octomap = mapper.OctoMapBytes(write_ot);
  octomap_resolution_m = mapper.options().octomap.resolution_m;
  terrain = mapper.options().terrain;
  if (const PoseChain* chain = mapper.chain()) {
    distance_m = chain->path_length_m();
    final_correction = chain->back().cumulative_correction;
  }
  if (mapper.sensor().type == io::SensorType::kStereo)
    stereo_num_disparities = mapper.sensor().stereo.num_disparities;
}

}  // namespace rovermap::mapper
