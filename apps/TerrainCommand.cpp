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
  const io::DemRaster raster = io::ReadDemGeoTiff(args.dem);
  std::size_t heights = 0;
  for (float z : raster.elevation_m) heights += std::isnan(z) ? 0 : 1;
  if (heights == 0)
    throw io::IoError(raster.file + ": the DEM holds no height (every cell is nodata)");
  const terrain::GridView grid = io::GridViewOf(raster);
  terrain::TerrainLayers layers;
  try {
    layers = terrain::ComputeTerrain(grid, cfg.terrain);
  } catch (const terrain::TerrainError& e) {
    throw UsageError(raster.file + ": " + e.what());
  }
  std::filesystem::create_directories(out);
  io::RasterFrame frame;
  frame.width = raster.width;
  frame.height = raster.height;
  frame.geotransform = raster.geotransform;
  frame.wkt = raster.wkt;
  io::WriteTerrainGeoTiff(out / "terrain.tif", frame, layers, cfg.terrain);
  io::WriteTerrainPreview(out / "terrain.png", io::DemLayersOf(raster), layers, {});

  nlohmann::json summary;
  summary["dem"] = raster.file;
  summary["width"] = raster.width;
  summary["height"] = raster.height;
  summary["cell_m"] = {grid.cell_x_m, grid.cell_y_m};
  const std::string band2 =
      raster.band_descriptions.size() > 1 && !raster.band_descriptions[1].empty()
          ? " (" + raster.band_descriptions[1] + ")"
          : "";
  summary["sigma"] = layers.has_sigma ? "band 2" + band2 : "none: from the fits' residuals";
  summary["footprint_m"] = cfg.terrain.footprint_m;
  summary["footprint_cells"] = {layers.footprint_cols, layers.footprint_rows};
  summary["height_cells"] = heights;
  summary["known_cells"] = layers.known;
  summary["hazard_cells"] = layers.hazard;
  summary["uncertain_cells"] = layers.uncertain_cells;
  summary["benign_cells"] = layers.benign;
  summary["time_ms"] = core::MsSince(start);
  std::cout << summary.dump(2) << "\n";
  std::cerr << "terrain: layers on " << layers.known << " cells (the DEM has " << heights
            << " heights): " << layers.hazard << " hazard, " << layers.uncertain_cells
            << " uncertain, " << layers.benign << " benign; outputs in " << out.string()
            << ": terrain.tif terrain.png\n";
  return kExitOk;
}

}  // namespace rovermap::apps
