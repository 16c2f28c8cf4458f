#include "mapper/Revisit.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/Skew.hpp"
#include "mapper/Mapper.hpp"

namespace rovermap::mapper {
namespace {

// [m] σ of the earlier ground's posts (the reference's σ in the match's noise model).
constexpr double kPostSigmaM = 0.05;

}  // namespace

void Validate(const RevisitOptions& o) {
  auto fail = [](const char* key, const char* rule) {
    throw std::invalid_argument(std::string("revisit.") + key + " must be " + rule);
  };
  if (!(o.every_m > 0.0)) fail("every_m", "> 0");
  if (!(o.window_m > 0.0)) fail("window_m", "> 0");
  if (!(o.post_m > 0.0)) fail("post_m", "> 0");
  if (!(o.min_gap_m > 0.0)) fail("min_gap_m", "> 0");
  if (!(o.search_m >= 0.0)) fail("search_m", ">= 0");
  if (!(o.search_yaw_deg >= 0.0)) fail("search_yaw_deg", ">= 0");
  if (!(o.min_overlap > 0.0 && o.min_overlap <= 1.0)) fail("min_overlap", "in (0, 1]");
  if (!(o.max_post_sigma_m > 0.0)) fail("max_post_sigma_m", "> 0");
}

graph::Matrix6d LoopInformation(const graph::Matrix6d& pose_information,
                                const Eigen::Isometry3d& T_world_from,
                                const Eigen::Isometry3d& T_from_to) {
  // T_to = T_from · Exp(δ) · T_from_to: the world rotation moves by R_from θ, the position by
  // R_from (θ × t + ρ), t = T_from_to's translation; e = A δ.
  const Eigen::Matrix3d R = T_world_from.linear();
  graph::Matrix6d A = graph::Matrix6d::Zero();
  A.topLeftCorner<3, 3>() = R;
  A.bottomLeftCorner<3, 3>() = -R * core::Skew(T_from_to.translation());
  A.bottomRightCorner<3, 3>() = R;
  graph::Matrix6d out = A.transpose() * pose_information * A;
  return 0.5 * (out + out.transpose());
}

RevisitTrack::RevisitTrack(const RevisitOptions& revisit, const ReferenceOptions& checks,
                           const registration::RegistrationOptions& registration)
    : options_(revisit), checks_(checks), registration_(registration) {
  Validate(options_);
  Validate(checks_);
  checks_.search_m = options_.search_m;
  checks_.search_yaw_deg = options_.search_yaw_deg;
  // Both grounds are the same chain's: the height is as good as the rest.
  checks_.vertical_trusted = true;
}

std::optional<RevisitMatch> RevisitTrack::AfterFrame(const Mapper& mapper, const FrameBins& bins) {
  const std::vector<FrameResult>& results = mapper.results();
  if (results.empty()) return std::nullopt;
  const std::size_t last = results.size() - 1;
  const std::size_t first =
      patches_.Advance(last, results[last].step.T_world_body, bins, options_.window_m);
  if (patches_.path_m() - last_look_m_ < options_.every_m) return std::nullopt;
  last_look_m_ = patches_.path_m();

  Saved now;
  now.posts = patches_.Window(first, last, options_.post_m, options_.max_post_sigma_m);
  if (now.posts.empty()) return std::nullopt;
  now.grid = GridOfPosts(now.posts, options_.post_m, kPostSigmaM);
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Post& p : now.posts) {
    now.box.extend(p.p.head<2>());
    centre += p.p.head<2>();
  }
  centre /= static_cast<double>(now.posts.size());
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t k = first; k <= last; ++k) poses.push_back(results[k].step.T_world_body);
  now.frame = first + NearestPose(poses, centre);
  now.path_m = patches_.path_m();

  // The earlier ground most of the recent posts lie over, far enough back along the path.
  const Saved* best = nullptr;
  double best_overlap = 0.0;
  for (const Saved& old : saved_) {
    if (now.path_m - old.path_m < options_.min_gap_m || !old.box.intersects(now.box)) continue;
    std::size_t over = 0;
    for (const Post& p : now.posts) over += std::isfinite(old.grid.HeightAt(p.p.x(), p.p.y()));
    const double overlap = static_cast<double>(over) / static_cast<double>(now.posts.size());
    if (overlap > best_overlap) {
      best_overlap = overlap;
      best = &old;
    }
  }
  std::optional<RevisitMatch> out;
  if (best != nullptr && best_overlap >= options_.min_overlap) {
    RevisitMatch r;
    r.from_frame = best->frame;
    r.match = MatchPosts(now.posts, best->grid, first, poses, Eigen::Isometry3d::Identity(),
                         checks_, registration_, "no earlier ground under the recent one");
    if (r.match.matched) {
      const Eigen::Isometry3d& T_from = results[r.from_frame].step.T_world_body;
      r.factor.from = r.from_frame;
      r.factor.to = r.match.frame;
      r.factor.T_from_to = T_from.inverse() * r.match.T_world_body;
      r.factor.information = LoopInformation(r.match.information, T_from, r.factor.T_from_to);
    }
    matches_.push_back(r);
    out = r;
  }
  saved_.push_back(std::move(now));
  return out;
}

}  // namespace rovermap::mapper
