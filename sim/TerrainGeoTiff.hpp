#pragma once
// terrain.tif: the simulator's true terrain written like dem.tif (docs/design.md §6), so that DEM
// accuracy can be measured with `rovermap eval --dem dem.tif --reference terrain.tif`.

#include <filesystem>

#include "dem/ElevationMap.hpp"
#include "io/GeoTiff.hpp"
#include "sim/Simulator.hpp"

namespace rovermap::sim {

/// Samples the true terrain height at the centre of every cell of an elevation grid with
/// `grid` options (cell size, tiles; its rotation is replaced by the georeference's meridian
/// convergence, as for dem.tif) that lies inside the terrain square, and writes it with
/// io::WriteDemGeoTiff (band 2: 0 m standard deviation, band 3: count 1) to `path`,
/// atomically. The origin and body are the simulator's.
/// @throw io::IoError naming `path` if it cannot be written.
io::GeoTiffInfo WriteTerrainGeoTiff(const std::filesystem::path& path, const Simulator& simulator,
                                    dem::ElevationMapOptions grid);

/// reference_dem.tif (SimOptions::reference_*): the true terrain averaged over square posts of
/// reference_post_m (a 5 × 5 sample each), plus Gaussian noise of reference_sigma_m, north-up in
/// the sequence's projected CRS, with its geotransform moved by reference_offset_m (east, north):
/// an orbital product's georeferencing error. Band 2 holds reference_sigma_m. Posts beyond the
/// terrain square are no data. Written atomically.
/// @throw io::IoError naming `path` if it cannot be written; std::invalid_argument if
///        reference_post_m is not > 0.
io::GeoTiffInfo WriteReferenceDem(const std::filesystem::path& path, const Simulator& simulator);

}  // namespace rovermap::sim
