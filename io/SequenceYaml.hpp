#pragma once
// sequence.yaml (docs/design.md §4) read into a plain struct, which io/Sequence turns into the
// sequence's typed description and checks against the other files. Here, beside the other input
// formats, so that io needs nothing from config/ (the layer above it).

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "io/CameraModel.hpp"
#include "io/RigCalibration.hpp"

namespace rovermap::io {

/// Largest image side and pixel count: OpenCV's default imread limits, so a bigger image
/// could never be read back (sequence.yaml's camera and `sim.image_*` obey them).
constexpr int kMaxImageSide = 1 << 20;
constexpr long long kMaxImagePixels = 1LL << 30;

/// The keys of sequence.yaml as written (angles in degrees, lengths in metres), after range
/// checks on each value. Exactly one of `rotation_rpy_deg` and `quaternion_xyzw` is set.
struct SequenceYaml {
  std::string sensor_type;                                ///< "stereo" or "cloud"
  std::optional<CameraModel> camera;                      ///< required for stereo
  std::array<double, 3> translation{};                    ///< T_body_sensor translation [m]
  std::optional<std::array<double, 3>> rotation_rpy_deg;  ///< R = Rz(y)·Ry(p)·Rx(r) [deg]
  std::optional<std::array<double, 4>> quaternion_xyzw;   ///< unit quaternion x y z w
  std::optional<RigCalibrationSigma> calibration_sigma;   ///< sensor.calibration_sigma
  double latitude_deg = 0.0;                              ///< origin, [-90, 90]
  double longitude_deg = 0.0;                             ///< origin, [-180, 180]
  double altitude_m = 0.0;                                ///< origin
  double frame_rate_hz = 0.0;                             ///< > 0
  std::string body = "earth";                             ///< earth|moon|mars
};

/// Reads and checks `path` (a sequence.yaml).
/// @throw IoError "FILE:LINE: KEY: reason" if the file is missing or not YAML, a required
///        key is missing, a key is unknown (docs/design.md §4: unknown keys are an error), a
///        value has the wrong type or is out of range (non-positive focal length, baseline, size
///        or frame rate; principal point outside the image; latitude/longitude out of range; a
///        quaternion that is not unit length within 1e-3; both or neither of rotation_rpy_deg
///        and quaternion; a calibration_sigma without both of its keys, or one negative or above
///        its bound: rotation_deg 10, scale 0.2), or a stereo sequence has no camera.
SequenceYaml ReadSequenceYaml(const std::filesystem::path& path);

/// ReadSequenceYaml on text already read; `path` only names the file in messages.
/// @throw IoError as ReadSequenceYaml.
SequenceYaml ParseSequenceYaml(std::string_view text, const std::filesystem::path& path);

}  // namespace rovermap::io
