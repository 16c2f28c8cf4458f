#pragma once
// Options of the matches of the rover's DEM against a reference DEM (docs/graph.md,
// `replay --reference-dem FILE`); the `reference.` keys.

namespace rovermap::mapper {

struct ReferenceOptions {
  /// [m] path between two matches; > 0.
  double every_m = 20.0;
  /// [m] the recent path whose DEM is matched (its cells first seen along it); > 0.
  double window_m = 40.0;
  /// Band 2 of the file holds the heights' σ when it has one; false: sigma_m everywhere.
  bool sigma_band = true;
  /// [m] σ of the reference's heights where no band gives it; > 0.
  double sigma_m = 0.5;
  /// The reference's vertical datum is the sequence's: a match also fixes the height.
  bool vertical_trusted = false;
  /// [m] σ per axis of the reference's horizontal placement in the world (its georeferencing:
  /// an orbital DTM's tie to its control). Shared by every match, it bounds how well the
  /// matches place the rover in the world, however sharp each one is; > 0.
  double horizontal_sigma_m = 1.0;
  /// A reference DEM that cannot be used (unreadable, another body, no coverage) stops the
  /// run (exit 1) instead of being reported and left out.
  bool required = false;
  /// [m] horizontal search about the last match's correction (the first: about the chain);
  /// starts every 1.5 posts within it; >= 0.
  double search_m = 3.0;
  /// [deg] heading search about it (starts at −, 0, +); >= 0.
  double search_yaw_deg = 2.0;
  /// [ratio] x, y and heading must each hold this many times the information the heights'
  /// noise alone gives on featureless ground; below it the match is refused as
  /// ill-conditioned (a plain, ripples of one direction). The match is weighed by what it
  /// holds beyond that noise; >= 1.
  double min_relief_ratio = 2.0;
  /// [ratio] another solution at least a post away whose RMS height difference is within this
  /// many times the best one's: refused as ambiguous (a periodic dune field); >= 1.
  double ambiguity_ratio = 1.2;
  /// [m] a match whose σ of x or y exceeds this is refused; > 0.
  double max_sigma_m = 1.0;
  /// [deg] a match whose σ of heading exceeds this is refused; > 0.
  double max_sigma_deg = 1.0;
  /// [ratio] the match's covariance × this (neighbouring posts share their errors); >= 1.
  double covariance_scale = 4.0;
  /// [count] fewer of the rover's cells (at the reference's posts) with a reference height
  /// under them: no match; >= 10.
  int min_posts = 50;
  /// [m] the rover's posts whose height σ (from its points' variances) exceeds this are left
  /// out: far stereo ground is metres off and would outweigh the near; > 0.
  double max_post_sigma_m = 0.2;
};

/// Revisits (docs/graph.md): the rover's recent ground matched onto its own earlier ground, a
/// loop factor for the graph; the `revisit.` keys. The match's checks (relief, ambiguity, σ,
/// posts, covariance scale) are reference.*'s.
struct RevisitOptions {
  /// Look for revisits in replay.
  bool enabled = true;
  /// [m] path between two looks (each saves the window's ground for later ones too); > 0.
  double every_m = 20.0;
  /// [m] the recent path whose ground is matched; > 0.
  double window_m = 40.0;
  /// [m] post spacing of the ground matched; > 0.
  double post_m = 0.5;
  /// [m] path between the two passes, at least: nearer ground is the frame-to-frame chain's; > 0.
  double min_gap_m = 100.0;
  /// [m] horizontal search about the chain's placement (the chain drifts between the passes);
  /// >= 0.
  double search_m = 6.0;
  /// [deg] heading search about it; >= 0.
  double search_yaw_deg = 3.0;
  /// [fraction] of the recent posts over the earlier ground, at least (a way back 4 m beside the
  /// way out shares about a quarter of its posts); in (0, 1].
  double min_overlap = 0.15;
  /// [m] posts whose height σ (from the points' variances) exceeds this are left out; > 0.
  double max_post_sigma_m = 0.1;
};

}  // namespace rovermap::mapper
