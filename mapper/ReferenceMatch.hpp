#pragma once
// Matches of the rover's recent ground against a reference DEM (docs/graph.md): every
// ReferenceOptions::every_m metres the points of the frames along the last window_m metres are
// averaged at the reference's posts (Patches) and registered onto it with the project's matcher
// (point-to-plane, weighted by both DEMs' σ), from several starts over the search region. A
// match that is ill-conditioned or ambiguous is refused and says why; a good one becomes an
// absolute factor on x, y, heading and height (the height up to the reference's vertical
// datum, unless trusted) of the frame nearest the patch's centre.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "io/ReferenceDem.hpp"
#include "io/Tum.hpp"
#include "mapper/Patches.hpp"
#include "mapper/ReferenceOptions.hpp"
#include "registration/Options.hpp"

namespace rovermap::mapper {

class Mapper;

/// One match of the rover's DEM against the reference.
struct ReferenceMatch {
  std::size_t frame = 0;        ///< the frame the factor holds (nearest the patch's centre)
  std::size_t first_frame = 0;  ///< the window: the frames whose new cells were matched
  std::size_t last_frame = 0;
  bool matched = false;  ///< a factor for the graph; false: refused, `reason` says why
  std::string reason;
  std::size_t posts = 0;  ///< rover posts (cells averaged at the reference's posts) matched
  /// [m] RMS height difference over the posts at the seed and at the match (each after the
  /// median height difference is removed).
  double rms_before_m = 0.0;
  double rms_after_m = 0.0;
  /// World to world: the patch placed on the reference (applied to the chained poses).
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  /// The measured pose of `frame`: its chained pose turned by the correction's heading and
  /// moved by the correction (roll and pitch kept).
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  /// z is on the sequence's vertical datum (ReferenceOptions::vertical_trusted); false: on the
  /// reference's, an unknown offset away that the graph estimates (one for all matches).
  bool vertical_absolute = false;
  /// [m] σ of the reference's horizontal placement in the world (reference.horizontal_sigma_m):
  /// shared by every match of it, so the graph solves for one offset with this prior; 0: the
  /// matches are its own ground (a revisit), nothing shared.
  double placement_sigma_m = 0.0;
  /// Information of T_world_body for the residual [log(R R_measᵀ); t − t_meas] (world axes,
  /// rad and m): heading, x, y and z at the patch's centre (zero in roll and pitch there),
  /// moved to the frame's position (the lever gives roll and pitch a little).
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  double sigma_x_m = 0.0;  ///< 1σ of the match (after covariance_scale), at the patch's centre
  double sigma_y_m = 0.0;
  double sigma_yaw_deg = 0.0;
  /// Smallest ratio, over x, y and heading, of the match's information to what the heights'
  /// noise alone gives (ReferenceOptions::min_relief_ratio).
  double relief_ratio = 0.0;
  int starts = 0;  ///< matcher runs (the search's starts)
  double ms = 0.0;
};

/// One match: `posts` (the window's ground, frames first_frame.. on), registered onto
/// `reference` from starts about `seed` (a world-to-world correction). `poses` are the window's
/// frames' chained T_world_body, first_frame first. Never throws on data: a refused match says
/// why.
ReferenceMatch MatchReference(const std::vector<Post>& posts, const io::ReferenceDem& reference,
                              std::size_t first_frame, const std::vector<Eigen::Isometry3d>& poses,
                              const Eigen::Isometry3d& seed, const ReferenceOptions& options,
                              const registration::RegistrationOptions& registration);

/// The same onto a grid already made (a reference resampled, or the rover's own earlier ground:
/// GridOfPosts); `no_grid` is the reason given when the grid holds no height.
ReferenceMatch MatchPosts(const std::vector<Post>& posts, const io::ReferenceGrid& grid,
                          std::size_t first_frame, const std::vector<Eigen::Isometry3d>& poses,
                          const Eigen::Isometry3d& seed, const ReferenceOptions& options,
                          const registration::RegistrationOptions& registration,
                          const std::string& no_grid);

/// `posts` as a grid of `spacing_m` (multiples of it), each node the height of the post nearest,
/// of σ `sigma_m`; nodes without a post NaN. Never throws.
io::ReferenceGrid GridOfPosts(const std::vector<Post>& posts, double spacing_m, double sigma_m);

/// When to match during a replay: after each frame (its points binned by BinFrame before it
/// was processed; empty bins for a frame that was not fused), AfterFrame matches once the path
/// since the last match reaches every_m, the window being the frames of the last window_m
/// metres; each match is seeded with the last accepted one's correction.
class ReferenceTrack {
 public:
  ReferenceTrack(const io::ReferenceDem& reference, const ReferenceOptions& options,
                 const registration::RegistrationOptions& registration);
  /// @return the match made after the mapper's last frame, if one was due.
  std::optional<ReferenceMatch> AfterFrame(const Mapper& mapper, const FrameBins& bins);
  const std::vector<ReferenceMatch>& matches() const { return matches_; }

 private:
  friend struct CheckpointAccess;  // service/Checkpoint: kept across a daemon's restart
  const io::ReferenceDem& reference_;
  ReferenceOptions options_;
  registration::RegistrationOptions registration_;
  double last_match_m_ = 0.0;
  Eigen::Isometry3d seed_ = Eigen::Isometry3d::Identity();
  PatchAccumulator patches_;
  std::vector<ReferenceMatch> matches_;
};

/// Why `reference` cannot serve a traverse along `odometry` ("" when it can): its footprint
/// misses the traverse's box (dead reckoning's positions, widened by 10 m). Never throws.
std::string CoverageProblem(const io::ReferenceDem& reference,
                            const std::vector<io::StampedPose>& odometry);

/// @throw std::invalid_argument naming the key if an option is out of range.
void Validate(const ReferenceOptions& options);

}  // namespace rovermap::mapper
