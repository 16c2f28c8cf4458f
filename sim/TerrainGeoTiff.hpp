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

}  // namespace rovermap::sim
