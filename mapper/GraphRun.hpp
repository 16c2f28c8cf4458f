#pragma once
// The pose graph's sources over one run (docs/graph.md), as replay and serve both keep them: a
// reference DEM's matches and the revisits, looked for after each frame, and the graph solved
// with them and the GNSS fixes when asked (at the end of a replay, at each publication of serve).

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/Gnss.hpp"
#include "io/ReferenceDem.hpp"
#include "mapper/GnssGraph.hpp"
#include "mapper/GraphOptions.hpp"
#include "mapper/Patches.hpp"
#include "mapper/ReferenceMatch.hpp"
#include "mapper/ReferenceOptions.hpp"
#include "mapper/Revisit.hpp"
#include "registration/Options.hpp"

namespace rovermap::mapper {

class Mapper;

/// The options the graph's sources read (the `graph.`, `reference.`, `revisit.` keys).
struct GraphSetup {
  GraphOptions graph;
  ReferenceOptions reference;
  RevisitOptions revisit;
  registration::RegistrationOptions registration;
  MapperOptions mapper;
};

class GraphRun {
 public:
  /// `reference`: the reference DEM to match against (nullptr: none); kept, must outlive this.
  /// Revisits are looked for when revisit.enabled and graph.enabled.
  /// @throw std::invalid_argument naming the key if an option is out of range.
  GraphRun(const GraphSetup& setup, const io::ReferenceDem* reference);

  /// Whether AfterFrame wants each frame's bins (a reference or revisits are looked for).
  bool wants_bins() const { return track_ != nullptr || revisit_ != nullptr; }
  /// After each frame the mapper took (its points binned by BinFrame, empty when it was not
  /// fused): the lines to log, one per match or look made, each starting with `who` + ": ".
  std::vector<std::string> AfterFrame(const Mapper& mapper, const FrameBins& bins,
                                      const std::string& who);
  /// SolveGraph over the mapper's results with `fixes` and what the tracks found; the
  /// reference that was given but left out is named in the outcome (`reference_unusable`).
  /// `window_frames` > 0: only the last so many frames are solved, the others held where the
  /// last Solve put them (a daemon's bounded solve; the first solves, and any after one that
  /// was not solved, are whole).
  /// @throw std::invalid_argument if the options are invalid.
  std::optional<GraphOutcome> Solve(const Mapper& mapper, const std::vector<io::GnssFix>& fixes,
                                    const std::string& reference_unusable = "",
                                    std::size_t window_frames = 0);

 private:
  friend struct CheckpointAccess;  // service/Checkpoint: the tracks kept across a restart
  GraphSetup setup_;
  std::unique_ptr<ReferenceTrack> track_;
  std::unique_ptr<RevisitTrack> revisit_;
  std::optional<GraphOutcome> last_;
};

}  // namespace rovermap::mapper
