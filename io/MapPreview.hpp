#pragma once
// dem.png (docs/design.md §6): hillshade blended with a colour map of elevation, a colour bar in
// metres, a scale bar, and the trajectory. Drawn in the map's grid frame, north up (the same
// orientation as dem.tif).

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "dem/ElevationMap.hpp"
#include "io/DemLayers.hpp"
#include "terrain/TerrainLayers.hpp"

namespace rovermap::io {

/// Options of the preview.
struct MapPreviewOptions {
  int max_map_px = 1200;            ///< [px] longest edge of the map part; larger maps decimated
  double sun_azimuth_deg = 315.0;   ///< [deg] clockwise from grid north (GIS default: north-west)
  double sun_elevation_deg = 45.0;  ///< [deg] above the horizon
  double hillshade_weight = 0.5;    ///< [ratio] 0 = colour only, 1 = shade only
  /// [ratio] the colour range runs from this quantile of the heights to 1 minus it (0 = the
  /// extremes), so that a few wrong cells do not set it; in [0, 0.5)
  double colour_quantile = 0.005;
};

/// A path to draw on the map, with its legend label and colour.
struct PreviewTrajectory {
  std::string label;  ///< legend text ("registered"); empty: no legend line
  std::array<unsigned char, 3> rgb{255, 255, 255};
  std::vector<Eigen::Vector3d> points;  ///< world x, y [m] (z ignored)
  /// [px] line width (outlined 1 px each side): a wide line drawn first shows as a band around
  /// the narrower ones drawn over it, where they coincide
  int width_px = 2;
};

/// Renders `map`'s published cells with `trajectories` (each a coloured line with a black
/// outline, its start marked, a legend line under the map) and writes it to `path` (PNG)
/// atomically. A map with no published cell gives a small "no data" image.
/// @throw IoError naming `path` if encoding or writing fails.
void WriteDemPreview(const std::filesystem::path& path, const dem::ElevationMap& map,
                     const std::vector<PreviewTrajectory>& trajectories,
                     const MapPreviewOptions& options = {});

/// The same from the map's layers (RasteriseDem), taken before: the serve daemon draws them
/// while the map goes on changing.
void WriteDemPreview(const std::filesystem::path& path, const DemLayers& layers,
                     const std::vector<PreviewTrajectory>& trajectories,
                     const MapPreviewOptions& options = {});

/// terrain.png: `terrain`'s traversability (red to green), its hazard, uncertain and unknown
/// cells, shaded by `layers`' relief, with `trajectories`, written to `path` atomically. Each
/// pixel of a decimated map shows the worst of its cells.
/// @throw std::invalid_argument if `terrain` is not on `layers`' grid.
/// @throw IoError naming `path` if encoding or writing fails.
void WriteTerrainPreview(const std::filesystem::path& path, const DemLayers& layers,
                         const terrain::TerrainLayers& terrain,
                         const std::vector<PreviewTrajectory>& trajectories,
                         const MapPreviewOptions& options = {});

/// Renders `map`'s published cells (ElevationMap::Published) and writes it to `path` (PNG)
/// atomically. `trajectory_world` (world x, y [m]; z ignored) is drawn in white with a black
/// outline when not empty; the start is marked. A map with no published cell gives a small
/// "no data" image.
/// @throw IoError naming `path` if encoding or writing fails.
void WriteDemPreview(const std::filesystem::path& path, const dem::ElevationMap& map,
                     const std::vector<Eigen::Vector3d>& trajectory_world = {},
                     const MapPreviewOptions& options = {});

}  // namespace rovermap::io
