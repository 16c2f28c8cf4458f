#pragma once
// The replay / serve output set (docs/design.md §6), each file written atomically.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "eval/EvalOptions.hpp"
#include "mapper/Mapper.hpp"
#include "service/DriftReport.hpp"
#include "service/OutputState.hpp"
#include "terrain/TerrainCache.hpp"

namespace rovermap::mapper {

/// Writes dem.tif, map.bt (map.ot with octomap.write_ot; none when the OctoMap is off),
/// trajectory.tum, odometry.tum, drift.csv, dem.png, drift.png and, last, summary.json into
/// `out_dir` (an existing directory), each through a temporary file and a rename, so a reader
/// sees the previous version or the new one, never a partial file. `run.write_ms` is measured
/// here; `run.peak_rss_mb` is taken here when 0.
/// `after_file`, when given, is called with each file name once it is in place (the daemon's
/// fault injection). @return the summary written.
/// @throw io::IoError naming the file that could not be written.
nlohmann::json WriteOutputs(const std::filesystem::path& out_dir, const Mapper& mapper, RunInfo run,
                            const eval::EvalOptions& eval_options,
                            const std::function<void(const std::string&)>& after_file = {});

/// With `state->move_dem_with_graph` and a solved graph: the DEM moved onto the graph's poses
/// (mapper/DemWarp), `dem_moved` and `graph->maps` set, the flag cleared; else nothing. Never
/// throws on data.
void MoveDemWithGraph(OutputState* state);

/// The same from an OutputState taken before (the daemon writes it on a thread of its own,
/// after MoveDemWithGraph): the DEM is written as `state.dem` holds it.
/// Touches nothing but `state`, `out_dir` and `terrain_cache`: when given, the terrain layers
/// are computed anew only in the tiles whose heights changed since its last use (the daemon
/// keeps one for its publications).
nlohmann::json WriteOutputs(const std::filesystem::path& out_dir, const OutputState& state,
                            RunInfo run, const eval::EvalOptions& eval_options,
                            const std::function<void(const std::string&)>& after_file = {},
                            terrain::TerrainCache* terrain_cache = nullptr);

}  // namespace rovermap::mapper
