#pragma once
// Rasters too large for memory, written a window at a time (the mosaic, the terrain layers of
// a large DEM): a tiled GeoTIFF staged beside the output, then copied into a COG and renamed
// over it. GDAL's errors become IoError naming the output.

#include <gdal_priv.h>

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace rovermap::io {

/// GDALAllRegister, once per process.
void RegisterGdal();

/// GDAL's block cache when the user set none (GDAL_CACHEMAX): 64 MiB. The default, 5 % of the
/// RAM, would dominate the memory of a raster written a window at a time.
void BoundGdalCache();

/// Keeps GDAL from printing while it lives: its errors are collected for IoError messages.
class QuietGdal {
 public:
  QuietGdal();
  ~QuietGdal();
  QuietGdal(const QuietGdal&) = delete;
  QuietGdal& operator=(const QuietGdal&) = delete;
  /// " (GDAL's last message)", or "" when there is none.
  static std::string Last();
};

struct GdalDatasetCloser {
  void operator()(GDALDataset* ds) const;
};
using GdalDatasetPtr = std::unique_ptr<GDALDataset, GdalDatasetCloser>;

/// A file beside `out` (`.NAME.TAG-XXXXXX`), removed unless committed.
class TemporaryFile {
 public:
  /// @throw IoError naming `out` if it cannot be created.
  TemporaryFile(const std::filesystem::path& out, const std::string& tag);
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  const std::filesystem::path& path() const { return path_; }
  /// Renamed over `out` (CommitTemporaryFile); no longer removed here.
  void CommitTo(const std::filesystem::path& out);

 private:
  std::filesystem::path path_;
};

/// Throws IoError "`out`: `what` (GDAL's last message)".
[[noreturn]] void FailGdalWrite(const std::filesystem::path& out, const std::string& what);

/// A band of a staged raster: its description and unit ("" for none).
struct StagedBand {
  std::string name;
  std::string unit;
};

/// A tiled (256²), DEFLATE-compressed, sparse Float32 GeoTIFF at `staging` with nodata NaN.
/// @throw IoError naming `out`.
GdalDatasetPtr CreateStaging(const std::filesystem::path& staging, const std::filesystem::path& out,
                             int width, int height, const std::array<double, 6>& geotransform,
                             const OGRSpatialReference& srs, const std::vector<StagedBand>& bands);

/// Writes one band's window of a staged raster. @throw IoError naming `out`.
void WriteWindow(GDALDataset* staging, const std::filesystem::path& out, int band, int col0,
                 int row0, int width, int height, const float* data);

/// Closes a staged raster, with GDAL's last error if flushing it failed.
/// @throw IoError naming `out`.
void CloseStaging(GdalDatasetPtr staged, const std::filesystem::path& out);

/// Copies the staged raster into a COG at `cog` (DEFLATE with the floating-point predictor,
/// 512² blocks, overviews resampled with `resampling`), synced to disk.
/// @throw IoError naming `out`.
void TranslateToCog(const std::filesystem::path& staging, const std::filesystem::path& cog,
                    const std::filesystem::path& out, const char* resampling = "AVERAGE");

}  // namespace rovermap::io
