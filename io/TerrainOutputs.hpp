#pragma once
// terrain.tif and the grids the terrain layers are computed on (docs/terrain.md): from the
// mapper's DEM (its layers) or from any north-up GeoTIFF GDAL reads.

#include <filesystem>
#include <string>

#include "io/DemLayers.hpp"
#include "io/GeoTiff.hpp"
#include "terrain/TerrainLayers.hpp"

namespace rovermap::io {

/// The DEM's heights and σ as the layers read them (views into `layers`).
terrain::GridView GridViewOf(const DemLayers& layers);

/// Whether a DEM GeoTIFF's band 2 is its heights' σ: when its description names a standard
/// deviation ("stddev", "sigma", "std", "uncertainty"; dem.tif's "elevation_stddev"), or when the
/// file has dem.tif's 2 or 3 bands, band 2 without a description and never negative.
bool RasterHasSigma(const DemRaster& raster);

/// A GeoTIFF read by ReadDemGeoTiff as the layers' grid: `raster`'s pixels as cells (column
/// spacing |g1|, row spacing |g5|), with its σ when RasterHasSigma.
/// @throw IoError naming the file if the raster is not in metres (a geographic CRS).
terrain::GridView GridViewOf(const DemRaster& raster);

/// `raster` as DemLayers (cells (0, 0) … (width − 1, height − 1), the column spacing as the cell
/// size), for the preview.
DemLayers DemLayersOf(const DemRaster& raster);

/// Writes terrain.tif: six Float32 bands on `frame` (dem.tif's grid), nodata NaN — slope_deg,
/// slope_stddev_deg, roughness_m, step_m, traversability, uncertain — with the footprint and the
/// limits in the metadata. Atomic; @throw as WriteFloatGeoTiff.
GeoTiffInfo WriteTerrainGeoTiff(const std::filesystem::path& path, const RasterFrame& frame,
                                const terrain::TerrainLayers& layers,
                                const terrain::TerrainOptions& options,
                                const GeoTiffOptions& tiff = {});

/// What WriteTerrainTiled read and computed.
struct TiledTerrain {
  terrain::TerrainLayers counts;  ///< counts, footprint and has_sigma; the layer vectors empty
  int width = 0;                  ///< [cells]
  int height = 0;                 ///< [cells]
  double cell_x_m = 0.0, cell_y_m = 0.0;
  std::size_t height_cells = 0;  ///< cells of the DEM with a height
  std::string sigma_band;        ///< band 2's description when it is the σ, else ""
};

/// terrain.tif for the DEM GeoTIFF `dem` (north-up, in metres; band 2 its σ as RasterHasSigma
/// says) in bounded memory, for DEMs too large to hold (a campaign's mosaic): the heights are
/// read a row of tiles at a time (terrain::ComputeTerrainByRows) and the layers staged in a
/// tiled GeoTIFF beside `tif`, then copied into the COG. The same bands, metadata and values as
/// WriteTerrainGeoTiff of the whole DEM's layers. terrain.png at `png` (when not empty) from
/// the layers and heights read back decimated to the preview's size. Each file atomic; nothing
/// is left on an error.
/// @throw IoError naming the file if the DEM cannot be read, holds no height, has a rotated
///        grid or a geographic CRS, or an output cannot be written.
/// @throw terrain::TerrainError for a footprint smaller than two cells or larger than the DEM.
TiledTerrain WriteTerrainTiled(const std::filesystem::path& dem, const std::filesystem::path& tif,
                               const std::filesystem::path& png,
                               const terrain::TerrainOptions& options);

}  // namespace rovermap::io
