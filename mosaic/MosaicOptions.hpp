#pragma once

#include <string>

namespace rovermap::mosaic {

/// Options of `rovermap mosaic` (config section `mosaic.`).
struct MosaicOptions {
  /// Output CRS as GDAL reads it ("EPSG:32633", WKT, PROJ string); "" = the first input's. It
  /// must be projected, in metres.
  std::string crs;
  double cell_size_m = 0.0;         ///< [m] output cell edge; 0 = the finest input's
  double disagreement_sigma = 3.0;  ///< [sigma] an input disagrees beyond this many combined σ
  int tile_cells = 512;             ///< [cells] edge of the square tiles the grid is fused in
  bool coregister = true;           ///< register each input onto the mosaic of those before it
  int min_overlap_cells = 100;      ///< [cells] less overlap: placed as it is, and flagged
};

}  // namespace rovermap::mosaic
