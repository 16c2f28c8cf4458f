#include "io/GeoTiff.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "io/DemLayers.hpp"
#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/TiledGeoTiff.hpp"

namespace rovermap::io {
namespace {

using DatasetPtr = GdalDatasetPtr;

// Most memory ReadDemGeoTiff may need for one raster: a 5 cm DEM of about 470 m x 470 m with its
// three bands.
constexpr std::size_t kMaxReadBytes = std::size_t{1} << 30;

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& what) {
  throw IoError(path.string() + ": " + what + QuietGdal::Last());
}

// A name in GDAL's in-memory file system, unique within the process.
std::string MemoryFileName() {
  static std::atomic<unsigned> counter{0};
  return "/vsimem/rovermap_dem_" + std::to_string(counter.fetch_add(1)) + ".tif";
}

}  // namespace

GeoTiffInfo WriteDemGeoTiff(const std::filesystem::path& path, const dem::ElevationMap& map,
                            const Georeference& georef, const GeoTiffOptions& options) {
  DemLayers layers;
  try {
    layers = RasteriseDem(map);
  } catch (const IoError& e) {
    throw IoError(path.string() + ": " + e.what());
  }
  return WriteDemGeoTiff(path, layers, georef, options);
}

static std::array<double, 6> DemGeotransform(const DemLayers& layers, const Georeference& georef) {
  if (std::abs(layers.grid_rotation_rad - georef.convergence_rad()) > 1e-9) {
    throw std::invalid_argument(
        "WriteDemGeoTiff: the map's grid_rotation_rad must equal the georeference's "
        "convergence_rad() so that the raster is north-up without resampling");
  }
  const double s = layers.cell_size_m;
  const double k = georef.scale_factor();
  const Eigen::Vector2d top_left = georef.GridToProjected(
      {static_cast<double>(layers.min.x) * s, static_cast<double>(layers.max.y + 1) * s});
  return {top_left.x(), k * s, 0.0, top_left.y(), 0.0, -k * s};
}

RasterFrame DemRasterFrame(const DemLayers& layers, const Georeference& georef) {
  RasterFrame frame;
  frame.width = layers.width;
  frame.height = layers.height;
  frame.geotransform = DemGeotransform(layers, georef);
  frame.wkt = georef.wkt();
  frame.metadata = {
      {"ELEVATION_DATUM", "height above the origin altitude " +
                              std::to_string(georef.origin().altitude_m) + " m (world z, ENU up)"},
      {"ORIGIN_LAT_LON", std::to_string(georef.origin().latitude_deg) + " " +
                             std::to_string(georef.origin().longitude_deg)}};
  return frame;
}

GeoTiffInfo WriteDemGeoTiff(const std::filesystem::path& path, const DemLayers& layers,
                            const Georeference& georef, const GeoTiffOptions& options) {
  const RasterFrame frame = DemRasterFrame(layers, georef);
  GeoTiffInfo info = WriteFloatGeoTiff(path, frame,
                                       {{&layers.elevation_m, "elevation", "m"},
                                        {&layers.stddev_m, "elevation_stddev", "m"},
                                        {&layers.count, "count", ""}},
                                       options);
  info.valid_cells = layers.valid_cells;
  return info;
}

GeoTiffInfo WriteFloatGeoTiff(const std::filesystem::path& path, const RasterFrame& frame,
                              const std::vector<RasterBand>& bands, const GeoTiffOptions& options) {
  if (path.empty() || !path.has_filename()) throw IoError(path.string() + ": not a file path");
  const std::size_t pixels =
      static_cast<std::size_t>(frame.width) * static_cast<std::size_t>(frame.height);
  if (bands.empty()) throw std::invalid_argument("WriteFloatGeoTiff: no band");
  for (const RasterBand& band : bands) {
    if (band.data == nullptr || band.data->size() != pixels)
      throw std::invalid_argument("WriteFloatGeoTiff: band " + band.name + " of the wrong size");
  }
  RegisterGdal();
  QuietGdal quiet;
  GeoTiffInfo info;
  info.width = frame.width;
  info.height = frame.height;
  info.geotransform = frame.geotransform;

  GDALDriver* mem_driver = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* cog_driver = GetGDALDriverManager()->GetDriverByName("COG");
  if (mem_driver == nullptr || cog_driver == nullptr)
    Fail(path, "GDAL lacks the MEM or COG driver");
  DatasetPtr mem(mem_driver->Create("", info.width, info.height, static_cast<int>(bands.size()),
                                    GDT_Float32, nullptr));
  if (!mem) Fail(path, "cannot create the in-memory raster");
  mem->SetGeoTransform(info.geotransform.data());
  if (!frame.wkt.empty() && mem->SetProjection(frame.wkt.c_str()) != CE_None)
    Fail(path, "cannot set the CRS");
  for (const auto& [key, value] : frame.metadata) mem->SetMetadataItem(key.c_str(), value.c_str());
  for (std::size_t b = 0; b < bands.size(); ++b) {
    GDALRasterBand* band = mem->GetRasterBand(static_cast<int>(b) + 1);
    band->SetDescription(bands[b].name.c_str());
    if (!bands[b].unit.empty()) band->SetUnitType(bands[b].unit.c_str());
    band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
    // GF_Write only reads the buffer; RasterIO takes it as void* for both directions.
    void* data = const_cast<float*>(bands[b].data->data());
    if (band->RasterIO(GF_Write, 0, 0, info.width, info.height, data, info.width, info.height,
                       GDT_Float32, 0, 0, nullptr) != CE_None) {
      Fail(path, "cannot fill band " + std::to_string(b + 1));
    }
  }
  for (float v : *bands.front().data) info.valid_cells += std::isnan(v) ? 0 : 1;

  char** create = nullptr;
  create = CSLSetNameValue(create, "COMPRESS", "DEFLATE");
  create = CSLSetNameValue(create, "PREDICTOR", "FLOATING_POINT");
  create = CSLSetNameValue(create, "LEVEL", std::to_string(options.deflate_level).c_str());
  create = CSLSetNameValue(create, "BLOCKSIZE", std::to_string(options.block_size).c_str());
  create = CSLSetNameValue(create, "OVERVIEWS", options.overviews ? "AUTO" : "NONE");
  create = CSLSetNameValue(create, "RESAMPLING", "AVERAGE");
  create =
      CSLSetNameValue(create, "NUM_THREADS",
                      options.threads > 0 ? std::to_string(options.threads).c_str() : "ALL_CPUS");
  // GDAL writes the GeoTIFF into memory, and WriteFileAtomically puts it on disk: GDAL 3.6 does
  // not report a short write to a file (a full disk or a file-size limit left a truncated
  // dem.tif in place, measured), whereas WriteFileAtomically checks every write, flushes, and
  // removes its temporary on failure.
  const std::string memory_file = MemoryFileName();
  CPLErrorReset();
  GDALDataset* out =
      cog_driver->CreateCopy(memory_file.c_str(), mem.get(), FALSE, create, nullptr, nullptr);
  CSLDestroy(create);
  bool written = out != nullptr && CPLGetLastErrorType() < CE_Failure;
  const std::string copy_error = QuietGdal::Last();
  if (out != nullptr) GDALClose(GDALDataset::ToHandle(out));  // void in GDAL 3.6: check the state
  written = written && CPLGetLastErrorType() < CE_Failure;
  vsi_l_offset size = 0;
  GByte* bytes = VSIGetMemFileBuffer(memory_file.c_str(), &size, /*bUnlinkAndSeize=*/TRUE);
  const std::unique_ptr<GByte, decltype(&VSIFree)> owned(bytes, &VSIFree);
  if (!written || bytes == nullptr) {
    VSIUnlink(memory_file.c_str());
    throw IoError(path.string() + ": GDAL cannot write the GeoTIFF" +
                  (copy_error.empty() ? QuietGdal::Last() : copy_error));
  }
  WriteFileAtomically(
      path, std::string_view(reinterpret_cast<const char*>(bytes), static_cast<std::size_t>(size)));
  return info;
}

float DemRaster::ElevationAt(int col, int row) const {
  if (col < 0 || row < 0 || col >= width || row >= height) {
    return std::numeric_limits<float>::quiet_NaN();
  }
  return elevation_m[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                     static_cast<std::size_t>(col)];
}

DemRaster ReadDemGeoTiff(const std::filesystem::path& path) {
  RegisterGdal();
  QuietGdal quiet;
  DatasetPtr ds(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) Fail(path, "cannot open as a raster");
  DemRaster raster;
  raster.file = path.string();
  raster.width = ds->GetRasterXSize();
  raster.height = ds->GetRasterYSize();
  if (ds->GetGeoTransform(raster.geotransform.data()) != CE_None) {
    Fail(path, "has no geotransform");
  }
  const auto& g = raster.geotransform;
  if (g[2] != 0.0 || g[4] != 0.0 || g[1] == 0.0 || g[5] == 0.0) {
    Fail(path, "rotated or degenerate grids are not supported");
  }
  if (const char* wkt = ds->GetProjectionRef(); wkt != nullptr) raster.wkt = wkt;
  if (const char* datum = ds->GetMetadataItem("ELEVATION_DATUM")) raster.elevation_datum = datum;
  if (const OGRSpatialReference* srs = ds->GetSpatialRef(); srs != nullptr) {
    const char* code = srs->GetAuthorityCode(nullptr);
    const char* name = srs->GetAuthorityName(nullptr);
    if (code != nullptr && name != nullptr && std::string(name) == "EPSG") {
      raster.epsg = std::atoi(code);
    }
  }
  const auto pixels =
      static_cast<std::size_t>(raster.width) * static_cast<std::size_t>(raster.height);
  std::vector<float>* targets[3] = {&raster.elevation_m, &raster.stddev_m, &raster.count};
  const int bands = std::min(3, ds->GetRasterCount());
  if (bands < 1) Fail(path, "has no raster band");
  // A few hundred bytes of header can claim any size (sparse or repeated tiles, thousands of
  // bands): check before reading. The cost is our Float32 copies plus one block as GDAL decodes
  // it, every band at once for pixel-interleaved data (GDAL's block cache comes on top).
  double stored_pixel_bytes = 0.0;
  for (int b = 1; b <= ds->GetRasterCount(); ++b) {
    stored_pixel_bytes += GDALGetDataTypeSizeBytes(ds->GetRasterBand(b)->GetRasterDataType());
  }
  int block_x = 0;
  int block_y = 0;
  ds->GetRasterBand(1)->GetBlockSize(&block_x, &block_y);
  const double bytes = static_cast<double>(pixels) * bands * sizeof(float) +
                       static_cast<double>(block_x) * block_y * stored_pixel_bytes;
  if (bytes > static_cast<double>(kMaxReadBytes)) {
    Fail(path, std::to_string(raster.width) + " x " + std::to_string(raster.height) + " pixels, " +
                   std::to_string(ds->GetRasterCount()) + " band(s): reading needs " +
                   std::to_string(std::llround(bytes / (1 << 20))) + " MiB, more than the " +
                   std::to_string(kMaxReadBytes >> 20) +
                   " MiB a DEM may take here (crop it first)");
  }
  if (const char* v = ds->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE")) raster.layout = v;
  if (const char* v = ds->GetMetadataItem("COMPRESSION", "IMAGE_STRUCTURE")) {
    raster.compression = v;
  }
  if (const char* v = ds->GetMetadataItem("PREDICTOR", "IMAGE_STRUCTURE")) raster.predictor = v;
  raster.overview_count = ds->GetRasterBand(1) ? ds->GetRasterBand(1)->GetOverviewCount() : 0;
  for (int b = 0; b < ds->GetRasterCount(); ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b + 1);
    raster.band_types.emplace_back(GDALGetDataTypeName(band->GetRasterDataType()));
    raster.band_descriptions.emplace_back(band->GetDescription());
    int has = 0;
    raster.nodata.push_back(band->GetNoDataValue(&has));
    raster.has_nodata.push_back(has != 0);
  }
  for (int b = 0; b < bands; ++b) {
    targets[b]->resize(pixels);
    if (ds->GetRasterBand(b + 1)->RasterIO(GF_Read, 0, 0, raster.width, raster.height,
                                           targets[b]->data(), raster.width, raster.height,
                                           GDT_Float32, 0, 0, nullptr) != CE_None) {
      Fail(path, "cannot read band " + std::to_string(b + 1));
    }
    if (raster.has_nodata[b] && !std::isnan(raster.nodata[b])) {
      const auto nodata = static_cast<float>(raster.nodata[b]);
      for (float& v : *targets[b]) {
        if (v == nodata) v = std::numeric_limits<float>::quiet_NaN();
      }
    }
  }
  return raster;
}

}  // namespace rovermap::io
