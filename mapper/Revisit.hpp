#pragma once
// Revisits (docs/graph.md): every RevisitOptions::every_m of path the ground of the last
// window_m is saved; when it overlaps ground saved at least min_gap_m of path before, it is
// registered onto it (MatchPosts: the same matcher and checks as a reference DEM's), and a good
// match becomes a loop factor between a frame of each pass.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "graph/PoseGraph.hpp"
#include "mapper/Patches.hpp"
#include "mapper/ReferenceMatch.hpp"
#include "mapper/ReferenceOptions.hpp"
#include "registration/Options.hpp"

namespace rovermap::mapper {

class Mapper;

/// One look for a revisit that found earlier ground.
struct RevisitMatch {
  std::size_t from_frame = 0;  ///< the earlier pass's frame (nearest its ground's centre)
  ReferenceMatch match;        ///< the recent ground onto the earlier one (frame: the later's)
  /// The loop factor (valid when match.matched): from_frame to match.frame.
  graph::LoopFactor factor;
};

/// Information of a pose factor's residual [log(R R_measᵀ); t − t_meas] at frame `to` (world
/// axes) as a loop factor's: a left perturbation in frame `from` of T_from_to, with
/// T_world_from fixed. Never throws.
graph::Matrix6d LoopInformation(const graph::Matrix6d& pose_information,
                                const Eigen::Isometry3d& T_world_from,
                                const Eigen::Isometry3d& T_from_to);

class RevisitTrack {
 public:
  RevisitTrack(const RevisitOptions& revisit, const ReferenceOptions& checks,
               const registration::RegistrationOptions& registration);
  /// After each frame (its points binned by BinFrame, empty when not fused): the look made, if
  /// one was due and earlier ground lay under the recent one.
  std::optional<RevisitMatch> AfterFrame(const Mapper& mapper, const FrameBins& bins);
  const std::vector<RevisitMatch>& matches() const { return matches_; }

 private:
  friend struct CheckpointAccess;  // service/Checkpoint: kept across a daemon's restart
  struct Saved {
    std::vector<Post> posts;
    io::ReferenceGrid grid;
    Eigen::AlignedBox2d box;
    std::size_t frame = 0;  // nearest its centre
    double path_m = 0.0;
  };
  RevisitOptions options_;
  ReferenceOptions checks_;
  registration::RegistrationOptions registration_;
  double last_look_m_ = 0.0;
  PatchAccumulator patches_;
  std::vector<Saved> saved_;
  std::vector<RevisitMatch> matches_;
};

/// @throw std::invalid_argument naming the key if an option is out of range.
void Validate(const RevisitOptions& options);

}  // namespace rovermap::mapper
