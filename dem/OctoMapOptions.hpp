#pragma once
// Options of dem::OctoMapFusion, apart so that config/ can hold them without OctoMap's headers.

namespace rovermap::dem {

/// Options of the OctoMap; plain values, in-class defaults.
struct OctoMapOptions {
  bool enabled = true;        ///< false: InsertFrame does nothing and tree() is nullptr
  double resolution_m = 0.1;  ///< [m] leaf edge, > 0
  double max_range_m = 20.0;  ///< [m] rays longer than this are truncated; 0 = unlimited
  double prob_hit = 0.7;      ///< [probability] occupancy update of an endpoint, in (0.5, 1)
  double prob_miss = 0.4;     ///< [probability] update of a traversed cell, in (0, 0.5)
  bool write_ot = false;      ///< also write map.ot (full probabilities) beside map.bt
};

/// @throw std::invalid_argument naming the field if a value is out of range.
void Validate(const OctoMapOptions& options);

}  // namespace rovermap::dem
