#include "mapper/GnssGraph.hpp"

#include <algorithm>
#include <cmath>

#include "io/IoError.hpp"
#include "mapper/FrameJudge.hpp"
#include "mapper/PoseUncertainty.hpp"

namespace rovermap::mapper {

FrameGnss GnssOfFrame(const GraphOutcome& graph, std::size_t frame) {
  if (frame >= graph.frame_fixes.size() || graph.frame_fixes[frame].empty())
    return FrameGnss::kNone;
  for (const std::size_t f : graph.frame_fixes[frame]) {
    if (graph.solution.solved && graph.solution.fix_used[f]) return FrameGnss::kUsed;
  }
  return FrameGnss::kRejected;
}

std::vector<graph::RelativeFactor> RelativeFactors(const std::vector<FrameResult>& results,
                                                   const SystematicRates& systematic,
                                                   const MapperOptions& o) {
  std::vector<graph::RelativeFactor> factors;
  for (std::size_t k = 1; k < results.size(); ++k) {
    const FrameResult& r = results[k];
    graph::RelativeFactor f;
    f.from = k - 1;
    f.to = k;
    f.T_from_to = results[k - 1].step.T_world_body.inverse() * r.step.T_world_body;
    const double length = f.T_from_to.translation().norm();
    const bool registered =
        (r.status == FrameStatus::kRegistered || r.status == FrameStatus::kPartial) &&
        !r.step.fallback && r.increment_covariance.allFinite() &&
        r.increment_covariance.diagonal().maxCoeff() > 0.0;
    if (registered) {
      f.covariance = r.increment_covariance;
      const double rot = systematic.rotation_rad_per_m * length;
      const double tra = systematic.translation_ratio * length;
      f.covariance.diagonal().head<3>().array() += rot * rot;
      f.covariance.diagonal().tail<3>().array() += tra * tra;
    } else {
      f.covariance = CovarianceOf(OdometryNoiseSigma(length, o));
    }
    f.covariance = 0.5 * (f.covariance + f.covariance.transpose()).eval();
    factors.push_back(f);
  }
  return factors;
}

namespace {

// Roll and pitch reach the graph only through the chain (its increments and the tilt priors,
// which restate the same increments frame by frame): their marginal there counts the chain's
// information many times over (KITTI with fixes: roll σ 0.17° where the error is 0.95° and the
// chain says 0.92°). Their rows and columns of `graph` are scaled up to the chain's σ,
// correlations kept.
void KeepTheChainsTilt(const graph::Matrix6d& chain, graph::Matrix6d* graph) {
  graph::Matrix6d S = graph::Matrix6d::Identity();
  for (int axis = 0; axis < 2; ++axis) {
    const double graph_var = (*graph)(axis, axis);
    if (graph_var > 0.0 && chain(axis, axis) > graph_var)
      S(axis, axis) = std::sqrt(chain(axis, axis) / graph_var);
  }
  *graph = S * *graph * S;
}

}  // namespace

std::optional<GraphOutcome> SolveGraph(
    const std::vector<FrameResult>& results, const SystematicRates& systematic,
    const std::vector<io::GnssFix>& fixes, const std::vector<ReferenceMatch>& matches,
    const std::vector<RevisitMatch>& revisits, const io::Georeference& georeference,
    const GraphOptions& options, const MapperOptions& mapper_options, const GraphOutcome* previous,
    std::size_t window_frames) {
  // A fix or two (a bag's origin fix) are no track to hold the trajectory to; one reference
  // match is (it holds heading as well as position).
  const bool enough_fixes =
      fixes.size() >= static_cast<std::size_t>(std::max(options.min_gnss_fixes, 1));
  if (!options.enabled || results.empty() ||
      (!enough_fixes && matches.empty() && revisits.empty())) {
    return std::nullopt;
  }
  std::vector<graph::PoseFactor> poses;
  double xy_sigma = 1.0;  // the reference's placement σ (one reference per run)
  GraphOutcome out;
  out.reference_matches = matches;
  for (const ReferenceMatch& m : matches) {
    if (!m.matched || m.frame >= results.size()) {
      out.reference_factor.push_back(-1);
      continue;
    }
    out.reference_factor.push_back(static_cast<long>(poses.size()));
    graph::PoseFactor f;
    f.node = m.frame;
    f.T_world_body = m.T_world_body;
    f.information = m.information;
    f.z_offset = !m.vertical_absolute;
    f.xy_offset = m.placement_sigma_m > 0.0;
    if (f.xy_offset) xy_sigma = m.placement_sigma_m;
    poses.push_back(f);
  }
  std::vector<graph::LoopFactor> loops;
  out.revisits = revisits;
  for (const RevisitMatch& r : revisits) {
    const bool usable = r.match.matched && r.factor.from < results.size() &&
                        r.factor.to < results.size() && r.factor.from != r.factor.to;
    out.revisit_factor.push_back(usable ? static_cast<long>(loops.size()) : -1);
    if (usable) loops.push_back(r.factor);
  }
  graph::PoseGraphOptions solver;
  solver.fix_gate_chi2 = options.fix_gate_chi2;
  solver.fix_huber_sigmas = options.fix_huber_sigmas;
  solver.max_gate_rounds = options.max_gate_rounds;
  solver.xy_offset_sigma_m = xy_sigma;
  solver.covariance =
      results.size() <= static_cast<std::size_t>(std::max(options.covariance_max_frames, 0));
  solver.min_fixes = poses.empty() && loops.empty() ? options.min_gnss_fixes : 1;
  graph::Validate(solver);

  out.fixes = fixes.size();
  out.frame_fixes.resize(results.size());
  const Eigen::Vector3d antenna(options.gnss_antenna_m.at(0), options.gnss_antenna_m.at(1),
                                options.gnss_antenna_m.at(2));
  std::vector<graph::PositionFactor> positions;
  for (const io::GnssFix& fix : fixes) {
    // The frame nearest in time (results are in time order).
    const auto after =
        std::lower_bound(results.begin(), results.end(), fix.timestamp,
                         [](const FrameResult& r, double t) { return r.timestamp < t; });
    std::size_t best = results.size();
    double best_dt = options.gnss_max_time_offset_s;
    for (auto it : {after, after == results.begin() ? after : after - 1}) {
      if (it == results.end()) continue;
      const double dt = std::abs(it->timestamp - fix.timestamp);
      if (dt <= best_dt) {
        best_dt = dt;
        best = static_cast<std::size_t>(it - results.begin());
      }
    }
    if (best == results.size()) {
      ++out.unmatched;
      continue;
    }
    graph::PositionFactor f;
    f.node = best;
    f.position_world =
        georeference.GeodeticToEnu(fix.latitude_deg, fix.longitude_deg, fix.altitude_m);
    f.covariance = fix.sigma_enu_m.cwiseAbs2().asDiagonal();
    f.lever_arm_body = antenna;
    out.frame_fixes[best].push_back(positions.size());
    positions.push_back(f);
  }
  std::vector<Eigen::Isometry3d> initial;
  initial.reserve(results.size());
  for (const FrameResult& r : results) initial.push_back(r.step.T_world_body);
  // A window: the frames before it where the last solve put them (and the frames after that
  // solve chained onto its last pose), only the window solved.
  const graph::PoseGraphResult* held = nullptr;
  if (previous != nullptr && window_frames > 0 && results.size() > window_frames) {
    const graph::PoseGraphResult& p = previous->solution;
    const std::size_t first_free = results.size() - window_frames;
    // A loop found since that solve onto ground older than the window: the frames between the
    // two passes must move too, so this solve is whole (once; the next ones hold its result).
    for (std::size_t k = previous->revisits.size(); k < revisits.size(); ++k) {
      if (revisits[k].match.matched && revisits[k].from_frame < first_free) {
        out.whole_for_loop_from = revisits[k].from_frame;
      }
    }
    if (p.solved && p.T_world_body.size() > first_free && p.T_world_body.size() <= results.size() &&
        !out.whole_for_loop_from) {
      held = &p;
      for (std::size_t k = 0; k < p.T_world_body.size(); ++k) initial[k] = p.T_world_body[k];
      for (std::size_t k = p.T_world_body.size(); k < results.size(); ++k) {
        initial[k] = initial[k - 1] *
                     (results[k - 1].step.T_world_body.inverse() * results[k].step.T_world_body);
      }
      solver.first_free_node = first_free;
      // Its covariance, or the chain's where it had none (a whole solve beyond
      // graph.covariance_max_frames, as after a daemon's restart late in a run).
      solver.held_covariance = first_free < p.covariance.size()
                                   ? p.covariance[first_free]
                                   : results[first_free].step.covariance;
      solver.covariance = true;  // the window's: its cost is the window's
    }
  }
  // The chain's own roll and pitch, with its σ, as priors: fixes and reference matches hold
  // position and heading, not the tilt, and without them the graph bought a shorter
  // horizontal path (a drifting scale) with a tilted one (10° over a 300 m loop, z metres off).
  for (std::size_t k = 1; k < results.size(); ++k) {
    const PoseSigmas sd = SigmasOf(results[k].step);
    const double sigma = std::max({sd.roll_deg, sd.pitch_deg, 0.01}) * M_PI / 180.0;
    graph::PoseFactor prior;
    prior.node = k;
    prior.T_world_body = results[k].step.T_world_body;
    prior.information(0, 0) = prior.information(1, 1) = 1.0 / (sigma * sigma);
    prior.gated = false;
    poses.push_back(prior);
  }
  out.solution = graph::SolvePoseGraph(
      initial, RelativeFactors(results, systematic, mapper_options),
      enough_fixes ? positions : std::vector<graph::PositionFactor>{}, poses, solver, loops);
  if (!solver.covariance && out.solution.solved) {
    out.solution.covariance_message = "not computed: " + std::to_string(results.size()) +
                                      " frames, more than graph.covariance_max_frames " +
                                      std::to_string(options.covariance_max_frames) +
                                      " (the chain's is reported)";
  }
  std::vector<graph::Matrix6d>& covariance = out.solution.covariance;
  if (held != nullptr && covariance.size() == results.size()) {
    for (std::size_t k = 0; k < solver.first_free_node; ++k) {
      covariance[k] =
          k < held->covariance.size() ? held->covariance[k] : results[k].step.covariance;
    }
  }
  for (std::size_t k = 0; k < covariance.size() && k < results.size(); ++k)
    KeepTheChainsTilt(results[k].step.covariance, &covariance[k]);
  if (!enough_fixes) {  // too few to weigh: left out, not rejected
    for (std::vector<std::size_t>& f : out.frame_fixes) f.clear();
  }
  return out;
}

namespace {

// What became of the matches whose frame is `frame`: `frame_of(k)` the frame of match k,
// `factor[k]` its factor's index into `used` (−1: refused by its own checks).
template <typename FrameOf>
FrameReference OutcomeOfFrame(std::size_t matches, FrameOf frame_of,
                              const std::vector<long>& factor, const std::vector<bool>& used,
                              std::size_t frame) {
  FrameReference out = FrameReference::kNone;
  for (std::size_t k = 0; k < matches; ++k) {
    if (frame_of(k) != frame) continue;
    const long f = k < factor.size() ? factor[k] : -1;
    if (f < 0) {
      if (out == FrameReference::kNone) out = FrameReference::kRefused;
      continue;
    }
    if (static_cast<std::size_t>(f) < used.size() && used[static_cast<std::size_t>(f)])
      return FrameReference::kUsed;
    out = FrameReference::kRejected;
  }
  return out;
}

}  // namespace

FrameReference ReferenceOfFrame(const GraphOutcome& graph, std::size_t frame) {
  return OutcomeOfFrame(
      graph.reference_matches.size(),
      [&](std::size_t k) { return graph.reference_matches[k].frame; }, graph.reference_factor,
      graph.solution.pose_used, frame);
}

FrameReference RevisitOfFrame(const GraphOutcome& graph, std::size_t frame) {
  return OutcomeOfFrame(
      graph.revisits.size(), [&](std::size_t k) { return graph.revisits[k].match.frame; },
      graph.revisit_factor, graph.solution.loop_used, frame);
}

const char* ToString(FrameReference outcome) {
  switch (outcome) {
    case FrameReference::kUsed:
      return "used";
    case FrameReference::kRejected:
      return "rejected";
    case FrameReference::kRefused:
      return "refused";
    case FrameReference::kNone:
      return "none";
  }
  return "none";
}

ChainStep ReportedStep(const FrameResult& result, const GraphOutcome* graph) {
  ChainStep step = result.step;
  if (graph == nullptr || !graph->solution.solved) return step;
  const graph::PoseGraphResult& g = graph->solution;
  if (result.index < g.T_world_body.size()) step.T_world_body = g.T_world_body[result.index];
  if (result.index < g.covariance.size()) step.covariance = g.covariance[result.index];
  return step;
}

std::size_t RefuseFrames(const io::FrameSource& source, Mapper* mapper,
                         const std::vector<Eigen::Isometry3d>& T_world_body,
                         const std::vector<graph::Matrix6d>& covariance,
                         const std::function<void(std::size_t, std::size_t)>& progress) {
  mapper->ResetMaps();
  const std::vector<FrameResult>& results = mapper->results();
  std::size_t refused = 0;
  for (std::size_t k = 0; k < results.size() && k < T_world_body.size(); ++k) {
    if (results[k].status != FrameStatus::kBadFrame) {
      try {
        const io::Frame frame = source.Read(k);
        const PreparedFrame prepared = mapper->Prepare(frame);
        if (prepared.loaded.ok) {
          ChainStep step = results[k].step;
          step.T_world_body = T_world_body[k];
          if (k < covariance.size()) step.covariance = covariance[k];
          mapper->FuseAgain(prepared, step);
        } else {
          ++refused;
        }
      } catch (const io::IoError&) {
        ++refused;  // read once, gone now: the rest of the map is still worth having
      }
    }
    if (progress) progress(k + 1, results.size());
  }
  return refused;
}

}  // namespace rovermap::mapper
