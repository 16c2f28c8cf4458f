#pragma once
// dem.tif (docs/design.md §6): a Cloud-Optimized GeoTIFF, Float32, north-up; band 1 elevation [m],
// band 2 elevation standard deviation [m], band 3 point count; nodata NaN; CRS and
// geotransform from io::Georeference. Written through GDAL: a MEM dataset, then CreateCopy
// with the COG driver (DEFLATE, floating-point predictor, overviews) to a temporary file in
// the same directory, renamed into place.

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "dem/ElevationMap.hpp"
#include "io/DemLayers.hpp"
#include "io/Georeference.hpp"

namespace rovermap::io {

/// Options of the GeoTIFF writer.
struct GeoTiffOptions {
  int block_size = 512;   ///< [px] COG tile edge (power of two, 64..4096)
  bool overviews = true;  ///< build overviews (COG OVERVIEWS=AUTO) or none
  int deflate_level = 1;  ///< [1..9] DEFLATE effort (1: much faster than 6, slightly larger;
                          ///< docs/benchmarks.md, "Maps")
  int threads = 0;        ///< [count] GDAL compression threads; 0 = all cores
};

/// What was written.
struct GeoTiffInfo {
  int width = 0;                         ///< [px] columns (west to east)
  int height = 0;                        ///< [px] rows (north to south)
  std::array<double, 6> geotransform{};  ///< GDAL order: E0, dE/dcol, 0, N0, 0, dN/drow (< 0)
  std::size_t valid_cells = 0;           ///< pixels with data (the published cells)
};

/// A north-up raster's place: its size, geotransform (GDAL order) and CRS (WKT; empty: none),
/// and dataset metadata items.
struct RasterFrame {
  int width = 0;
  int height = 0;
  std::array<double, 6> geotransform{};
  std::string wkt;
  std::vector<std::pair<std::string, std::string>> metadata;
};

/// One Float32 band: its cells (row-major, row 0 north, NaN = no data), description and unit.
struct RasterBand {
  const std::vector<float>* data = nullptr;
  std::string name;
  std::string unit;
};

/// Writes `bands` as a Cloud-Optimized GeoTIFF (Float32, nodata NaN, DEFLATE with the
/// floating-point predictor, overviews per `options`) to `path` atomically; valid_cells counts
/// the first band's cells with data.
/// @throw std::invalid_argument if there is no band or a band's size is not width × height.
/// @throw IoError naming `path` if GDAL cannot write it or the rename fails.
GeoTiffInfo WriteFloatGeoTiff(const std::filesystem::path& path, const RasterFrame& frame,
                              const std::vector<RasterBand>& bands,
                              const GeoTiffOptions& options = {});

/// dem.tif's frame for the map's layers: the geotransform from `georef`, its CRS, the datum.
/// @throw std::invalid_argument if the layers' grid rotation differs from
///        georef.convergence_rad() (the grid would not be north-up).
RasterFrame DemRasterFrame(const DemLayers& layers, const Georeference& georef);

/// Writes `map` as dem.tif to `path` atomically: its published cells (ElevationMap::Published;
/// the others are NaN with count 0). The raster covers the map's cell bounds; an empty map gives
/// one NaN pixel at the origin.
/// @throw std::invalid_argument if the map's grid_rotation_rad differs from
///        georef.convergence_rad() by more than 1e-9 rad (the grid would not be north-up).
/// @throw IoError naming `path` if GDAL cannot write it, the raster would exceed 2^31 pixels,
///        or the rename fails; no file is left behind.
GeoTiffInfo WriteDemGeoTiff(const std::filesystem::path& path, const dem::ElevationMap& map,
                            const Georeference& georef, const GeoTiffOptions& options = {});
/// The same from the map's layers (RasteriseDem), taken before: the serve daemon encodes them
/// while the map goes on changing.
/// @throw as above; std::invalid_argument also if the layers' sizes disagree.
GeoTiffInfo WriteDemGeoTiff(const std::filesystem::path& path, const DemLayers& layers,
                            const Georeference& georef, const GeoTiffOptions& options = {});

/// A DEM GeoTIFF read back (row-major, row 0 = north, as stored).
struct DemRaster {
  std::string file;  ///< where it was read from (for messages)
  int width = 0;
  int height = 0;
  /// GDAL order: x = g[0] + col·g[1], y = g[3] + row·g[5] at a cell's corner; g[2] = g[4] = 0.
  std::array<double, 6> geotransform{};
  std::string wkt;                             ///< the CRS as WKT, empty when the file has none
  /// ELEVATION_DATUM metadata as written (rovermap's DEMs: "height above the origin altitude
  /// A m ..."), empty when absent.
  std::string elevation_datum;
  int epsg = 0;                                ///< when the CRS has an EPSG code, else 0
  std::vector<float> elevation_m;              ///< band 1, NaN = no data
  std::vector<float> stddev_m;                 ///< band 2 (empty if the file has one band)
  std::vector<float> count;                    ///< band 3 (empty if absent)
  std::vector<std::string> band_types;         ///< GDAL data type name per band ("Float32")
  std::vector<std::string> band_descriptions;  ///< per band ("elevation", ...)
  std::vector<double> nodata;                  ///< per band; NaN when nodata is NaN
  std::vector<bool> has_nodata;                ///< per band
  std::string layout;       ///< IMAGE_STRUCTURE LAYOUT metadata ("COG" for a COG), else ""
  std::string compression;  ///< IMAGE_STRUCTURE COMPRESSION ("DEFLATE"), else ""
  std::string predictor;    ///< IMAGE_STRUCTURE PREDICTOR ("3": floating point), else ""
  int overview_count = 0;   ///< overviews of band 1
  /// Band 1 at (col, row); NaN outside.
  float ElevationAt(int col, int row) const;
};

/// Reads a GeoTIFF written by WriteDemGeoTiff (or any north-up 1..3-band raster GDAL reads:
/// band 1 elevation) as Float32; values equal to a band's nodata become NaN.
/// @throw IoError naming `path` if it cannot be opened or read, has no geotransform, its grid
///        is rotated or degenerate, or reading it would take more than 1 GiB (the bands as
///        Float32 and one block of the file as GDAL decodes it).
DemRaster ReadDemGeoTiff(const std::filesystem::path& path);

}  // namespace rovermap::io
