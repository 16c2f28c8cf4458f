#pragma once
// What the outputs of docs/design.md §6 are made of, copied out of a Mapper: the results, the DEM's
// published layers, the OctoMap's serialised bytes and the few figures summary.json reports.
// Taking it costs a copy of the results and a pass over the DEM's tiles; the OcTree is
// serialised on the OctoMap's own thread. Writing it (encoding the GeoTIFF and the PNGs, most
// of a publication) can then go on beside the mapper.

#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "io/DemLayers.hpp"
#include "io/Georeference.hpp"
#include "mapper/DemWarp.hpp"
#include "mapper/GnssGraph.hpp"
#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

struct OutputState {
  /// Does not wait for the OctoMap's thread (Mapper::OctoMapBytes).
  /// @throw io::IoError if the DEM's raster would be too large (io::RasteriseDem).
  explicit OutputState(const Mapper& mapper) : OutputState(mapper, std::nullopt, false) {}
  /// With `graph` (kept as `graph`). With `move_maps` and a solved graph, the maps follow it
  /// without being fused again (serve): the DEM is moved by the writer (move_dem_with_graph)
  /// and the OctoMap's bytes are its tree moved with each frame's correction
  /// (OctoMapWorker::SerialiseWhenQueuedIn, dem::BatchOcTree::MovedCopy).
  OutputState(const Mapper& mapper, std::optional<GraphOutcome> graph, bool move_maps);

  std::vector<FrameResult> results;
  io::Georeference georeference;
  io::DemLayers dem;                  ///< the published cells (dem.tif, dem.png)
  std::size_t dem_cells_reached = 0;  ///< cells holding a point, published or not [count]
  std::size_t dem_tiles = 0;          ///< tiles allocated [count]
  /// map.bt's bytes (map.ot's too with octomap.write_ot), made on the OctoMap's thread once
  /// the frames taken are in: get() waits for them; nullopt when the OctoMap is off.
  std::shared_future<std::optional<OctoMapWorker::TreeBytes>> octomap;
  bool write_ot = false;
  double octomap_resolution_m = 0.0;
  double distance_m = 0.0;  ///< path length of the registered chain
  Eigen::Isometry3d final_correction = Eigen::Isometry3d::Identity();
  std::optional<int> stereo_num_disparities;  ///< stereo sequences only
  /// The rig's calibration σ the DEM's σ carries (Mapper::rig_calibration), and whether the
  /// recording stated it (sensor.calibration_sigma) or the mapper assumed it (mapper.rig_*).
  io::RigCalibrationSigma rig_calibration;
  bool rig_calibration_stated = false;
  terrain::TerrainOptions terrain;            ///< terrain.tif and terrain.png
  /// The pose graph's outcome (replay with GNSS fixes, docs/graph.md); set by the caller. When
  /// solved, trajectory.tum, the metrics and the previews are its poses, and the chained ones
  /// go to trajectory_f2f.tum.
  std::optional<GraphOutcome> graph;
  /// With a solved graph, write the DEM (and terrain.tif) moved onto its poses
  /// (mapper/DemWarp) rather than as fused: serve, which does not fuse its frames again.
  bool move_dem_with_graph = false;
  /// The OctoMap's bytes are its tree moved onto the graph (`octomap` asked with corrections).
  bool octomap_moved_with_graph = false;
  /// Set by WriteOutputs on the state it wrote when it moved the DEM (summary.json graph.maps).
  std::optional<DemWarpStats> dem_moved;
};

}  // namespace rovermap::mapper
