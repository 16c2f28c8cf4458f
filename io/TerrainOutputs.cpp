#include "io/TerrainOutputs.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iterator>
#include <limits>

#include "io/IoError.hpp"
#include "io/MapPreview.hpp"
#include "io/TiledGeoTiff.hpp"

namespace rovermap::io {

terrain::GridView GridViewOf(const DemLayers& layers) {
  terrain::GridView grid;
  grid.width = layers.width;
  grid.height = layers.height;
  grid.cell_x_m = grid.cell_y_m = layers.cell_size_m;
  grid.elevation_m = layers.elevation_m.data();
  grid.stddev_m =
      layers.stddev_m.size() == layers.elevation_m.size() ? layers.stddev_m.data() : nullptr;
  // Pixel (col, row) is cell (min.x + col, max.y − row): rows count south.
  grid.origin_col = layers.min.x;
  grid.origin_row = -layers.max.y;
  return grid;
}

namespace {

// Whether a band's description names a standard deviation.
bool DescribesSigma(std::string name) {
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* word : {"stddev", "sigma", "std", "uncertainty"}) {
    if (name.find(word) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

bool RasterHasSigma(const DemRaster& raster) {
  if (raster.stddev_m.size() != raster.elevation_m.size() || raster.band_descriptions.size() < 2)
    return false;
  const std::string& name = raster.band_descriptions[1];
  if (DescribesSigma(name)) return true;
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

namespace {

// terrain.tif's bands, in order: name, unit, the layer.
struct TerrainBand {
  const char* name;
  const char* unit;
  std::vector<float> terrain::TerrainLayers::*layer;
};
constexpr TerrainBand kTerrainBands[] = {
    {"slope_deg", "deg", &terrain::TerrainLayers::slope_deg},
    {"slope_stddev_deg", "deg", &terrain::TerrainLayers::slope_sigma_deg},
    {"roughness_m", "m", &terrain::TerrainLayers::roughness_m},
    {"step_m", "m", &terrain::TerrainLayers::step_m},
    {"traversability", "", &terrain::TerrainLayers::traversability},
    {"uncertain", "", &terrain::TerrainLayers::uncertain}};

// The footprint and the limits, as terrain.tif's metadata.
std::vector<std::pair<std::string, std::string>> TerrainMetadata(
    const terrain::TerrainLayers& layers, const terrain::TerrainOptions& options) {
  const auto number = [](double v) {
    std::string s = std::to_string(v);
    s.erase(s.find_last_not_of('0') + 1);
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  };
  return {{"TERRAIN_FOOTPRINT_M", number(options.footprint_m)},
          {"TERRAIN_FOOTPRINT_CELLS",
           std::to_string(layers.footprint_cols) + " x " + std::to_string(layers.footprint_rows)},
          {"TERRAIN_MAX_SLOPE_DEG", number(options.max_slope_deg)},
          {"TERRAIN_MAX_STEP_M", number(options.max_step_m)},
          {"TERRAIN_MAX_ROUGHNESS_M", number(options.max_roughness_m)},
          {"TERRAIN_UNCERTAINTY_SIGMAS", number(options.uncertainty_sigmas)},
          {"TERRAIN_SIGMA",
           layers.has_sigma ? "from the DEM's sigma band" : "from the fits' residuals"}};
}

}  // namespace

GeoTiffInfo WriteTerrainGeoTiff(const std::filesystem::path& path, const RasterFrame& frame,
                                const terrain::TerrainLayers& layers,
                                const terrain::TerrainOptions& options,
                                const GeoTiffOptions& tiff) {
  RasterFrame with_limits = frame;
  for (auto& item : TerrainMetadata(layers, options)) with_limits.metadata.push_back(item);
  std::vector<RasterBand> bands;
  for (const TerrainBand& band : kTerrainBands)
    bands.push_back({&(layers.*band.layer), band.name, band.unit});
  return WriteFloatGeoTiff(path, with_limits, bands, tiff);
}

namespace {

// A band's nodata value (when it has one other than NaN) read as NaN.
void NoDataToNaN(GDALRasterBand& band, std::vector<float>* values) {
  int has_nodata = 0;
  const double nodata = band.GetNoDataValue(&has_nodata);
  if (has_nodata == 0 || std::isnan(nodata)) return;
  for (float& v : *values) {
    if (v == static_cast<float>(nodata)) v = std::numeric_limits<float>::quiet_NaN();
  }
}

// One band of `path` read whole but decimated (GDAL's nearest) to width × height.
std::vector<float> ReadDecimated(const std::filesystem::path& path, int band, int width,
                                 int height) {
  GdalDatasetPtr ds(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) throw IoError(path.string() + ": cannot open as a raster" + QuietGdal::Last());
  std::vector<float> out(static_cast<std::size_t>(width) * height);
  GDALRasterBand* b = ds->GetRasterBand(band);
  if (b->RasterIO(GF_Read, 0, 0, ds->GetRasterXSize(), ds->GetRasterYSize(), out.data(), width,
                  height, GDT_Float32, 0, 0, nullptr) != CE_None) {
    throw IoError(path.string() + ": cannot read band " + std::to_string(band) + QuietGdal::Last());
  }
  NoDataToNaN(*b, &out);
  return out;
}

// terrain.png from the DEM and terrain.tif on disk, read decimated to the preview's size (a
// pixel per cell up to MapPreviewOptions::max_map_px), so memory stays that of the picture.
void WritePreviewFromFiles(const std::filesystem::path& dem, const std::filesystem::path& tif,
                           const std::filesystem::path& png, const TiledTerrain& t) {
  const int longest = std::max(t.width, t.height);
  const int max_px = MapPreviewOptions{}.max_map_px;
  const int factor = std::max(1, (longest + max_px - 1) / max_px);
  const int w = (t.width + factor - 1) / factor, h = (t.height + factor - 1) / factor;
  DemLayers layers;
  layers.min = {0, 0};
  layers.max = {w - 1, h - 1};
  layers.width = w;
  layers.height = h;
  layers.cell_size_m = t.cell_x_m * factor;
  layers.elevation_m = ReadDecimated(dem, 1, w, h);
  layers.stddev_m.assign(layers.elevation_m.size(), 0.0f);
  layers.count.assign(layers.elevation_m.size(), 0.0f);
  for (std::size_t i = 0; i < layers.elevation_m.size(); ++i) {
    if (!std::isnan(layers.elevation_m[i])) {
      layers.count[i] = 1.0f;
      ++layers.valid_cells;
    }
  }
  terrain::TerrainLayers terrain;
  terrain.width = w;
  terrain.height = h;
  terrain.traversability = ReadDecimated(tif, 5, w, h);
  terrain.uncertain = ReadDecimated(tif, 6, w, h);
  WriteTerrainPreview(png, layers, terrain, {});
}

}  // namespace

TiledTerrain WriteTerrainTiled(const std::filesystem::path& dem, const std::filesystem::path& tif,
                               const std::filesystem::path& png,
                               const terrain::TerrainOptions& options) {
  RegisterGdal();
  BoundGdalCache();
  QuietGdal quiet;
  GdalDatasetPtr ds(GDALDataset::Open(dem.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  const std::string file = dem.string();
  if (!ds) throw IoError(file + ": cannot open as a raster" + QuietGdal::Last());
  if (ds->GetRasterCount() < 1) throw IoError(file + ": has no raster band");
  std::array<double, 6> g{};
  if (ds->GetGeoTransform(g.data()) != CE_None) throw IoError(file + ": has no geotransform");
  if (g[2] != 0.0 || g[4] != 0.0 || g[1] == 0.0 || g[5] == 0.0)
    throw IoError(file + ": rotated or degenerate grids are not supported");
  const OGRSpatialReference* srs = ds->GetSpatialRef();
  if (srs != nullptr && srs->IsGeographic()) {
    throw IoError(file +
                  ": its CRS is geographic (degrees); the terrain layers need a projected CRS "
                  "in metres (reproject it first, e.g. gdalwarp -t_srs to a UTM zone)");
  }
  TiledTerrain result;
  result.width = ds->GetRasterXSize();
  result.height = ds->GetRasterYSize();
  result.cell_x_m = std::abs(g[1]);
  result.cell_y_m = std::abs(g[5]);
  // Band 2 is the σ as RasterHasSigma decides, without reading the band whole: its minimum
  // from GDAL when it has no description.
  GDALRasterBand* sigma_band = nullptr;
  if (ds->GetRasterCount() >= 2) {
    GDALRasterBand* band = ds->GetRasterBand(2);
    const std::string name = band->GetDescription();
    double min_max[2] = {0.0, 0.0};
    if (DescribesSigma(name) ||
        (name.empty() && ds->GetRasterCount() <= 3 &&
         band->ComputeRasterMinMax(FALSE, min_max) == CE_None && min_max[0] >= 0.0)) {
      sigma_band = band;
      result.sigma_band = name;
    }
  }
  terrain::GridShape shape{result.width, result.height, result.cell_x_m, result.cell_y_m,
                           sigma_band != nullptr};

  TemporaryFile staging(tif, "staging");
  GdalDatasetPtr staged;
  {
    std::vector<StagedBand> bands;
    for (const TerrainBand& band : kTerrainBands) bands.push_back({band.name, band.unit});
    const OGRSpatialReference none;
    staged = CreateStaging(staging.path(), tif, result.width, result.height, g,
                           srs != nullptr ? *srs : none, bands);
  }
  int counted_rows = 0;
  const auto read = [&](int row0, int rows, std::vector<float>* z, std::vector<float>* s) {
    const std::size_t cells = static_cast<std::size_t>(result.width) * rows;
    z->resize(cells);
    if (ds->GetRasterBand(1)->RasterIO(GF_Read, 0, row0, result.width, rows, z->data(),
                                       result.width, rows, GDT_Float32, 0, 0, nullptr) != CE_None) {
      throw IoError(file + ": cannot read rows " + std::to_string(row0) + QuietGdal::Last());
    }
    NoDataToNaN(*ds->GetRasterBand(1), z);  // the DEM's own nodata value: no height
    if (s != nullptr) {
      s->resize(cells);
      if (sigma_band->RasterIO(GF_Read, 0, row0, result.width, rows, s->data(), result.width, rows,
                               GDT_Float32, 0, 0, nullptr) != CE_None) {
        throw IoError(file + ": cannot read rows " + std::to_string(row0) + QuietGdal::Last());
      }
    }
    // Heights counted once: the halo rows come again with the next tile row.
    for (int r = std::max(row0, counted_rows); r < row0 + rows; ++r) {
      const float* row = z->data() + static_cast<std::size_t>(r - row0) * result.width;
      for (int c = 0; c < result.width; ++c) result.height_cells += std::isnan(row[c]) ? 0 : 1;
    }
    counted_rows = std::max(counted_rows, row0 + rows);
  };
  const auto write = [&](int row0, const terrain::TerrainLayers& rows) {
    for (std::size_t b = 0; b < std::size(kTerrainBands); ++b) {
      WriteWindow(staged.get(), tif, static_cast<int>(b) + 1, 0, row0, rows.width, rows.height,
                  (rows.*kTerrainBands[b].layer).data());
    }
  };
  result.counts = terrain::ComputeTerrainByRows(shape, options, read, write);
  if (result.height_cells == 0)
    throw IoError(file + ": the DEM holds no height (every cell is nodata)");
  for (const auto& [key, value] : TerrainMetadata(result.counts, options))
    staged->SetMetadataItem(key.c_str(), value.c_str());
  CloseStaging(std::move(staged), tif);
  TemporaryFile cog(tif, "tmp");
  TranslateToCog(staging.path(), cog.path(), tif);
  if (!png.empty()) WritePreviewFromFiles(dem, cog.path(), png, result);
  cog.CommitTo(tif);
  return result;
}

}  // namespace rovermap::io
