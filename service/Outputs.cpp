#include "service/Outputs.hpp"

#include <chrono>
#include <utility>
#include <vector>

#include "core/Stopwatch.hpp"
#include "io/FileUtil.hpp"
#include "io/GeoTiff.hpp"
#include "io/MapPreview.hpp"
#include "io/OctoMapIo.hpp"
#include "io/TerrainOutputs.hpp"
#include "io/Tum.hpp"
#include "terrain/TerrainLayers.hpp"

namespace rovermap::mapper {
namespace {

// terrain.tif and terrain.png from the DEM's layers (docs/terrain.md); what summary.json says of
// them. A DEM smaller than the footprint (the first frames) gets none, and says why. `cache`
// holds the last publication's layers (serve); without one every tile is computed.
nlohmann::json WriteTerrain(const std::filesystem::path& out_dir, const OutputState& state,
                            const std::vector<io::PreviewTrajectory>& drawn,
                            const std::function<void(const char*)>& done,
                            terrain::TerrainCache* cache) {
  nlohmann::json j;
  j["enabled"] = state.terrain.enabled;
  if (!state.terrain.enabled) return j;
  const auto start = std::chrono::steady_clock::now();
  terrain::TerrainCache own;
  if (cache == nullptr) cache = &own;
  try {
    const terrain::TerrainLayers& layers = cache->Update(io::GridViewOf(state.dem), state.terrain);
    j["compute_ms"] = core::MsSince(start);
    j["tiles"] = cache->tiles();
    j["tiles_computed"] = cache->tiles_computed();
    io::WriteTerrainGeoTiff(out_dir / "terrain.tif",
                            io::DemRasterFrame(state.dem, state.georeference), layers,
                            state.terrain);
    done("terrain.tif");
    io::WriteTerrainPreview(out_dir / "terrain.png", state.dem, layers, drawn);
    done("terrain.png");
    j["written"] = true;
    j["known_cells"] = layers.known;
    j["hazard_cells"] = layers.hazard;
    j["uncertain_cells"] = layers.uncertain_cells;
    j["benign_cells"] = layers.benign;
    j["footprint_cells"] = {layers.footprint_cols, layers.footprint_rows};
  } catch (const terrain::TerrainError& e) {
    // Not an error of the run: the map is not yet as large as the rover. No stale layers stay.
    std::error_code ignored;
    std::filesystem::remove(out_dir / "terrain.tif", ignored);
    std::filesystem::remove(out_dir / "terrain.png", ignored);
    j["written"] = false;
    j["reason"] = e.what();
  }
  j["time_ms"] = core::MsSince(start);
  return j;
}

}  // namespace

void MoveDemWithGraph(OutputState* state) {
  if (!state->move_dem_with_graph || !state->graph || !state->graph->solution.solved) return;
  const auto start = std::chrono::steady_clock::now();
  DemWarpStats stats;
  state->dem = WarpDemToGraph(state->dem, state->results, *state->graph, &stats);
  stats.ms = core::MsSince(start);
  state->move_dem_with_graph = false;
  state->dem_moved = stats;
  state->graph->maps = state->octomap_moved_with_graph ? GraphOutcome::Maps::kMapsMoved
                                                       : GraphOutcome::Maps::kDemMoved;
}

nlohmann::json WriteOutputs(const std::filesystem::path& out_dir, const Mapper& mapper, RunInfo run,
                            const eval::EvalOptions& eval_options,
                            const std::function<void(const std::string&)>& after_file) {
  return WriteOutputs(out_dir, OutputState(mapper), std::move(run), eval_options, after_file);
}

nlohmann::json WriteOutputs(const std::filesystem::path& out_dir, const OutputState& state,
                            RunInfo run, const eval::EvalOptions& eval_options,
                            const std::function<void(const std::string&)>& after_file,
                            terrain::TerrainCache* terrain_cache) {
  const auto done = [&](const char* name) {
    if (after_file) after_file(name);
  };
  const auto start = std::chrono::steady_clock::now();
  const std::vector<FrameResult>& results = state.results;
  // The pose graph's trajectory, when it was solved, is the result; the chain's is kept beside.
  const GraphOutcome* graph = state.graph ? &*state.graph : nullptr;
  const std::vector<Eigen::Isometry3d>* optimised =
      graph != nullptr && graph->solution.solved &&
              graph->solution.T_world_body.size() == results.size()
          ? &graph->solution.T_world_body
          : nullptr;

  std::vector<io::StampedPose> trajectory, chained, odometry;
  // dem.png: ground truth (when every frame has it) as a wide band, dead reckoning, registered
  // on top: where the registered path follows the truth, the truth shows on both sides of it.
  io::PreviewTrajectory truth_xy{"ground truth", {40, 200, 40}, {}, 8};
  io::PreviewTrajectory odometry_xy{"dead reckoning", {230, 60, 40}, {}};
  io::PreviewTrajectory registered_xy{"registered", {255, 255, 255}, {}};
  for (std::size_t k = 0; k < results.size(); ++k) {
    const FrameResult& r = results[k];
    const Eigen::Isometry3d& T = optimised ? (*optimised)[k] : r.step.T_world_body;
    trajectory.push_back({r.timestamp, T, 0, {}});
    chained.push_back({r.timestamp, r.step.T_world_body, 0, {}});
    odometry.push_back({r.timestamp, r.step.T_world_body_odom, 0, {}});
    registered_xy.points.push_back(T.translation());
    odometry_xy.points.push_back(r.step.T_world_body_odom.translation());
    if (r.T_world_body_truth) truth_xy.points.push_back(r.T_world_body_truth->translation());
  }
  std::vector<io::PreviewTrajectory> drawn;
  if (truth_xy.points.size() == results.size()) drawn.push_back(std::move(truth_xy));
  drawn.push_back(std::move(odometry_xy));
  drawn.push_back(std::move(registered_xy));
  io::WriteTum(out_dir / "trajectory.tum", trajectory);
  done("trajectory.tum");
  if (optimised) {
    io::WriteTum(out_dir / "trajectory_f2f.tum", chained);
    done("trajectory_f2f.tum");
  } else {
    std::error_code ignored;  // an earlier run's, into the same folder with --force
    std::filesystem::remove(out_dir / "trajectory_f2f.tum", ignored);
  }
  io::WriteTum(out_dir / "odometry.tum", odometry);
  done("odometry.tum");
  io::WriteFileAtomically(out_dir / "drift.csv", DriftCsv(results, graph));
  done("drift.csv");

  io::WriteDemGeoTiff(out_dir / "dem.tif", state.dem, state.georeference);
  done("dem.tif");
  // summary.json counts the DEM's cells and the OcTree's leaves in the same state.
  const std::optional<OctoMapWorker::TreeBytes>& tree = state.octomap.get();
  if (tree) {
    io::WriteFileAtomically(out_dir / "map.bt", tree->bt);
    done("map.bt");
    if (state.write_ot) io::WriteFileAtomically(out_dir / "map.ot", tree->ot);
  }
  io::WriteDemPreview(out_dir / "dem.png", state.dem, drawn);
  done("dem.png");
  nlohmann::json terrain = WriteTerrain(out_dir, state, drawn, done, terrain_cache);
  const std::optional<DriftMetrics> drift = EvaluateDrift(results, eval_options, optimised);
  const std::optional<DriftMetrics> chained_drift =
      optimised ? EvaluateDrift(results, eval_options) : std::nullopt;
  WriteDriftPlot(out_dir / "drift.png", results, drift, graph, chained_drift);
  done("drift.png");

  run.write_ms = core::MsSince(start);
  if (run.peak_rss_mb <= 0.0) run.peak_rss_mb = PeakRssMb();
  nlohmann::json summary = Summary(state, run, drift);
  summary["terrain"] = std::move(terrain);
  if (graph != nullptr) {
    summary["graph"] = GraphJson(*graph);
    if (state.dem_moved) {
      summary["graph"]["dem_moved"] = {{"cells_in", state.dem_moved->cells_in},
                                       {"cells_moved", state.dem_moved->cells_moved},
                                       {"cells_out", state.dem_moved->cells_out},
                                       {"median_shift_m", state.dem_moved->median_shift_m},
                                       {"max_shift_m", state.dem_moved->max_shift_m},
                                       {"ms", state.dem_moved->ms},
                                       {"refused", state.dem_moved->refused}};
    }
    if (tree && tree->moved) {
      const dem::OcTreeMoveStats& m = *tree->moved;
      summary["graph"]["octomap_moved"] = {{"leaves_in", m.leaves_in},
                                           {"leaves_moved", m.leaves_moved},
                                           {"leaves_out", m.leaves_out},
                                           {"dropped", m.dropped},
                                           {"median_shift_m", m.median_shift_m},
                                           {"max_shift_m", m.max_shift_m},
                                           {"ms", tree->move_ms}};
    }
    if (optimised && drift && chained_drift) {
      summary["metrics"]["frame_to_frame"] = eval::ToJson(chained_drift->registered);
    }
  }
  io::WriteFileAtomically(out_dir / "summary.json", summary.dump(2) + "\n");
  done("summary.json");
  return summary;
}

}  // namespace rovermap::mapper
