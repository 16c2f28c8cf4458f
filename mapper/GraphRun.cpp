#include "mapper/GraphRun.hpp"

#include <iomanip>
#include <sstream>

#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

GraphRun::GraphRun(const GraphSetup& setup, const io::ReferenceDem* reference) : setup_(setup) {
  Validate(setup_.reference);
  if (reference != nullptr) {
    track_ = std::make_unique<ReferenceTrack>(*reference, setup_.reference, setup_.registration);
  }
  if (setup_.revisit.enabled && setup_.graph.enabled) {
    revisit_ =
        std::make_unique<RevisitTrack>(setup_.revisit, setup_.reference, setup_.registration);
  }
}

std::vector<std::string> GraphRun::AfterFrame(const Mapper& mapper, const FrameBins& bins,
                                              const std::string& who) {
  std::vector<std::string> lines;
  if (track_) {
    if (const std::optional<ReferenceMatch> m = track_->AfterFrame(mapper, bins)) {
      std::ostringstream line;
      line << std::fixed << std::setprecision(2) << who << ": reference match, frames "
           << m->first_frame << "-" << m->last_frame << ": ";
      if (m->matched) {
        line << "matched on frame " << m->frame << ", RMS " << std::setprecision(3)
             << m->rms_before_m << " -> " << m->rms_after_m << " m, sigma x/y " << m->sigma_x_m
             << "/" << m->sigma_y_m << " m, heading " << m->sigma_yaw_deg << " deg";
      } else {
        line << "refused: " << m->reason;
      }
      lines.push_back(line.str());
    }
  }
  if (revisit_) {
    if (const std::optional<RevisitMatch> v = revisit_->AfterFrame(mapper, bins)) {
      std::ostringstream line;
      line << std::fixed << std::setprecision(3) << who << ": revisit, frames "
           << v->match.first_frame << "-" << v->match.last_frame << " onto frame " << v->from_frame
           << ": ";
      if (v->match.matched) {
        line << "matched on frame " << v->match.frame << ", RMS " << v->match.rms_before_m << " -> "
             << v->match.rms_after_m << " m, sigma x/y " << v->match.sigma_x_m << "/"
             << v->match.sigma_y_m << " m";
      } else {
        line << "refused: " << v->match.reason;
      }
      lines.push_back(line.str());
    }
  }
  return lines;
}

std::optional<GraphOutcome> GraphRun::Solve(const Mapper& mapper,
                                            const std::vector<io::GnssFix>& fixes,
                                            const std::string& reference_unusable,
                                            std::size_t window_frames) {
  std::optional<GraphOutcome> graph = SolveGraph(
      mapper.results(),
      SystematicRatesOf(mapper.sensor().type, mapper.rig_calibration(), setup_.mapper), fixes,
      track_ ? track_->matches() : std::vector<ReferenceMatch>{},
      revisit_ ? revisit_->matches() : std::vector<RevisitMatch>{}, mapper.georeference(),
      setup_.graph, setup_.mapper, last_ ? &*last_ : nullptr, window_frames);
  last_ = graph;
  if (!reference_unusable.empty()) {
    // Reported in summary.json even without a graph.
    if (!graph) graph.emplace();
    graph->reference_unusable = reference_unusable;
  }
  return graph;
}

}  // namespace rovermap::mapper
