#pragma once
// The camera of a sequence (docs/design.md §4). A plain struct: io/SequenceYaml fills it from
// sequence.yaml, io/Sequence hands it out.

namespace rovermap::io {

/// `camera:` of sequence.yaml: a rectified stereo pair (pinhole, shared intrinsics).
struct CameraModel {
  int width = 0;            ///< [px]
  int height = 0;           ///< [px]
  double fx = 0.0;          ///< [px]
  double fy = 0.0;          ///< [px]
  double cx = 0.0;          ///< [px]
  double cy = 0.0;          ///< [px]
  double baseline_m = 0.0;  ///< [m]
};

}  // namespace rovermap::io
