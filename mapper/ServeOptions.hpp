#pragma once
// Options of the daemon, `rovermap serve` (config keys under `serve.`). Plain struct.

namespace rovermap::mapper {

struct ServeOptions {
  /// Watch the inbox with inotify; false (or a file system without it): look every
  /// poll_interval_s.
  bool use_inotify = true;
  /// [s] between looks at the inbox when polling (and the longest wait with inotify).
  double poll_interval_s = 0.5;
  /// [s] a missing frame index holds the queue this long once a later frame is complete; then
  /// it is declared missing and the daemon goes on.
  double gap_timeout_s = 30.0;
  /// [frames] publish the outputs (DESIGN §6) after this many frames, and on exit.
  int publish_every = 10;
  /// [frames] snapshot the state after this many frames (each frame is journalled anyway, so a
  /// restart never registers a frame twice; a larger value writes less, and a restart re-fuses
  /// up to this many frames).
  int checkpoint_every = 10;
  /// [s] while frames are queued, status.json is rewritten at most this often (0: after every
  /// frame); it is always rewritten when the queue runs dry, at a publication and on exit.
  double status_interval_s = 1.0;
};

}  // namespace rovermap::mapper
