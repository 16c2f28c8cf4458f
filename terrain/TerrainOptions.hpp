#pragma once
// What a planner reads from the DEM: the rover's footprint and its limits (docs/terrain.md).

namespace rovermap::terrain {

struct TerrainOptions {
  /// Write terrain.tif and terrain.png with the DEM (replay, serve, mosaic).
  bool enabled = true;
  /// Side of the square footprint every layer is computed over, centred on the cell [m]: the
  /// rover's size. At least two cells, at most the DEM.
  double footprint_m = 0.6;
  double max_slope_deg = 20.0;    ///< [deg] steepest plane the rover may stand on
  double max_step_m = 0.15;       ///< [m] largest height difference within the footprint
  double max_roughness_m = 0.05;  ///< [m] largest RMS residual of the footprint's plane
  /// Fraction of the footprint's cells that must hold a height, else the cell is unknown.
  double min_coverage = 0.5;
  /// A layer whose limit lies within this many of its σ of its value makes the cell uncertain
  /// (and traversability is computed from value + this many σ).
  double uncertainty_sigmas = 2.0;
  int tile_cells = 256;  ///< [cells] computed tile by tile (bounded memory), in parallel
};

}  // namespace rovermap::terrain
