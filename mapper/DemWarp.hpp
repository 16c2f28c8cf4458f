#pragma once
// The chain's DEM moved onto a solved pose graph's trajectory without fusing its frames again:
// what `serve` publishes (docs/serve.md), where a second pass over every frame at each
// publication is out of its time budget. Each published cell moves rigidly with the graph's
// correction of the frame that made it (T_graph · T_chain⁻¹ of DemLayers::frame), is splatted
// bilinearly into the grid, and trades the chain's pose share of its variance for the graph's.
// A deformation of the map, as the graph's correction varies slowly along the path; what it
// cannot do is pull apart two passes that the chain fused into one cell (replay's re-fusion can).

#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "io/DemLayers.hpp"
#include "mapper/GnssGraph.hpp"
#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

struct DemWarpStats {
  std::size_t cells_in = 0;     ///< published cells of the chain's DEM [count]
  std::size_t cells_moved = 0;  ///< of them, with a frame the graph solved [count]
  std::size_t cells_out = 0;    ///< published cells of the moved DEM [count]
  double max_shift_m = 0.0;     ///< largest horizontal move of a cell [m]
  double median_shift_m = 0.0;  ///< median horizontal move [m]
  double ms = 0.0;              ///< time it took, set by the caller that measures it [ms]
  /// Why the chain's DEM was kept unmoved although the graph was solved (else empty): the
  /// corrections would spread it over more than 4 times its raster (a graph gone wrong).
  std::string refused;
};

/// Per chain step index (FrameResult::step.index), the correction that moves the chain's pose
/// onto `graph`'s, T_graph · T_chain⁻¹ (world frame, on the left); nullopt for the frames the
/// graph did not solve, and for all when it is not solved. Never throws but std::bad_alloc.
std::vector<std::optional<Eigen::Isometry3d>> GraphCorrections(
    const std::vector<FrameResult>& results, const GraphOutcome& graph);

/// `dem` (the chain's, with its frame layer) moved with `graph`'s correction of each cell's
/// frame among `results`. A cell whose frame has no solved pose keeps the chain's place. An
/// output cell is published when the moved cells cover at least half of it (bilinear weights);
/// its height and σ are the covered cells' inverse-variance mean, its count their weighted
/// mean. Returns `dem` unchanged when the graph is not solved, `dem` has no frame layer, or
/// the moved raster would exceed 4 times `dem`'s and 10^7 cells (stats->refused says so).
/// Never throws on data.
io::DemLayers WarpDemToGraph(const io::DemLayers& dem, const std::vector<FrameResult>& results,
                             const GraphOutcome& graph, DemWarpStats* stats = nullptr);

}  // namespace rovermap::mapper
