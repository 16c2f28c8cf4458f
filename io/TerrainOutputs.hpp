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

}  // namespace rovermap::io
