// `rovermap terrain DEM.tif --out DIR`: the layers a planner reads (slope, roughness, step,
// traversability; docs/terrain.md) for any north-up DEM GeoTIFF in metres.
#include <chrono>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/Commands.hpp"
#include "core/Stopwatch.hpp"
#include "io/GeoTiff.hpp"
#include "io/IoError.hpp"
#include "io/MapPreview.hpp"
#include "io/TerrainOutputs.hpp"
#include "terrain/TerrainLayers.hpp"

namespace rovermap::apps {

CLI::App* AddTerrainCommand(CLI::App* app, TerrainArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "terrain",
      "Slope, roughness, step height and traversability over the rover's footprint, from a DEM "
      "GeoTIFF (terrain.tif, terrain.png)");
  cmd->add_option("dem", args->dem,
                  "DEM GeoTIFF: dem.tif, a mosaic, or any north-up raster in metres (band 1 "
                  "heights; band 2 their sigma when its description says so)")
      ->required();
  cmd->add_option("--out", args->out, "Output directory (created)")->required();
  cmd->add_flag("--force", args->force, "Write into a non-empty DIR (its outputs are replaced)");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Writes terrain.tif (slope_deg, slope_stddev_deg, roughness_m, step_m, traversability,\n"
      "uncertain; the DEM's grid and CRS) and terrain.png into DIR, each atomically; prints a\n"
      "summary on stdout. Options: the terrain. keys (footprint_m, max_slope_deg, max_step_m,\n"
      "max_roughness_m, ...). Exit status: 0 done, 1 unreadable or unusable DEM (no heights,\n"
      "rotated grid, geographic CRS) or cannot write, 2 usage or config error (a footprint\n"
      "smaller than two cells or larger than the DEM).\n");
  return cmd;
}

int RunTerrain(const TerrainArgs& args) {
  const auto start = core::Clock::now();
  const config::Config cfg = LoadConfigArgs(args.config);
  const std::filesystem::path out(args.out);
  CheckOutputDirectory(out, args.force, "overwrite terrain.tif and terrain.png");
  std::filesystem::create_directories(out);
  // A row of tiles at a time: a mosaic of any size in bounded memory (docs/terrain.md).
  io::TiledTerrain t;
  try {
    t = io::WriteTerrainTiled(args.dem, out / "terrain.tif", out / "terrain.png", cfg.terrain);
  } catch (const terrain::TerrainError& e) {
    throw UsageError(args.dem + ": " + e.what());
  }
  const terrain::TerrainLayers& layers = t.counts;

  nlohmann::json summary;
  summary["dem"] = args.dem;
  summary["width"] = t.width;
  summary["height"] = t.height;
  summary["cell_m"] = {t.cell_x_m, t.cell_y_m};
  const std::string band2 = t.sigma_band.empty() ? "" : " (" + t.sigma_band + ")";
  summary["sigma"] = layers.has_sigma ? "band 2" + band2 : "none: from the fits' residuals";
  summary["footprint_m"] = cfg.terrain.footprint_m;
  summary["footprint_cells"] = {layers.footprint_cols, layers.footprint_rows};
  summary["height_cells"] = t.height_cells;
  summary["known_cells"] = layers.known;
  summary["hazard_cells"] = layers.hazard;
  summary["uncertain_cells"] = layers.uncertain_cells;
  summary["benign_cells"] = layers.benign;
  summary["time_ms"] = core::MsSince(start);
  std::cout << summary.dump(2) << "\n";
  std::cerr << "terrain: layers on " << layers.known << " cells (the DEM has " << t.height_cells
            << " heights): " << layers.hazard << " hazard, " << layers.uncertain_cells
            << " uncertain, " << layers.benign << " benign; outputs in " << out.string()
            << ": terrain.tif terrain.png\n";
  return kExitOk;
}

nlohmann::json WriteMosaicTerrain(const std::filesystem::path& mosaic,
                                  const terrain::TerrainOptions& options) {
  nlohmann::json j = {{"enabled", options.enabled}};
  if (!options.enabled) return j;
  const std::string stem = mosaic.stem().string();
  const std::filesystem::path tif = mosaic.parent_path() / (stem + "_terrain.tif");
  const std::filesystem::path png = mosaic.parent_path() / (stem + "_terrain.png");
  try {
    const io::TiledTerrain t = io::WriteTerrainTiled(mosaic, tif, png, options);
    j["written"] = true;
    j["file"] = tif.filename().string();
    j["preview"] = png.filename().string();
    j["known_cells"] = t.counts.known;
    j["hazard_cells"] = t.counts.hazard;
    j["uncertain_cells"] = t.counts.uncertain_cells;
    j["benign_cells"] = t.counts.benign;
    j["footprint_cells"] = {t.counts.footprint_cols, t.counts.footprint_rows};
  } catch (const terrain::TerrainError& e) {
    // Not an error of the mosaic: it is smaller than the rover. No stale layers stay.
    std::error_code ignored;
    std::filesystem::remove(tif, ignored);
    std::filesystem::remove(png, ignored);
    j["written"] = false;
    j["reason"] = e.what();
  }
  return j;
}

}  // namespace rovermap::apps
