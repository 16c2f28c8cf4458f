#pragma once
// A reference DEM (docs/graph.md): an elevation model made before the rover came (an orbital
// stereo DTM, an earlier survey) that the rover's own DEM is matched against. Any raster GDAL
// reads with a CRS it can transform to geographic coordinates on the sequence's body: band 1
// elevation (above the ellipsoid, or above the altitude its ELEVATION_DATUM names, as rovermap's
// own DEMs say), band 2 its σ when the file has one.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "io/Georeference.hpp"

namespace rovermap::io {

/// How a reference DEM's heights are weighed.
struct ReferenceDemOptions {
  bool sigma_band = true;  ///< band 2 holds the heights' σ [m] when the file has one
  double sigma_m = 0.5;    ///< [m] σ of the heights otherwise; > 0
};

/// A reference DEM resampled onto a world (ENU) grid: node (col, row) at
/// origin_world + spacing_m · (col, row), x east, y north.
struct ReferenceGrid {
  Eigen::Vector2d origin_world = Eigen::Vector2d::Zero();  ///< [m]
  double spacing_m = 0.0;                                  ///< [m]
  int width = 0;                                           ///< nodes along x
  int height = 0;                                          ///< nodes along y
  std::vector<float> z_m;      ///< world z per node (row-major, row = y index); NaN = no data
  std::vector<float> sigma_m;  ///< [m] σ of z_m
  Eigen::Vector2d Node(int col, int row) const {
    return origin_world + spacing_m * Eigen::Vector2d(col, row);
  }
  /// Bilinear height at world (x, y); NaN outside or next to a node without data.
  double HeightAt(double x_m, double y_m) const;
  std::size_t ValidNodes() const;
};

/// One reference DEM, read whole when opened, placed in a sequence's world frame.
class ReferenceDem {
 public:
  /// Opens `file` and checks that it can be used with `georef`'s world frame.
  /// @throw IoError naming the file if GDAL cannot read it (ReadDemGeoTiff's cases), it has no
  ///        CRS, GDAL cannot transform its CRS to geographic coordinates, its ellipsoid is of
  ///        another body than `georef`'s (semi-major axes more than 1 % apart), no cell holds a
  ///        height, or its σ (band 2 or options.sigma_m) is not > 0 where it has heights.
  ReferenceDem(const std::filesystem::path& file, const Georeference& georef,
               const ReferenceDemOptions& options = {});
  ~ReferenceDem();
  ReferenceDem(const ReferenceDem&) = delete;
  ReferenceDem& operator=(const ReferenceDem&) = delete;

  const std::string& file() const;
  /// [m] its cell edge on the ground, near the world origin (or its centre if farther).
  double post_spacing_m() const;
  /// The world (x, y) box its cells cover (corners and edges transformed).
  const Eigen::AlignedBox2d& footprint_world() const;
  /// Heights resampled (bilinear, in the file's own grid) at the world nodes covering
  /// [min_world, max_world] at post_spacing_m, aligned to multiples of it; nodes outside the
  /// file or next to its no-data cells are NaN. Not thread-safe (one GDAL transformation).
  ReferenceGrid Resample(const Eigen::Vector2d& min_world, const Eigen::Vector2d& max_world) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rovermap::io
