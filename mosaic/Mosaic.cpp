#include "mosaic/Mosaic.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <fcntl.h>
#include <gdal_priv.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "mosaic/Coregister.hpp"
#include "mosaic/Fusion.hpp"
#include "mosaic/Warp.hpp"

namespace rovermap::mosaic {
namespace {

namespace fs = std::filesystem;
using detail::CellFusion;
using detail::DatasetPtr;
using detail::FusedLayers;
using detail::Input;
using detail::OutputGrid;
using detail::Window;

// GDAL's block cache when the user set none: the default (5 % of the RAM) would dominate the
// memory of a tiled mosaic.
constexpr GIntBig kCacheBytes = GIntBig{64} << 20;

void CheckOptions(const MosaicOptions& options) {
  auto fail = [](const std::string& key, const std::string& why) {
    throw std::invalid_argument("mosaic." + key + ": " + why);
  };
  if (!std::isfinite(options.cell_size_m) || options.cell_size_m < 0.0)
    fail("cell_size_m", "must be a finite number >= 0");
  if (!std::isfinite(options.disagreement_sigma) || options.disagreement_sigma <= 0.0)
    fail("disagreement_sigma", "must be a finite number > 0");
  if (options.tile_cells < 16) fail("tile_cells", "must be >= 16");
  if (options.min_overlap_cells < 3) fail("min_overlap_cells", "must be >= 3");
}

OGRSpatialReference OutputSrs(const MosaicOptions& options, const Input& first) {
  OGRSpatialReference srs;
  if (options.crs.empty()) {
    srs = first.srs;
    if (!srs.IsProjected()) {
      throw io::IoError(first.file.string() + ": its CRS is not projected (a DEM's is UTM or a " +
                        "local projection); set mosaic.crs");
    }
  } else {
    if (srs.SetFromUserInput(options.crs.c_str()) != OGRERR_NONE)
      throw std::invalid_argument("mosaic.crs: GDAL does not read '" + options.crs + "'");
    if (!srs.IsProjected())
      throw std::invalid_argument("mosaic.crs: must be a projected CRS (got '" + options.crs +
                                  "')");
  }
  if (std::abs(srs.GetLinearUnits() - 1.0) > 1e-9)
    throw std::invalid_argument("mosaic.crs: the output CRS must be in metres");
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

// The common grid: the finest input cell (or mosaic.cell_size_m), the union of the footprints,
// its edges on multiples of the cell size so that mosaics of parts share the grid of the whole.
OutputGrid MakeGrid(const std::vector<Input>& inputs, OGRSpatialReference srs,
                    const MosaicOptions& options) {
  OutputGrid grid;
  grid.srs = std::move(srs);
  char* wkt = nullptr;
  grid.srs.exportToWkt(&wkt);
  grid.wkt = wkt != nullptr ? wkt : "";
  CPLFree(wkt);
  double cell = options.cell_size_m;
  Eigen::Vector2d min = inputs.front().min_out;
  Eigen::Vector2d max = inputs.front().max_out;
  for (const Input& input : inputs) {
    if (options.cell_size_m == 0.0 && (cell == 0.0 || input.cell_size_out_m < cell))
      cell = input.cell_size_out_m;
    min = min.cwiseMin(input.min_out);
    max = max.cwiseMax(input.max_out);
  }
  // Footprints computed through a CRS transform land a hair off the multiples they are meant
  // to sit on: a millionth of a cell is taken as on.
  constexpr double kSnap = 1e-6;
  const double col0 = std::floor(min.x() / cell + kSnap);
  const double col1 = std::ceil(max.x() / cell - kSnap);
  const double row0 = std::floor(min.y() / cell + kSnap);
  const double row1 = std::ceil(max.y() / cell - kSnap);
  const double width = std::max(1.0, col1 - col0);
  const double height = std::max(1.0, row1 - row0);
  if (width * height > static_cast<double>(std::numeric_limits<int>::max()) * 64.0 ||
      width > std::numeric_limits<int>::max() || height > std::numeric_limits<int>::max()) {
    throw std::invalid_argument("mosaic.cell_size_m: " + std::to_string(cell) +
                                " m gives a grid of " + std::to_string(width) + " x " +
                                std::to_string(height) + " cells, too large");
  }
  grid.width = static_cast<int>(width);
  grid.height = static_cast<int>(height);
  grid.geotransform = {col0 * cell, cell, 0.0, row1 * cell, 0.0, -cell};
  return grid;
}

// Temporary files beside the output, removed unless committed.
class TemporaryFile {
 public:
  explicit TemporaryFile(const fs::path& out, const std::string& tag) {
    std::string pattern =
        (out.parent_path() / ("." + out.filename().string() + "." + tag + "-XXXXXX")).string();
    const int fd = ::mkstemp(pattern.data());
    if (fd < 0) {
      throw io::IoError(out.string() + ": cannot create a temporary file beside it (" +
                        std::generic_category().message(errno) + ")");
    }
    // mkstemp makes the file 0600: the mosaic gets the mode any new file would (0666 less the
    // umask), as the other outputs.
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::fchmod(fd, 0666 & ~mask);
    ::close(fd);
    path_ = pattern;
  }
  ~TemporaryFile() {
    if (!path_.empty()) {
      std::error_code ignored;
      fs::remove(path_, ignored);
    }
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  const fs::path& path() const { return path_; }
  /// Renamed over `out` (io::CommitTemporaryFile); no longer removed here.
  void CommitTo(const fs::path& out) {
    const fs::path temp = path_;
    path_.clear();
    io::CommitTemporaryFile(temp, out);
  }

 private:
  fs::path path_;
};

[[noreturn]] void FailWrite(const fs::path& out, const std::string& what) {
  const char* msg = CPLGetLastErrorMsg();
  throw io::IoError(out.string() + ": " + what +
                    (msg != nullptr && *msg != '\0' ? std::string(" (") + msg + ")" : ""));
}

const char* const kBandNames[4] = {"elevation", "elevation_stddev", "count", "disagreement"};

// A GDAL option list (free with CSLDestroy).
char** CreationOptions(std::initializer_list<std::pair<const char*, const char*>> options) {
  char** list = nullptr;
  for (const auto& [name, value] : options) list = CSLSetNameValue(list, name, value);
  return list;
}

// The tiled intermediate GeoTIFF the tiles are written into.
DatasetPtr CreateStaging(const fs::path& staging, const fs::path& out, const OutputGrid& grid,
                         const std::string& datum, std::size_t inputs) {
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (gtiff == nullptr) FailWrite(out, "GDAL lacks the GTiff driver");
  char** create = CreationOptions({{"TILED", "YES"},
                                   {"BLOCKXSIZE", "256"},
                                   {"BLOCKYSIZE", "256"},
                                   {"COMPRESS", "DEFLATE"},
                                   {"PREDICTOR", "3"},
                                   {"ZLEVEL", "1"},
                                   {"BIGTIFF", "IF_SAFER"},
                                   {"SPARSE_OK", "TRUE"}});
  DatasetPtr ds(gtiff->Create(staging.c_str(), grid.width, grid.height, 4, GDT_Float32, create));
  CSLDestroy(create);
  if (!ds) FailWrite(out, "cannot create the staging GeoTIFF");
  std::array<double, 6> g = grid.geotransform;
  ds->SetGeoTransform(g.data());
  ds->SetSpatialRef(&grid.srs);
  if (!datum.empty()) ds->SetMetadataItem("ELEVATION_DATUM", datum.c_str());
  ds->SetMetadataItem("MOSAIC_INPUTS", std::to_string(inputs).c_str());
  for (int b = 0; b < 4; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b + 1);
    band->SetDescription(kBandNames[b]);
    if (b < 2) band->SetUnitType("m");
    band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
  }
  return ds;
}

void WriteTile(GDALDataset* staging, const fs::path& out, const Window& window,
               FusedLayers& fused) {
  std::vector<float>* bands[4] = {&fused.elevation_m, &fused.stddev_m, &fused.count,
                                  &fused.disagreement};
  for (int b = 0; b < 4; ++b) {
    if (staging->GetRasterBand(b + 1)->RasterIO(
            GF_Write, window.col0, window.row0, window.width, window.height, bands[b]->data(),
            window.width, window.height, GDT_Float32, 0, 0, nullptr) != CE_None) {
      FailWrite(out, "cannot write a tile");
    }
  }
}

void TranslateToCog(const fs::path& staging, const fs::path& cog, const fs::path& out) {
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("COG");
  if (driver == nullptr) FailWrite(out, "GDAL lacks the COG driver");
  DatasetPtr source(GDALDataset::Open(staging.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!source) FailWrite(out, "cannot reopen the staging GeoTIFF");
  char** create = CreationOptions({{"COMPRESS", "DEFLATE"},
                                   {"PREDICTOR", "FLOATING_POINT"},
                                   {"LEVEL", "1"},
                                   {"BLOCKSIZE", "512"},
                                   {"OVERVIEWS", "AUTO"},
                                   {"RESAMPLING", "AVERAGE"},
                                   {"BIGTIFF", "IF_SAFER"},
                                   {"NUM_THREADS", "2"}});
  CPLErrorReset();
  GDALDataset* copy =
      driver->CreateCopy(cog.c_str(), source.get(), FALSE, create, nullptr, nullptr);
  CSLDestroy(create);
  bool ok = copy != nullptr && CPLGetLastErrorType() < CE_Failure;
  if (copy != nullptr) GDALClose(GDALDataset::ToHandle(copy));
  ok = ok && CPLGetLastErrorType() < CE_Failure;
  if (!ok) FailWrite(out, "GDAL cannot write the COG");
  // On disk before the rename, as io::WriteFileAtomically does.
  const int fd = ::open(cog.c_str(), O_RDONLY | O_CLOEXEC);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  if (!synced) {
    throw io::IoError(out.string() + ": cannot flush the COG to disk (" +
                      std::generic_category().message(errno) + ")");
  }
}

}  // namespace

MosaicResult BuildMosaic(const std::vector<fs::path>& files, const fs::path& out,
                         const fs::path& report, const MosaicOptions& options,
                         const registration::RegistrationOptions& registration) {
  CheckOptions(options);
  if (files.empty()) throw std::invalid_argument("mosaic: no input DEM");
  if (CPLGetConfigOption("GDAL_CACHEMAX", nullptr) == nullptr) GDALSetCacheMax64(kCacheBytes);
  CPLPushErrorHandler(CPLQuietErrorHandler);
  struct PopHandler {
    ~PopHandler() { CPLPopErrorHandler(); }
  } pop_handler;

  // Open, check and place every input before any output exists.
  std::vector<Input> inputs;
  for (const fs::path& file : files) inputs.push_back(detail::OpenInput(file));
  const OGRSpatialReference srs = OutputSrs(options, inputs.front());
  for (Input& input : inputs) detail::LocateInput(&input, srs);
  const OutputGrid grid = MakeGrid(inputs, srs, options);
  for (Input& input : inputs) {
    detail::Correction datum;
    datum.datum_offset_m = input.datum_altitude_m - inputs.front().datum_altitude_m;
    detail::SetCorrection(&input, grid.srs, datum);
  }

  MosaicResult result;
  result.width = grid.width;
  result.height = grid.height;
  result.geotransform = grid.geotransform;
  result.wkt = grid.wkt;
  result.cell_size_m = grid.cell_size_m();
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    InputReport entry;
    entry.file = inputs[i].file.string();
    entry.reference = i == 0;
    entry.status = i == 0 ? "reference" : "off";
    if (i > 0 && options.coregister) {
      entry = detail::Coregister(inputs, i, grid, options, registration);
    }
    result.inputs.push_back(entry);
  }

  // Fusion, tile by tile: each tile warps only the inputs that reach it.
  TemporaryFile staging(out, "staging");
  TemporaryFile cog(out, "tmp");
  {
    DatasetPtr staged =
        CreateStaging(staging.path(), out, grid, inputs.front().datum_text, inputs.size());
    const int tile = options.tile_cells;
    for (int row0 = 0; row0 < grid.height; row0 += tile) {
      for (int col0 = 0; col0 < grid.width; col0 += tile) {
        const Window window{col0, row0, std::min(tile, grid.width - col0),
                            std::min(tile, grid.height - row0)};
        CellFusion fusion(window.cells());
        for (const Input& input : inputs) {
          if (detail::Touches(input, grid, window))
            fusion.Add(detail::WarpInput(input, grid, window));
        }
        FusedLayers fused = fusion.Finish(options.disagreement_sigma);
        result.valid_cells += fused.valid_cells;
        WriteTile(staged.get(), out, window, fused);
        ++result.tiles;
      }
    }
    CPLErrorReset();
    GDALDataset* raw = staged.release();
    GDALClose(GDALDataset::ToHandle(raw));
    if (CPLGetLastErrorType() >= CE_Failure) FailWrite(out, "cannot finish the staging GeoTIFF");
  }
  TranslateToCog(staging.path(), cog.path(), out);
  if (report.empty()) {
    cog.CommitTo(out);
  } else {
    const fs::path json = io::WriteTemporaryFile(report, MosaicReportJson(result, options));
    try {
      cog.CommitTo(out);
    } catch (...) {
      std::error_code ignored;
      fs::remove(json, ignored);
      throw;
    }
    io::CommitTemporaryFile(json, report);
  }
  return result;
}

std::string MosaicReportJson(const MosaicResult& result, const MosaicOptions& options) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const InputReport& r : result.inputs) {
    inputs.push_back(
        {{"file", r.file},
         {"reference", r.reference},
         {"status", r.status},
         {"overlaps", r.overlaps},
         {"applied", r.applied},
         {"translation_m", {r.translation_m.x(), r.translation_m.y(), r.translation_m.z()}},
         {"rotation_deg", {r.rotation_deg.x(), r.rotation_deg.y(), r.rotation_deg.z()}},
         {"overlap_cells", r.overlap_cells},
         {"inlier_ratio", r.inlier_ratio},
         {"iterations", r.iterations},
         {"disagreement_before", r.disagreement_before},
         {"disagreement_after", r.disagreement_after},
         {"rms_before_m", r.rms_before_m},
         {"rms_after_m", r.rms_after_m}});
  }
  const nlohmann::json out = {{"width", result.width},
                              {"height", result.height},
                              {"cell_size_m", result.cell_size_m},
                              {"geotransform", result.geotransform},
                              {"tiles", result.tiles},
                              {"valid_cells", result.valid_cells},
                              {"options",
                               {{"crs", options.crs},
                                {"cell_size_m", options.cell_size_m},
                                {"disagreement_sigma", options.disagreement_sigma},
                                {"tile_cells", options.tile_cells},
                                {"coregister", options.coregister},
                                {"min_overlap_cells", options.min_overlap_cells}}},
                              {"inputs", inputs}};
  return out.dump(2) + "\n";
}

}  // namespace rovermap::mosaic
