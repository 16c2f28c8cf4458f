#pragma once
// Internal to mosaic/: the inputs as GDAL datasets and their resampling onto windows of the
// output grid with GDAL's warper.

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "io/TiledGeoTiff.hpp"

namespace rovermap::mosaic::detail {

using DatasetPtr = io::GdalDatasetPtr;

/// A rigid correction found by co-registration, in output-CRS coordinates relative to `origin`:
/// p' = origin + T·(p − origin). Plus the shift between the input's and the mosaic's
/// elevation datums.
struct Correction {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< [m] output CRS x, y and height
  double datum_offset_m = 0.0;  ///< [m] added to the input's heights (its origin altitude − ours)
};

/// A window of the output grid: `width` × `height` cells from (col0, row0).
struct Window {
  int col0 = 0;
  int row0 = 0;
  int width = 0;
  int height = 0;
  std::size_t cells() const {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  }
};

/// The output grid: north-up, in `srs`.
struct OutputGrid {
  OGRSpatialReference srs;
  std::string wkt;
  std::array<double, 6> geotransform{};  ///< GDAL order, g[5] = −g[1]
  int width = 0;
  int height = 0;
  double cell_size_m() const { return geotransform[1]; }
  /// Output-CRS centre of cell (col, row).
  Eigen::Vector2d CellCentre(int col, int row) const {
    return {geotransform[0] + (col + 0.5) * geotransform[1],
            geotransform[3] + (row + 0.5) * geotransform[5]};
  }
  /// The cells a box (output CRS) touches, clipped to the grid; empty width if none.
  Window Cover(const Eigen::Vector2d& min, const Eigen::Vector2d& max) const;
};

/// One input DEM, open for the whole run.
struct Input {
  std::filesystem::path file;
  DatasetPtr dataset;
  std::array<double, 6> geotransform{};
  OGRSpatialReference srs;
  bool is_mosaic = false;         ///< has the disagreement band (a mosaic made by this module)
  double datum_altitude_m = 0;    ///< [m] its heights are above this altitude (ELEVATION_DATUM)
  std::string datum_text;         ///< ELEVATION_DATUM as written, "" if absent
  Eigen::Vector2d min_out{0, 0};  ///< footprint bounding box in the output CRS [m]
  Eigen::Vector2d max_out{0, 0};
  double cell_size_out_m = 0.0;  ///< [m] its cell edge in the output CRS
  Correction correction;
  /// The geotransform the warper reads it with: `geotransform` with the correction's horizontal
  /// part (set by SetCorrection).
  std::array<double, 6> warp_geotransform{};
};

/// Opens and checks one input. @throw io::IoError naming the file.
Input OpenInput(const std::filesystem::path& file);

/// Footprint and cell size of `input` in `srs`. @throw io::IoError naming the file if it cannot
/// be transformed.
void LocateInput(Input* input, const OGRSpatialReference& srs);

/// Sets the input's correction and the geotransform that moves it horizontally: the correction
/// (an affine map in the output CRS) carried into the input's CRS through the Jacobian of the
/// CRS transform at the footprint's centre (exact when both CRS are the same).
/// @throw io::IoError naming the file if the CRS transform fails there.
void SetCorrection(Input* input, const OGRSpatialReference& srs, const Correction& correction);

/// An input resampled onto a window: elevation and σ bilinearly, count and disagreement by
/// nearest neighbour; NaN where it has no data. Heights carry the input's correction.
struct WarpedLayers {
  std::vector<float> elevation_m;
  std::vector<float> stddev_m;
  std::vector<float> count;
  std::vector<float> disagreement;  ///< empty unless the input is a mosaic
};

/// Resamples `input` (with its correction) onto `window` of `grid`.
/// @throw io::IoError naming the file if GDAL fails.
WarpedLayers WarpInput(const Input& input, const OutputGrid& grid, const Window& window);

/// Whether the input's footprint meets the window.
bool Touches(const Input& input, const OutputGrid& grid, const Window& window);

}  // namespace rovermap::mosaic::detail
