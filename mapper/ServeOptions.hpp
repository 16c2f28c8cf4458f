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
  /// [frames] a ready frame numbered more than this beyond the next one expected is rejected as
  /// misnumbered, instead of every index between being declared missing.
  int max_gap_frames = 10000;
  /// [frames] publish the outputs (docs/design.md §6) after this many frames, when the queue
  /// runs dry with frames done since the last publication, and on exit.
  int publish_every = 10;
  /// [fraction] while frames are queued, the largest share of the frames' processing time the
  /// publications may take (handing the state over on the daemon's thread, and writing it on
  /// the publisher's, which shares the cores with the next frames): a publication grows with
  /// the map, so one that is due waits until the frames since the last took 1/publish_share
  /// times as long as that one did; 0 = a publication every publish_every. A queue that runs
  /// dry is published at once whatever this says.
  double publish_share = 0.05;
  /// [frames] a publication is never put off longer than this many frames.
  int publish_max_every = 100;
  /// [frames] the pose graph solved at each publication over this many last frames, the
  /// earlier ones held where the last solve put them (bounded time per publication); 0 =
  /// every frame each time.
  int graph_window_frames = 200;
  /// [frames] snapshot the state after this many frames (each frame is journalled anyway, so a
  /// restart never registers a frame twice; a larger value writes less, and a restart re-fuses
  /// up to this many frames).
  int checkpoint_every = 10;
  /// [fraction] the largest share of the frames' processing time snapshots may take: a snapshot
  /// grows with the map, so one that is due waits until the frames since the last took
  /// 1/checkpoint_share times as long as that one did; 0 = a snapshot every checkpoint_every.
  /// With publish_share, the daemon's writing through a backlog stays within a tenth of the
  /// frames' time, the margin serve is held to against replay (docs/serve.md, checkpoints).
  double checkpoint_share = 0.05;
  /// [frames] a snapshot is never put off longer than this many frames (a restart re-fuses at
  /// most this many).
  int checkpoint_max_every = 100;
  /// [s] while frames are queued, status.json is rewritten at most this often (0: after every
  /// frame); it is always rewritten when the queue runs dry, at a publication and on exit.
  double status_interval_s = 1.0;
};

/// Whether a periodic write is due after `frames` frames that took `frames_ms` [ms] since the
/// last one, which took `last_ms` [ms] (0 before the first): every `every` frames at least,
/// then only once the frames took 1/`share` times as long as the last write (`share` 0: no
/// wait), and never later than `max_every` frames.
inline bool ShareDue(int frames, double frames_ms, double last_ms, int every, double share,
                     int max_every) {
  if (frames < every) return false;
  return share <= 0.0 || frames >= max_every || last_ms <= share * frames_ms;
}

/// A snapshot (checkpoint_every, checkpoint_share, checkpoint_max_every).
inline bool SnapshotDue(const ServeOptions& o, int frames, double frames_ms,
                        double last_snapshot_ms) {
  return ShareDue(frames, frames_ms, last_snapshot_ms, o.checkpoint_every, o.checkpoint_share,
                  o.checkpoint_max_every);
}

/// A publication while frames are queued (publish_every, publish_share, publish_max_every).
inline bool PublicationDue(const ServeOptions& o, int frames, double frames_ms,
                           double last_publication_ms) {
  return ShareDue(frames, frames_ms, last_publication_ms, o.publish_every, o.publish_share,
                  o.publish_max_every);
}

}  // namespace rovermap::mapper
