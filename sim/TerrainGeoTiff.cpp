#include "sim/TerrainGeoTiff.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "io/Georeference.hpp"
#include "sim/Terrain.hpp"

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

io::GeoTiffInfo WriteReferenceDem(const std::filesystem::path& path, const Simulator& simulator) {
  constexpr std::uint64_t kSaltReference = 5000;
  constexpr int kSamples = 5;  // per post edge
  const SimOptions& o = simulator.options();
  if (!(o.reference_post_m > 0.0)) {
    throw std::invalid_argument("sim.reference_post_m must be > 0 to write a reference DEM");
  }
  const io::Georeference georef(
      io::GeodeticOrigin{o.origin_latitude_deg, o.origin_longitude_deg, o.origin_altitude_m},
      io::Body::kEarth);
  // Projected (E, N) -> world: g = (P − P0) / s, rotated back by the convergence.
  const double s = georef.scale_factor();
  const Eigen::Rotation2Dd to_world(-georef.convergence_rad());
  auto world_of = [&](double e, double n) {
    return Eigen::Vector2d(to_world * ((Eigen::Vector2d(e, n) - georef.origin_projected()) / s));
  };
  // The terrain square's box in the projection.
  const double half = simulator.terrain().half_size_m();
  const Eigen::Rotation2Dd to_grid(georef.convergence_rad());
  Eigen::AlignedBox2d box;
  for (const double sx : {-half, half})
    for (const double sy : {-half, half})
      box.extend(georef.origin_projected() + s * (to_grid * Eigen::Vector2d(sx, sy)));
  const double post = o.reference_post_m;
  const double e0 = std::floor(box.min().x() / post) * post;
  const double n0 = std::ceil(box.max().y() / post) * post;
  io::RasterFrame frame;
  frame.width = static_cast<int>(std::ceil((box.max().x() - e0) / post));
  frame.height = static_cast<int>(std::ceil((n0 - box.min().y()) / post));
  frame.wkt = georef.wkt();
  frame.metadata = {{"ELEVATION_DATUM", "height above the origin altitude " +
                                            std::to_string(georef.origin().altitude_m) +
                                            " m (world z, ENU up)"}};
  const double dx = o.reference_offset_m.size() == 2 ? o.reference_offset_m[0] : 0.0;
  const double dy = o.reference_offset_m.size() == 2 ? o.reference_offset_m[1] : 0.0;
  frame.geotransform = {e0 + dx, post, 0.0, n0 + dy, 0.0, -post};
  const auto n = static_cast<std::size_t>(frame.width) * static_cast<std::size_t>(frame.height);
  std::vector<float> z(n, std::numeric_limits<float>::quiet_NaN());
  std::vector<float> sigma(n, std::numeric_limits<float>::quiet_NaN());
  for (int row = 0; row < frame.height; ++row) {
    for (int col = 0; col < frame.width; ++col) {
      double sum = 0.0;
      int count = 0;
      for (int a = 0; a < kSamples; ++a) {
        for (int b = 0; b < kSamples; ++b) {
          const double e = e0 + (col + (a + 0.5) / kSamples) * post;
          const double nn = n0 - (row + (b + 0.5) / kSamples) * post;
          const Eigen::Vector2d w = world_of(e, nn);
          const double h = simulator.terrain().Height(w.x(), w.y());
          if (!std::isfinite(h)) continue;
          sum += h;
          ++count;
        }
      }
      if (count < kSamples * kSamples) continue;  // a post partly off the terrain
      const std::size_t k = static_cast<std::size_t>(row) * frame.width + col;
      z[k] = static_cast<float>(sum / count +
                                o.reference_sigma_m * HashNormal(static_cast<std::uint64_t>(o.seed),
                                                                 kSaltReference,
                                                                 static_cast<std::uint64_t>(row),
                                                                 static_cast<std::uint64_t>(col)));
      sigma[k] = static_cast<float>(o.reference_sigma_m);
    }
  }
  return io::WriteFloatGeoTiff(
      path, frame, {{&z, "elevation", "m"}, {&sigma, "elevation standard deviation", "m"}});
}

}  // namespace rovermap::sim
