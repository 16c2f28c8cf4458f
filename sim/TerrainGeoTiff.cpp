#include "sim/TerrainGeoTiff.hpp"

#include <algorithm>
#include <cmath>

#include "io/Georeference.hpp"

namespace rovermap::sim {

io::GeoTiffInfo WriteTerrainGeoTiff(const std::filesystem::path& path, const Simulator& simulator,
                                    dem::ElevationMapOptions grid) {
  const SimOptions& o = simulator.options();
  const io::Georeference georef(
      io::GeodeticOrigin{o.origin_latitude_deg, o.origin_longitude_deg, o.origin_altitude_m},
      io::Body::kEarth);
  grid.grid_rotation_rad = georef.convergence_rad();
  dem::ElevationMap map(grid);
  // Grid-frame bounding box of the terrain square (the grid may be rotated by the convergence).
  const double half = simulator.terrain().half_size_m();
  double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
  for (const double sx : {-half, half}) {
    for (const double sy : {-half, half}) {
      const Eigen::Vector2d g = map.WorldToGrid(sx, sy);
      lo_x = std::min(lo_x, g.x());
      hi_x = std::max(hi_x, g.x());
      lo_y = std::min(lo_y, g.y());
      hi_y = std::max(hi_y, g.y());
    }
  }
  const double cell = grid.cell_size_m;
  for (auto y = static_cast<std::int64_t>(std::floor(lo_y / cell));
       y <= static_cast<std::int64_t>(std::floor(hi_y / cell)); ++y) {
    for (auto x = static_cast<std::int64_t>(std::floor(lo_x / cell));
         x <= static_cast<std::int64_t>(std::floor(hi_x / cell)); ++x) {
      const dem::CellIndex index{x, y};
      const Eigen::Vector2d centre = map.CellCenterWorld(index);
      const double height = simulator.terrain().Height(centre.x(), centre.y());
      // SetCell's default count is the map's min_support: every true cell is published.
      if (std::isfinite(height)) map.SetCell(index, height, 0.0);
    }
  }
  return io::WriteDemGeoTiff(path, map, georef);
}

}  // namespace rovermap::sim
