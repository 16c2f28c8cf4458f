#pragma once
// The pose graph of a replay (docs/graph.md): the frames' chained increments with their
// covariances, GNSS fixes as absolute position factors (graph/PoseGraph), and the maps fused
// again from the optimised poses.

#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "graph/PoseGraph.hpp"
#include "io/FrameSource.hpp"
#include "io/Georeference.hpp"
#include "io/Gnss.hpp"
#include "mapper/GraphOptions.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ReferenceMatch.hpp"
#include "mapper/Revisit.hpp"
#include "mapper/SystematicRates.hpp"

namespace rovermap::mapper {

/// What the graph made of a run.
struct GraphOutcome {
  graph::PoseGraphResult solution;  ///< T_world_body per frame (the chain's when not solved)
  std::size_t fixes = 0;            ///< in the recording
  std::size_t unmatched = 0;        ///< no frame within GraphOptions::gnss_max_time_offset_s
  /// Per frame: its fixes' indices into solution.fix_used (empty: none).
  std::vector<std::vector<std::size_t>> frame_fixes;
  std::size_t frames_refused = 0;  ///< frames that could not be read again for the re-fusion
  /// How the DEM and the OctoMap follow the solved graph (summary.json `graph.maps`): fused
  /// again from its poses (replay), moved with it (serve: mapper/DemWarp here, and the OctoMap's
  /// bytes moved on its thread, which the writer reports), or both the chain's.
  enum class Maps { kChain, kFusedAgain, kDemMoved, kMapsMoved };
  Maps maps = Maps::kChain;
  /// A windowed solve (a daemon's) made whole because a revisit found since the last solve
  /// reaches this frame, before the window: the earlier frame of that loop.
  std::optional<std::size_t> whole_for_loop_from;
  /// Every match against the reference DEM, refused ones too (ReferenceTrack), in order.
  std::vector<ReferenceMatch> reference_matches;
  /// Per entry of reference_matches: its index into solution.pose_used, or −1 if refused.
  std::vector<long> reference_factor;
  /// A reference DEM was given but could not be used at all: why (else empty).
  std::string reference_unusable;
  /// Every look that found earlier ground (RevisitTrack), refused ones too, in order.
  std::vector<RevisitMatch> revisits;
  /// Per entry of revisits: its index into solution.loop_used, or −1 if refused.
  std::vector<long> revisit_factor;
};

/// What became of frame `frame`'s GNSS fixes: kUsed if the solved graph used one of them,
/// kRejected if it has fixes and none was used, kNone without a fix. Never throws.
enum class FrameGnss { kNone, kUsed, kRejected };
FrameGnss GnssOfFrame(const GraphOutcome& graph, std::size_t frame);

/// What became of a reference match held by frame `frame`: kUsed by the solved graph,
/// kRejected by its gate (or the graph was not solved), kRefused by the match's own checks,
/// kNone when no match is on this frame. Never throws.
enum class FrameReference { kNone, kUsed, kRejected, kRefused };
FrameReference ReferenceOfFrame(const GraphOutcome& graph, std::size_t frame);
const char* ToString(FrameReference outcome);

/// The same for a revisit whose later frame is `frame`. Never throws.
FrameReference RevisitOfFrame(const GraphOutcome& graph, std::size_t frame);

/// The pose and covariance the outputs report for `result` (drift.csv's σ, the DEM's
/// re-fusion, summary.json's pose_uncertainty): the graph's pose and marginal covariance when
/// it was solved with them, else the chain's step. Never throws.
ChainStep ReportedStep(const FrameResult& result, const GraphOutcome* graph);

/// The relative factor of every frame k >= 1 (frame k−1 to k): the chained increment, with the
/// registration's covariance plus the per-step σ of the rig's systematic error (`systematic`,
/// SystematicRatesOf; a white-noise stand-in for an error the graph does not model as
/// repeating), or dead reckoning's noise (mapper.odometry_noise_*) where dead reckoning
/// carried the step. Never throws.
std::vector<graph::RelativeFactor> RelativeFactors(const std::vector<FrameResult>& results,
                                                   const SystematicRates& systematic,
                                                   const MapperOptions& options);

/// Solves the graph of `results` with `fixes` (geodetic, placed in the world frame by
/// `georeference`) and the accepted `matches` against a reference DEM (pose factors; the
/// refused ones are kept in the outcome for the report), and the accepted `revisits` (loop
/// factors). nullopt when the graph is off, or there are fewer fixes than
/// GraphOptions::min_gnss_fixes (a bag's single origin fix is no track) and no match or
/// revisit at all. A reference match holds position and heading, a revisit the two passes
/// together: one is enough. With `previous` (an earlier solve of the same run, solved with its
/// covariance) and `window_frames` > 0, the frames before the last `window_frames` are held
/// where `previous` put them, with its covariance, and only the window is solved (a daemon's
/// bounded solve; graph::PoseGraphOptions::first_free_node).
/// @throw std::invalid_argument if the options are invalid.
std::optional<GraphOutcome> SolveGraph(
    const std::vector<FrameResult>& results, const SystematicRates& systematic,
    const std::vector<io::GnssFix>& fixes, const std::vector<ReferenceMatch>& matches,
    const std::vector<RevisitMatch>& revisits, const io::Georeference& georeference,
    const GraphOptions& options, const MapperOptions& mapper_options,
    const GraphOutcome* previous = nullptr, std::size_t window_frames = 0);

/// Empties `mapper`'s DEM and OctoMap and fuses every frame it fused before again, read anew
/// from `source` (random access), at `T_world_body` (one per result) with `covariance` (the
/// graph's marginals; the chain's where it has none for a frame). `progress(k, n)` after each
/// frame. @return frames that could not be read again (left out of the maps). Never throws on
/// data.
std::size_t RefuseFrames(const io::FrameSource& source, Mapper* mapper,
                         const std::vector<Eigen::Isometry3d>& T_world_body,
                         const std::vector<graph::Matrix6d>& covariance,
                         const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace rovermap::mapper
