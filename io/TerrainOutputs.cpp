#include "io/TerrainOutputs.hpp"

#include <ogr_spatialref.h>

#include <algorithm>
#include <cctype>
#include <cmath>

#include "io/IoError.hpp"

namespace rovermap::io {

terrain::GridView GridViewOf(const DemLayers& layers) {
  terrain::GridView grid;
  grid.width = layers.width;
  grid.height = layers.height;
  grid.cell_x_m = grid.cell_y_m = layers.cell_size_m;
  grid.elevation_m = layers.elevation_m.data();
  grid.stddev_m =
      layers.stddev_m.size() == layers.elevation_m.size() ? layers.stddev_m.data() : nullptr;
  return grid;
}

bool RasterHasSigma(const DemRaster& raster) {
  if (raster.stddev_m.size() != raster.elevation_m.size() || raster.band_descriptions.size() < 2)
    return false;
  std::string name = raster.band_descriptions[1];
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* word : {"stddev", "sigma", "std", "uncertainty"}) {
    if (name.find(word) != std::string::npos) return true;
  }
  // dem.tif's layout without its descriptions (heights, σ, count): band 2 is σ when no value
  // of it is negative.
  if (!name.empty() || raster.band_descriptions.size() > 3) return false;
  return std::none_of(raster.stddev_m.begin(), raster.stddev_m.end(),
                      [](float s) { return s < 0.0f; });
}

terrain::GridView GridViewOf(const DemRaster& raster) {
  if (!raster.wkt.empty()) {
    OGRSpatialReference srs;
    if (srs.importFromWkt(raster.wkt.c_str()) == OGRERR_NONE && srs.IsGeographic()) {
      throw IoError(raster.file +
                    ": its CRS is geographic (degrees); the terrain layers need a projected CRS "
                    "in metres (reproject it first, e.g. gdalwarp -t_srs to a UTM zone)");
    }
  }
  terrain::GridView grid;
  grid.width = raster.width;
  grid.height = raster.height;
  grid.cell_x_m = std::abs(raster.geotransform[1]);
  grid.cell_y_m = std::abs(raster.geotransform[5]);
  grid.elevation_m = raster.elevation_m.data();
  grid.stddev_m = RasterHasSigma(raster) ? raster.stddev_m.data() : nullptr;
  return grid;
}

DemLayers DemLayersOf(const DemRaster& raster) {
  DemLayers layers;
  layers.min = {0, 0};
  layers.max = {raster.width - 1, raster.height - 1};
  layers.width = raster.width;
  layers.height = raster.height;
  layers.cell_size_m = std::abs(raster.geotransform[1]);
  layers.elevation_m = raster.elevation_m;
  layers.stddev_m = raster.stddev_m.size() == raster.elevation_m.size()
                        ? raster.stddev_m
                        : std::vector<float>(raster.elevation_m.size(), 0.0f);
  layers.count.assign(raster.elevation_m.size(), 0.0f);
  for (std::size_t i = 0; i < layers.elevation_m.size(); ++i) {
    if (!std::isnan(layers.elevation_m[i])) {
      layers.count[i] = 1.0f;
      ++layers.valid_cells;
    }
  }
  return layers;
}

GeoTiffInfo WriteTerrainGeoTiff(const std::filesystem::path& path, const RasterFrame& frame,
                                const terrain::TerrainLayers& layers,
                                const terrain::TerrainOptions& options,
                                const GeoTiffOptions& tiff) {
  RasterFrame with_limits = frame;
  const auto number = [](double v) {
    std::string s = std::to_string(v);
    s.erase(s.find_last_not_of('0') + 1);
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  };
  with_limits.metadata.push_back({"TERRAIN_FOOTPRINT_M", number(options.footprint_m)});
  with_limits.metadata.push_back(
      {"TERRAIN_FOOTPRINT_CELLS",
       std::to_string(layers.footprint_cols) + " x " + std::to_string(layers.footprint_rows)});
  with_limits.metadata.push_back({"TERRAIN_MAX_SLOPE_DEG", number(options.max_slope_deg)});
  with_limits.metadata.push_back({"TERRAIN_MAX_STEP_M", number(options.max_step_m)});
  with_limits.metadata.push_back({"TERRAIN_MAX_ROUGHNESS_M", number(options.max_roughness_m)});
  with_limits.metadata.push_back(
      {"TERRAIN_UNCERTAINTY_SIGMAS", number(options.uncertainty_sigmas)});
  with_limits.metadata.push_back({"TERRAIN_SIGMA", layers.has_sigma ? "from the DEM's sigma band"
                                                                    : "from the fits' residuals"});
  return WriteFloatGeoTiff(path, with_limits,
                           {{&layers.slope_deg, "slope_deg", "deg"},
                            {&layers.slope_sigma_deg, "slope_stddev_deg", "deg"},
                            {&layers.roughness_m, "roughness_m", "m"},
                            {&layers.step_m, "step_m", "m"},
                            {&layers.traversability, "traversability", ""},
                            {&layers.uncertain, "uncertain", ""}},
                           tiff);
}

}  // namespace rovermap::io
