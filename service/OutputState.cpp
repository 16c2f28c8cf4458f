#include "service/OutputState.hpp"

#include <memory>
#include <utility>

namespace rovermap::mapper {

OutputState::OutputState(const Mapper& mapper, std::optional<GraphOutcome> graph_in, bool move_maps)
    : results(mapper.results()),
      georeference(mapper.georeference()),
      dem(io::RasteriseDem(mapper.elevation_map())),
      dem_cells_reached(mapper.elevation_map().CellCount()),
      dem_tiles(mapper.elevation_map().TileCount()) {
  write_ot = mapper.options().octomap.write_ot;
  graph = std::move(graph_in);
  std::shared_ptr<const OctoMapWorker::Corrections> corrections;
  if (move_maps && graph && graph->solution.solved) {
    move_dem_with_graph = true;  // on the publisher's thread (mapper/DemWarp)
    octomap_moved_with_graph = mapper.options().octomap.enabled;
    corrections =
        std::make_shared<const OctoMapWorker::Corrections>(GraphCorrections(results, *graph));
  }
  octomap = mapper.OctoMapBytes(write_ot, std::move(corrections));
  octomap_resolution_m = mapper.options().octomap.resolution_m;
  terrain = mapper.options().terrain;
  if (const PoseChain* chain = mapper.chain()) {
    distance_m = chain->path_length_m();
    final_correction = chain->back().cumulative_correction;
  }
  rig_calibration = mapper.rig_calibration();
  rig_calibration_stated = mapper.sequence().calibration_sigma.has_value();
  if (mapper.sensor().type == io::SensorType::kStereo)
    stereo_num_disparities = mapper.sensor().stereo.num_disparities;
}

}  // namespace rovermap::mapper
