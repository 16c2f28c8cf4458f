#pragma once
// Internal to mosaic/: co-registration of one input onto the mosaic of the inputs before it.

#include <cstddef>
#include <vector>

#include "mosaic/Mosaic.hpp"
#include "mosaic/Warp.hpp"

namespace rovermap::mosaic::detail {

/// Registers inputs[index] (its cells on the output grid as points, with their σ) onto the
/// fused inputs[0..index) over its footprint, with the project's matcher (point-to-plane,
/// weighted by the cells' covariances), and sets its correction when the matcher succeeds.
/// Holds the whole footprint in memory. Never throws on data: the report says what happened.
/// @throw io::IoError naming a file if GDAL fails to read it.
InputReport Coregister(std::vector<Input>& inputs, std::size_t index, const OutputGrid& grid,
                       const MosaicOptions& options,
                       const registration::RegistrationOptions& registration);

}  // namespace rovermap::mosaic::detail
