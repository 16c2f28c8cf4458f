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
  // A correction is applied only when it passes all three tests below (else "refused").
  /// [ratio] directions with less information than this × the best's (rotations scaled to
  /// metres of arc over the overlap) are not corrected; refused if x, y or yaw is among them
  double min_information = 2e-5;
  /// [ratio] the RMS height difference over the overlap must fall below this × its value before
  double min_improvement = 0.8;
  double max_correction_m = 2.0;    ///< [m] largest shift of the overlap's centre (start error)
  double max_correction_deg = 5.0;  ///< [deg] largest rotation (start heading error)
  /// [deg] σ of the inputs' roll and pitch (from gravity): a tilt correction is weighed
  /// against it; 0 = never tilted
  double tilt_sigma_deg = 0.05;
};

}  // namespace rovermap::mosaic
