#pragma once
// Internal to mosaic/: co-registration of one input onto the mosaic of the inputs before it.

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "mosaic/Mosaic.hpp"
#include "mosaic/Warp.hpp"
#include "registration/Directions.hpp"

namespace rovermap::mosaic::detail {

/// Registers inputs[index] (its cells on the output grid as points, with their σ) onto the
/// fused inputs[0..index) over its footprint, with the project's matcher (point-to-plane,
/// weighted by the cells' covariances), coarse to fine, and sets its correction when the
/// correction found passes JudgeCorrection; otherwise the input keeps the correction it had.
/// Holds the whole footprint in memory. Never throws on data: the report says what happened.
/// @throw io::IoError naming a file if GDAL fails to read it.
InputReport Coregister(std::vector<Input>& inputs, std::size_t index, const OutputGrid& grid,
                       const MosaicOptions& options,
                       const registration::RegistrationOptions& registration);

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Directions (registration::Direction) of a correction here are in the output CRS about the
// overlap's centre: rotations about x (east: "roll"), y (north: "pitch") and z ("yaw").

/// The horizontal placement co-registration exists to correct.
constexpr unsigned kHorizontal = registration::kYaw | registration::kX | registration::kY;

/// What a match's information (RegistrationResult: left perturbation [r (rad), t (m)]) says.
struct Constraint {
  /// Keeps the constrained part of a step δ = [r, t]: the eigen-directions of the information
  /// (rotations scaled by extent_m) with at least min_information × the largest eigenvalue.
  Matrix6d projector = Matrix6d::Zero();
  unsigned unconstrained = 0x3fu;  ///< registration::Direction bits of the weak directions
  double conditioning = 0.0;       ///< smallest / largest eigenvalue, scaled
};

/// The constrained directions of `information`; a zero or non-finite one constrains none.
Constraint ConstrainDirections(const Matrix6d& information, double extent_m,
                               double min_information);

/// Why a correction must not be applied ("" when it may be): `unconstrained` holds x, y or
/// yaw, the RMS height difference over the overlap does not fall below options.min_improvement
/// × its value before, or the correction exceeds options.max_correction_m / _deg.
std::string JudgeCorrection(unsigned unconstrained, double rms_before_m, double rms_after_m,
                            double shift_m, double rotation_deg, const MosaicOptions& options);

}  // namespace rovermap::mosaic::detail
