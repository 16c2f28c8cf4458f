#pragma once
// The drift report of a run (docs/design.md §6): drift.csv (one row per frame), summary.json and
// drift.png, from the mapper's per-frame results.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "eval/EvalOptions.hpp"
#include "eval/TrajectoryMetrics.hpp"
#include "mapper/Mapper.hpp"
#include "service/OutputState.hpp"

namespace rovermap::mapper {

/// drift.csv: a header row, then per frame: index, timestamp, the increment correction (dx dy
/// dz m, droll dpitch dyaw deg), the cumulative correction (same six, `cum_` prefix), status,
/// fallback_reason, odometry_directions (space separated, e.g. "x y yaw"), iterations, inliers,
/// inlier_ratio, rms_m, time_ms; then matcher_status, conditioning, points, outliers_removed and
/// the quoted detail.
/// With `graph` (solved): then graph_dx_m … graph_dyaw_deg, the graph's correction of the
/// chained pose (T_chained⁻¹ · T_graph, in the chained body frame), and `gnss`: used, rejected
/// or none; without one the columns are 0 and none.
std::string DriftCsv(const std::vector<FrameResult>& results, const GraphOutcome* graph = nullptr);

/// Registered and dead-reckoning trajectories against the ground truth, over the frames that
/// carry a true pose (all of them when the sequence has groundtruth.tum).
struct DriftMetrics {
  eval::TrajectoryMetrics registered;
  eval::TrajectoryMetrics odometry;
};
/// nullopt when fewer than two frames carry a true pose. `poses`, when given (one per result),
/// is the trajectory judged instead of the chained one (the pose graph's). Never throws.
std::optional<DriftMetrics> EvaluateDrift(const std::vector<FrameResult>& results,
                                          const eval::EvalOptions& options,
                                          const std::vector<Eigen::Isometry3d>* poses = nullptr);

/// summary.json's `graph`: fixes given, matched to frames, used and rejected, the solver's
/// rounds, iterations and time, and why it kept the chain when it did.
nlohmann::json GraphJson(const GraphOutcome& graph);

/// What the caller measured around the mapper.
struct RunInfo {
  std::string sequence;                             ///< input (for the record)
  double wall_ms = 0.0;                             ///< whole run, reading included
  double write_ms = 0.0;                            ///< writing the outputs before summary.json
  double peak_rss_mb = 0.0;                         ///< PeakRssMb() at the end
  nlohmann::json extra = nlohmann::json::object();  ///< more top-level keys (serve's queue)
};

/// The frames' own processing time [ms]: reading and ProcessFrame, summed. RunInfo::wall_ms for
/// a caller that idles between frames (the daemon, a Python loop).
double ProcessingMs(const std::vector<FrameResult>& results);

/// summary.json: frames, registered, partial, fallbacks (whole increment from dead reckoning,
/// bad frames included), bad_frames, distance_m, final_correction, timing (per stage: total and
/// per-frame median, ms), frames_per_second, peak_rss_mb, dem and octomap figures, and `metrics`
/// {registered, odometry} (docs/design.md §8 keys) when `drift` is given.
nlohmann::json Summary(const OutputState& state, const RunInfo& run,
                       const std::optional<DriftMetrics>& drift);

/// drift.png: the increment correction per frame (translation, rotation; fallbacks marked) and
/// the drift against distance travelled: position error against the ground truth (registered
/// and dead reckoning, aligned at the first pose) when `drift` is given, else the cumulative
/// correction. Written atomically. @throw io::IoError naming `path`.
/// With a solved pose graph (`graph`, `drift` judging its trajectory): the chained trajectory's
/// error too (`chained`), no 2σ line (the chain's σ is not the graph's), and ticks where the
/// frames' GNSS fixes were used (green) or rejected (magenta).
void WriteDriftPlot(const std::filesystem::path& path, const std::vector<FrameResult>& results,
                    const std::optional<DriftMetrics>& drift, const GraphOutcome* graph = nullptr,
                    const std::optional<DriftMetrics>& chained = std::nullopt);

/// Peak resident set size of this process [MB] (getrusage).
double PeakRssMb();

}  // namespace rovermap::mapper
