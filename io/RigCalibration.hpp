#pragma once
// How well the sensor's calibration is known (sequence.yaml `sensor.calibration_sigma`,
// docs/sequences.md): a plain struct, filled by io/SequenceYaml, read by the mapper.

namespace rovermap::io {

/// σ of the rig's calibration error that every frame repeats: the sensor's mounting rotation on
/// the body (about each axis) and the scale of its depths (a stereo baseline's relative error, a
/// lidar's range scale). A field calibration leaves a few tenths of a degree and a few tenths of
/// a percent; 0 declares an exact rig.
struct RigCalibrationSigma {
  double rotation_deg = 0.0;  ///< [deg] about each axis, >= 0
  double scale = 0.0;         ///< [ratio] of every depth, >= 0
};

}  // namespace rovermap::io
