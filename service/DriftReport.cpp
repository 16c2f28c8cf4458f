#include "service/DriftReport.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "core/Units.hpp"
#include "eval/PlotPrimitives.hpp"
#include "io/OctoMapIo.hpp"
#include "mapper/Degeneracy.hpp"
#include "mapper/PoseUncertainty.hpp"

namespace rovermap::mapper {
namespace {

using core::kRadToDeg;

nlohmann::json Number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

double Median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = values.begin() + static_cast<long>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) out += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

void AppendComponents(std::ostringstream& s, const Eigen::Isometry3d& T) {
  const TransformComponents c = CorrectionComponents(T);
  s << ',' << c.dx_m << ',' << c.dy_m << ',' << c.dz_m << ',' << c.droll_deg << ',' << c.dpitch_deg
    << ',' << c.dyaw_deg;
}

nlohmann::json CorrectionJson(const Eigen::Isometry3d& T) {
  const TransformComponents c = CorrectionComponents(T);
  return {{"translation_m", T.translation().norm()},
          {"rotation_deg", Eigen::AngleAxisd(T.linear()).angle() * kRadToDeg},
          {"dx_m", c.dx_m},
          {"dy_m", c.dy_m},
          {"dz_m", c.dz_m},
          {"droll_deg", c.droll_deg},
          {"dpitch_deg", c.dpitch_deg},
          {"dyaw_deg", c.dyaw_deg}};
}

// Dead reckoning's estimated bias per frame after the last frame (BlendIncrement).
nlohmann::json OdometryBiasJson(const std::vector<FrameResult>& results) {
  const Vector6d b = results.empty() ? Vector6d::Zero() : results.back().odometry_bias.bias;
  return {{"droll_deg", b(0) * kRadToDeg},
          {"dpitch_deg", b(1) * kRadToDeg},
          {"dyaw_deg", b(2) * kRadToDeg},
          {"dx_m", b(3)},
          {"dy_m", b(4)},
          {"dz_m", b(5)}};
}

// Total and median over the frames of one stage.
nlohmann::json StageJson(const std::vector<FrameResult>& results,
                         const std::function<double(const StageTimes&)>& stage) {
  std::vector<double> values;
  double total = 0.0;
  for (const FrameResult& r : results) {
    values.push_back(stage(r.time));
    total += values.back();
  }
  return {{"total_ms", total}, {"median_ms", Number(Median(values))}};
}

}  // namespace

std::string DriftCsv(const std::vector<FrameResult>& results, const GraphOutcome* graph) {
  std::ostringstream s;
  s << "index,timestamp,dx_m,dy_m,dz_m,droll_deg,dpitch_deg,dyaw_deg,"
       "cum_dx_m,cum_dy_m,cum_dz_m,cum_droll_deg,cum_dpitch_deg,cum_dyaw_deg,"
       "status,fallback_reason,odometry_directions,iterations,inliers,inlier_ratio,rms_m,time_ms,"
       "matcher_status,conditioning,points,outliers_removed,detail,"
       "sigma_x_m,sigma_y_m,sigma_z_m,sigma_roll_deg,sigma_pitch_deg,sigma_yaw_deg,image_check,"
       "graph_dx_m,graph_dy_m,graph_dz_m,graph_droll_deg,graph_dpitch_deg,graph_dyaw_deg,gnss,"
       "reference,revisit\n";
  s << std::setprecision(9);
  for (const FrameResult& r : results) {
    s << r.index << ',' << std::fixed << std::setprecision(6) << r.timestamp << std::defaultfloat
      << std::setprecision(9);
    AppendComponents(s, r.step.increment_correction);
    AppendComponents(s, r.step.cumulative_correction);
    s << ',' << ToString(r.status) << ',' << ToString(r.fallback_reason) << ','
      << DirectionNames(r.odometry_directions) << ',' << r.iterations << ',' << r.inliers << ','
      << r.inlier_ratio << ',' << r.rms_m << ',' << r.time.total_ms << ',' << r.matcher_status
      << ',' << r.conditioning << ',' << r.points << ',' << r.outliers_removed << ','
      << Quoted(r.detail);
    const PoseSigmas sd = SigmasOf(ReportedStep(r, graph));
    s << ',' << sd.x_m << ',' << sd.y_m << ',' << sd.z_m << ',' << sd.roll_deg << ','
      << sd.pitch_deg << ',' << sd.yaw_deg << ',' << ToString(r.image_check);
    const bool solved =
        graph != nullptr && graph->solution.solved && r.index < graph->solution.T_world_body.size();
    AppendComponents(s, solved
                            ? r.step.T_world_body.inverse() * graph->solution.T_world_body[r.index]
                            : Eigen::Isometry3d::Identity());
    const FrameGnss gnss = graph != nullptr ? GnssOfFrame(*graph, r.index) : FrameGnss::kNone;
    s << ','
      << (gnss == FrameGnss::kUsed       ? "used"
          : gnss == FrameGnss::kRejected ? "rejected"
                                         : "none")
      << ','
      << ToString(graph != nullptr ? ReferenceOfFrame(*graph, r.index) : FrameReference::kNone)
      << ',' << ToString(graph != nullptr ? RevisitOfFrame(*graph, r.index) : FrameReference::kNone)
      << '\n';
  }
  return s.str();
}

std::optional<DriftMetrics> EvaluateDrift(const std::vector<FrameResult>& results,
                                          const eval::EvalOptions& options,
                                          const std::vector<Eigen::Isometry3d>* poses) {
  std::vector<Eigen::Isometry3d> registered, odometry, truth;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const FrameResult& r = results[k];
    if (!r.T_world_body_truth) continue;
    registered.push_back(poses != nullptr && k < poses->size() ? (*poses)[k] : r.step.T_world_body);
    odometry.push_back(r.step.T_world_body_odom);
    truth.push_back(*r.T_world_body_truth);
  }
  if (truth.size() < 2) return std::nullopt;
  return DriftMetrics{eval::EvaluateAssociated(registered, truth, options),
                      eval::EvaluateAssociated(odometry, truth, options)};
}

nlohmann::json Summary(const OutputState& state, const RunInfo& run,
                       const std::optional<DriftMetrics>& drift) {
  const std::vector<FrameResult>& results = state.results;
  std::size_t registered = 0, partial = 0, fallbacks = 0, bad = 0, outliers = 0, nonfinite = 0;
  std::size_t cleared = 0;
  std::map<std::string, std::size_t> image_check;
  for (const FrameResult& r : results) {
    if (r.image_check != mapper::ImageCheckOutcome::kNone) ++image_check[ToString(r.image_check)];
    if (r.status == FrameStatus::kRegistered || r.status == FrameStatus::kPartial) ++registered;
    if (r.status == FrameStatus::kPartial) ++partial;
    if (r.status == FrameStatus::kFallback || r.status == FrameStatus::kBadFrame) ++fallbacks;
    if (r.status == FrameStatus::kBadFrame) ++bad;
    outliers += r.outliers_removed;
    cleared += r.dem.cells_cleared;
    nonfinite += r.dropped_nonfinite;
  }
  nlohmann::json timing = {
      {"load", StageJson(results, [](const StageTimes& t) { return t.load_ms; })},
      {"stereo", StageJson(results, [](const StageTimes& t) { return t.stereo_ms; })},
      {"prepare", StageJson(results, [](const StageTimes& t) { return t.prepare_ms; })},
      {"register", StageJson(results, [](const StageTimes& t) { return t.register_ms; })},
      {"fuse_dem", StageJson(results, [](const StageTimes& t) { return t.fuse_dem_ms; })},
      {"fuse_octomap", StageJson(results, [](const StageTimes& t) { return t.fuse_octomap_ms; })},
      {"frame", StageJson(results, [](const StageTimes& t) { return t.total_ms + t.load_ms; })},
      {"write", {{"total_ms", run.write_ms}}},
      {"wall_ms", run.wall_ms}};
  nlohmann::json summary = {
      {"sequence", run.sequence},
      {"frames", results.size()},
      {"registered", registered},
      {"partial", partial},
      {"fallbacks", fallbacks},
      {"bad_frames", bad},
      {"dropped_nonfinite", nonfinite},
      {"distance_m", state.distance_m},
      {"final_correction", CorrectionJson(state.final_correction)},
      {"odometry_bias", OdometryBiasJson(results)},
      {"image_check",
       {{"used", image_check["used"]},
        {"disagreed", image_check["disagreed"]},
        {"failed", image_check["failed"]}}},
      {"timing", timing},
      {"frames_per_second",
       run.wall_ms > 0.0 ? 1000.0 * static_cast<double>(results.size()) / run.wall_ms : 0.0},
      {"peak_rss_mb", run.peak_rss_mb},
      {"dem",
       {{"cells", state.dem.valid_cells},
        {"cells_reached", state.dem_cells_reached},
        {"tiles", state.dem_tiles},
        {"cell_size_m", state.dem.cell_size_m},
        {"outliers_removed", outliers},
        {"cells_cleared", cleared},
        {"rig_calibration_sigma",
         {{"rotation_deg", state.rig_calibration.rotation_deg},
          {"scale", state.rig_calibration.scale},
          {"source", state.rig_calibration_stated ? "sequence.yaml" : "assumed"}}}}},
  };
  if (state.stereo_num_disparities) {
    summary["stereo"] = {{"num_disparities", *state.stereo_num_disparities}};
  }
  if (const auto& tree = state.octomap.get()) {
    summary["octomap"] = {{"leaves", io::CountSerialisedLeaves(tree->bt, /*binary=*/true)},
                          {"resolution_m", state.octomap_resolution_m}};
  }
  if (drift) {
    summary["metrics"] = {{"registered", eval::ToJson(drift->registered)},
                          {"odometry", eval::ToJson(drift->odometry)}};
  }
  // The uncertainty of the trajectory written: the graph's when it states one.
  const GraphOutcome* graph = state.graph ? &*state.graph : nullptr;
  std::optional<CalibrationCheck> check;
  if (graph != nullptr && graph->solution.solved &&
      graph->solution.covariance.size() == results.size()) {
    std::vector<ChainStep> steps;
    for (const FrameResult& r : results) steps.push_back(ReportedStep(r, graph));
    check = CheckCalibration(results, steps, !graph->solution.covariance_given_first);
  } else {
    check = CheckCalibration(results);
  }
  if (check) {
    const Vector6d& a = check->axis_ratio;
    summary["pose_uncertainty"] = {{"frames", check->frames},
                                   {"within_2sigma", check->within_2sigma},
                                   {"nees_mean", Number(check->nees_mean)},
                                   {"nees_median", Number(check->nees_median)},
                                   {"nees_expected", 6},
                                   {"axis_error_ratio",
                                    {{"x", Number(a(0))},
                                     {"y", Number(a(1))},
                                     {"z", Number(a(2))},
                                     {"roll", Number(a(3))},
                                     {"pitch", Number(a(4))},
                                     {"yaw", Number(a(5))}}}};
  }
  for (const auto& [key, value] : run.extra.items()) summary[key] = value;
  return summary;
}

namespace {

// One match's figures, with what became of it: refused (its own checks), used or rejected (the
// graph's gate).
nlohmann::json MatchJson(const ReferenceMatch& m, const char* status) {
  return {{"frame", m.frame},
          {"first_frame", m.first_frame},
          {"last_frame", m.last_frame},
          {"status", status},
          {"reason", m.reason},
          {"posts", m.posts},
          {"rms_before_m", Number(m.rms_before_m)},
          {"rms_after_m", Number(m.rms_after_m)},
          {"sigma_x_m", Number(m.sigma_x_m)},
          {"sigma_y_m", Number(m.sigma_y_m)},
          {"sigma_yaw_deg", Number(m.sigma_yaw_deg)},
          {"relief_ratio", Number(m.relief_ratio)},
          {"starts", m.starts},
          {"ms", m.ms}};
}

const char* StatusOf(long factor, const std::vector<bool>& used) {
  if (factor < 0) return "refused";
  const auto f = static_cast<std::size_t>(factor);
  return f < used.size() && used[f] ? "used" : "rejected";
}

}  // namespace

nlohmann::json GraphJson(const GraphOutcome& graph) {
  const graph::PoseGraphResult& s = graph.solution;
  nlohmann::json matches = nlohmann::json::array();
  std::size_t refused = 0;
  for (std::size_t k = 0; k < graph.reference_matches.size(); ++k) {
    const long f = k < graph.reference_factor.size() ? graph.reference_factor[k] : -1;
    refused += f < 0 ? 1 : 0;
    matches.push_back(MatchJson(graph.reference_matches[k], StatusOf(f, s.pose_used)));
  }
  nlohmann::json revisits = nlohmann::json::array();
  std::size_t revisits_refused = 0;
  for (std::size_t k = 0; k < graph.revisits.size(); ++k) {
    const long f = k < graph.revisit_factor.size() ? graph.revisit_factor[k] : -1;
    revisits_refused += f < 0 ? 1 : 0;
    nlohmann::json j = MatchJson(graph.revisits[k].match, StatusOf(f, s.loop_used));
    j["earlier_frame"] = graph.revisits[k].from_frame;
    revisits.push_back(j);
  }
  return {{"solved", s.solved},
          {"reference_matches", graph.reference_matches.size()},
          {"reference_used", s.poses_used},
          {"reference_rejected", s.poses_rejected},
          {"reference_refused", refused},
          {"reference_unusable", graph.reference_unusable},
          {"reference_vertical_offset_m", s.z_offset_m},
          {"reference_horizontal_offset_m", {s.xy_offset_m.x(), s.xy_offset_m.y()}},
          {"covariance", s.covariance.empty()       ? s.covariance_message
                         : s.covariance_given_first ? "given the first frame"
                                                    : "against the world"},
          {"reference", matches},
          {"revisits", graph.revisits.size()},
          {"revisits_used", s.loops_used},
          {"revisits_rejected", s.loops_rejected},
          {"revisits_refused", revisits_refused},
          {"revisit", revisits},
          {"gnss_fixes", graph.fixes},
          {"gnss_unmatched", graph.unmatched},
          {"gnss_used", s.fixes_used},
          {"gnss_rejected", s.fixes_rejected},
          {"rounds", s.solves},
          {"iterations", s.iterations},
          {"solve_ms", s.solve_ms},
          {"frames_not_refused", graph.frames_refused},
          {"maps", graph.maps == GraphOutcome::Maps::kFusedAgain  ? "fused again"
                   : graph.maps == GraphOutcome::Maps::kDemMoved  ? "dem moved"
                   : graph.maps == GraphOutcome::Maps::kMapsMoved ? "dem and octomap moved"
                                                                  : "chain"},
          {"message", s.message}};
}

void WriteDriftPlot(const std::filesystem::path& path, const std::vector<FrameResult>& results,
                    const std::optional<DriftMetrics>& drift, const GraphOutcome* graph,
                    const std::optional<DriftMetrics>& chained) {
  const bool graph_solved = graph != nullptr && graph->solution.solved;
  // The σ line goes with the drift from the start: the chain's, or a graph's given its first
  // frame (loops alone); a graph held against the world states another uncertainty.
  const bool chain_sigma = !graph_solved || (graph->solution.covariance.size() == results.size() &&
                                             graph->solution.covariance_given_first);
  using namespace eval::plot;
  const cv::Scalar kRed(40, 40, 210);
  std::vector<double> index, dt, dr, fallback_index;
  for (const FrameResult& r : results) {
    index.push_back(static_cast<double>(r.index));
    dt.push_back(r.step.increment_correction.translation().norm());
    dr.push_back(Eigen::AngleAxisd(r.step.increment_correction.linear()).angle() * kRadToDeg);
    if (r.status == FrameStatus::kFallback || r.status == FrameStatus::kBadFrame)
      fallback_index.push_back(static_cast<double>(r.index));
  }
  const double last = index.empty() ? 1.0 : std::max(1.0, index.back());
  auto peak = [](const std::vector<double>& v) {
    double m = 1e-6;
    for (double x : v) m = std::max(m, x);
    return m * 1.1;
  };
  cv::Mat img(1180, 920, CV_8UC3, kWhite);
  cv::putText(img, "drift correction per frame and drift against distance travelled", {80, 25},
              kFont, 0.55, kBlack, 1, cv::LINE_AA);
  // Panels 1-2: what registration changed in each increment; red ticks = dead reckoning used.
  // The translation panel carries the two-line legend: its data stays below it.
  const cv::Rect translation_area(80, 60, 800, 250);
  const Axes translation{translation_area, 0.0, last, 0.0,
                         peak(dt) * LegendHeadroom(translation_area.height, 2)};
  const Axes rotation{cv::Rect(80, 400, 800, 250), 0.0, last, 0.0, peak(dr)};
  for (const auto& [axes, values, label] :
       {std::tuple{translation, dt, "increment correction, translation [m]"},
        std::tuple{rotation, dr, "increment correction, rotation [deg]"}}) {
    DrawAxes(img, axes, "frame", label);
    for (double f : fallback_index) {
      const cv::Point p = axes.Map(f, axes.y0);
      cv::line(img, p, p - cv::Point(0, 12), kRed, 2);
    }
    DrawLine(img, axes, index, values, Colour(1), 2);
  }
  DrawLegend(img,
             {{"registered increment vs dead reckoning", Colour(1)},
              {"dead reckoning used (fallback / bad frame)", kRed}},
             {translation.area.x + 15, translation.area.y + 20});

  // Panel 3: drift against distance, with the position uncertainty the chain states (2 √tr of
  // its position covariance: an error above it is one the covariance did not expect).
  std::vector<double> two_sigma;
  for (const FrameResult& r : results) {
    const PoseSigmas s = SigmasOf(ReportedStep(r, graph));  // drift.csv's σ columns
    two_sigma.push_back(2.0 * std::sqrt(s.x_m * s.x_m + s.y_m * s.y_m + s.z_m * s.z_m));
  }
  const std::string sigma_label = std::string(graph_solved ? "pose graph" : "registered") +
                                  ": 2 sigma it states (2 sqrt trace, position)";
  const cv::Scalar sigma_colour = Colour(2);
  std::vector<std::pair<std::string, cv::Scalar>> legend;
  const cv::Rect area(80, 740, 800, 360);
  if (drift && drift->registered.status == eval::MetricStatus::kOk &&
      drift->odometry.status == eval::MetricStatus::kOk) {
    const auto& reg = drift->registered;
    const auto& odo = drift->odometry;
    // One error per frame when every frame has ground truth; else no σ line.
    const bool with_sigma = chain_sigma && reg.distance_m.size() == two_sigma.size();
    const bool chained_ok =
        graph_solved && chained && chained->registered.status == eval::MetricStatus::kOk;
    const bool gnss_ticks = graph != nullptr && graph->fixes > 0;
    const bool reference_ticks = graph != nullptr && !graph->reference_matches.empty();
    const bool revisit_ticks = graph != nullptr && !graph->revisits.empty();
    const std::size_t legend_lines = 2 + (with_sigma ? 1 : 0) + (chained_ok ? 1 : 0) +
                                     (gnss_ticks ? 2 : 0) + (reference_ticks ? 2 : 0) +
                                     (revisit_ticks ? 1 : 0);
    const double y1 = std::max({peak(reg.ate_origin_error_m), peak(odo.ate_origin_error_m),
                                with_sigma ? peak(two_sigma) : 0.0,
                                chained_ok ? peak(chained->registered.ate_origin_error_m) : 0.0}) *
                      LegendHeadroom(area.height, legend_lines);
    const Axes axes{area, 0.0, std::max(reg.distance_m.back(), 1e-6), 0.0, y1};
    DrawAxes(img, axes, "distance travelled (ground truth) [m]",
             "position error against the ground truth, aligned at the first pose [m]");
    DrawLine(img, axes, odo.distance_m, odo.ate_origin_error_m, Colour(0), 2);
    if (with_sigma) DrawLine(img, axes, reg.distance_m, two_sigma, sigma_colour, 1);
    const bool with_chained =
        chained_ok && chained->registered.distance_m.size() == reg.distance_m.size();
    if (with_chained) {
      DrawLine(img, axes, reg.distance_m, chained->registered.ate_origin_error_m, Colour(4), 1);
    }
    DrawLine(img, axes, reg.distance_m, reg.ate_origin_error_m, Colour(1), 2);
    legend = {{"dead reckoning (ATE origin " + Format(odo.ate_origin_m.rmse) + " m)", Colour(0)},
              {std::string(graph_solved ? "pose graph" : "registered") + " (ATE origin " +
                   Format(reg.ate_origin_m.rmse) + " m)",
               Colour(1)}};
    if (with_chained) {
      legend.emplace_back(
          "frame to frame (ATE origin " + Format(chained->registered.ate_origin_m.rmse) + " m)",
          Colour(4));
    }
    if (with_sigma) legend.emplace_back(sigma_label, sigma_colour);
    // Where the GNSS fixes were: one tick per frame with a fix, at its distance.
    if (gnss_ticks && reg.distance_m.size() == results.size()) {
      const cv::Scalar used(60, 170, 60), rejected(200, 0, 200);
      for (std::size_t k = 0; k < results.size(); ++k) {
        const FrameGnss gnss = GnssOfFrame(*graph, k);
        if (gnss == FrameGnss::kNone) continue;
        const cv::Point p = axes.Map(reg.distance_m[k], axes.y0);
        cv::line(img, p, p - cv::Point(0, 10), gnss == FrameGnss::kUsed ? used : rejected, 2);
      }
      legend.emplace_back("GNSS fix used (tick)", used);
      legend.emplace_back("GNSS fix rejected (tick)", rejected);
    }
    // Where the reference DEM was matched: a taller tick on the frame the match holds.
    if (reference_ticks && reg.distance_m.size() == results.size()) {
      // Teal and brown (BGR): apart from the trajectories' blue and orange.
      const cv::Scalar used(150, 150, 0), refused(30, 80, 150);
      for (std::size_t k = 0; k < results.size(); ++k) {
        const FrameReference ref = ReferenceOfFrame(*graph, k);
        if (ref == FrameReference::kNone) continue;
        const cv::Point p = axes.Map(reg.distance_m[k], axes.y0);
        cv::line(img, p, p - cv::Point(0, 20), ref == FrameReference::kUsed ? used : refused, 2);
      }
      legend.emplace_back("reference DEM match used (tall tick)", used);
      legend.emplace_back("reference DEM match refused or rejected (tall tick)", refused);
    }
    // Where the rover matched its own earlier ground: a tallest tick, used or not.
    if (revisit_ticks && reg.distance_m.size() == results.size()) {
      const cv::Scalar colour(30, 30, 30);
      for (std::size_t k = 0; k < results.size(); ++k) {
        const FrameReference rv = RevisitOfFrame(*graph, k);
        if (rv == FrameReference::kNone) continue;
        const cv::Point p = axes.Map(reg.distance_m[k], axes.y0);
        cv::line(img, p, p - cv::Point(0, 30), colour, rv == FrameReference::kUsed ? 3 : 1);
      }
      legend.emplace_back("revisit: used (thick) or refused (thin), tallest tick", colour);
    }
  } else {
    std::vector<double> distance, correction;
    double travelled = 0.0;
    for (const FrameResult& r : results) {
      travelled += r.step.used_increment.translation().norm();
      distance.push_back(travelled);
      correction.push_back(r.step.cumulative_correction.translation().norm());
    }
    const Axes axes{area, 0.0, std::max(travelled, 1e-6), 0.0,
                    std::max(peak(correction), peak(two_sigma)) * LegendHeadroom(area.height, 2)};
    DrawAxes(img, axes, "distance travelled (registered) [m]",
             "cumulative correction of dead reckoning [m]");
    DrawLine(img, axes, distance, two_sigma, sigma_colour, 1);
    DrawLine(img, axes, distance, correction, Colour(1), 2);
    legend = {{"|registered - dead reckoning| (no ground truth)", Colour(1)},
              {sigma_label, sigma_colour}};
  }
  DrawLegend(img, legend, {area.x + 15, area.y + 20});
  WritePng(path, img);
}

double ProcessingMs(const std::vector<FrameResult>& results) {
  double ms = 0.0;
  for (const FrameResult& r : results) ms += r.time.load_ms + r.time.total_ms;
  return ms;
}

double PeakRssMb() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

}  // namespace rovermap::mapper
