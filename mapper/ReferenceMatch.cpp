#include "mapper/ReferenceMatch.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/Skew.hpp"
#include "core/Units.hpp"
#include "mapper/Mapper.hpp"
#include "registration/Directions.hpp"
#include "registration/Icp.hpp"

namespace rovermap::mapper {
namespace {

using core::kRadToDeg;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// [m] the rover's posts' σ in the matcher's weights and gate.
constexpr double kPostSigmaM = 0.05;

std::string Figure(double v, int digits) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

// Local coordinates: the rover's posts about `source` (their centre), the reference about
// `target` (the same, lowered by the median height difference at the seed), so that a
// reference on another vertical datum (metres, an orbital product's geoid) does not put the
// rotations' lever arm far below the patch. A local T maps source-local to target-local.
struct Local {
  Eigen::Vector3d source = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d World(const Eigen::Isometry3d& T, const Eigen::Vector3d& p) const {
    return target + T * (p - source);
  }
  Eigen::Isometry3d ToWorld(const Eigen::Isometry3d& T) const {
    return Eigen::Translation3d(target) * T * Eigen::Translation3d(-source);
  }
  Eigen::Isometry3d FromWorld(const Eigen::Isometry3d& C) const {
    return Eigen::Translation3d(-target) * C * Eigen::Translation3d(source);
  }
};

// Height differences of `posts` moved by `T` (local) against the reference: their RMS after
// removing the median, and how many have a reference height.
struct Fit {
  double rms_m = std::numeric_limits<double>::infinity();
  double median_m = 0.0;
  std::size_t covered = 0;
};

Fit FitOf(const std::vector<Post>& posts, const io::ReferenceGrid& grid, const Local& local,
          const Eigen::Isometry3d& T) {
  std::vector<double> dz;
  dz.reserve(posts.size());
  for (const Post& post : posts) {
    const Eigen::Vector3d q = local.World(T, post.p);
    const double z = grid.HeightAt(q.x(), q.y());
    if (std::isfinite(z)) dz.push_back(q.z() - z);
  }
  Fit fit;
  fit.covered = dz.size();
  if (dz.empty()) return fit;
  std::vector<double> sorted = dz;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  fit.median_m = sorted[sorted.size() / 2];
  double sum = 0.0;
  for (const double d : dz) sum += (d - fit.median_m) * (d - fit.median_m);
  fit.rms_m = std::sqrt(sum / static_cast<double>(dz.size()));
  return fit;
}

double SlopeVariance(const io::ReferenceGrid& g, double x, double y, int axis);

// The information of the height differences of `posts` moved by `T` (local)
// against the reference surface, for a left perturbation [r, t] of T: r_i = q_z − H(q_x, q_y),
// J = ∂r/∂[r, t], weighed by 1 / residual_m² (the RMS height difference at the match: the
// posts' own σ carries the chain's pose uncertainty, which is shared by the whole patch and is
// what the match estimates, not noise). `noise` gets the part the errors of the reference's
// slopes alone give (SlopeVariance): what a plain with this noise would show.
Matrix6d HeightInformation(const std::vector<Post>& posts, const io::ReferenceGrid& grid,
                           const Local& local, const Eigen::Isometry3d& T, double residual_m,
                           Matrix6d* noise) {
  Matrix6d info = Matrix6d::Zero();
  *noise = Matrix6d::Zero();
  const double s = grid.spacing_m;
  for (const Post& post : posts) {
    const Eigen::Vector3d q = T * (post.p - local.source);
    const Eigen::Vector3d w = q + local.target;
    const double hx = (grid.HeightAt(w.x() + s, w.y()) - grid.HeightAt(w.x() - s, w.y())) / (2 * s);
    const double hy = (grid.HeightAt(w.x(), w.y() + s) - grid.HeightAt(w.x(), w.y() - s)) / (2 * s);
    const double z = grid.HeightAt(w.x(), w.y());
    if (!std::isfinite(hx) || !std::isfinite(hy) || !std::isfinite(z)) continue;
    const double weight = 1.0 / std::max(residual_m * residual_m, 1e-8);
    Eigen::Matrix<double, 6, 1> J;
    J << q.y() + hy * q.z(), -q.x() - hx * q.z(), hx * q.y() - hy * q.x(), -hx, -hy, 1.0;
    info += weight * J * J.transpose();
    Eigen::Matrix<double, 6, 1> a, b;  // ∂J/∂hx, ∂J/∂hy
    a << 0.0, -q.z(), q.y(), -1.0, 0.0, 0.0;
    b << q.z(), 0.0, -q.x(), 0.0, -1.0, 0.0;
    const double vx = SlopeVariance(grid, w.x(), w.y(), 0);
    const double vy = SlopeVariance(grid, w.x(), w.y(), 1);
    if (std::isfinite(vx) && std::isfinite(vy))
      *noise += weight * (vx * a * a.transpose() + vy * b * b.transpose());
  }
  return info;
}

// Variance of the central-difference slope (H(p + s·e) − H(p − s·e)) / 2s at world (x, y)
// along x (axis 0) or y (1) when the reference's nodes err independently by their σ: the two
// bilinear stencils combined (they share nodes), Σ c_k² σ_k². NaN outside.
double SlopeVariance(const io::ReferenceGrid& g, double x, double y, int axis) {
  const double s = g.spacing_m;
  std::array<std::pair<std::size_t, double>, 8> c{};
  int n = 0;
  for (const double sign : {1.0, -1.0}) {
    const double px = x + (axis == 0 ? sign * s : 0.0);
    const double py = y + (axis == 1 ? sign * s : 0.0);
    const double u = (px - g.origin_world.x()) / s;
    const double v = (py - g.origin_world.y()) / s;
    if (!(u >= 0.0 && v >= 0.0 && u <= g.width - 1 && v <= g.height - 1)) return NAN;
    const int c0 = std::min(static_cast<int>(u), g.width - 2);
    const int r0 = std::min(static_cast<int>(v), g.height - 2);
    const double fu = u - c0, fv = v - r0;
    const double w[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
    const int dc[4] = {0, 1, 0, 1}, dr[4] = {0, 0, 1, 1};
    for (int q = 0; q < 4; ++q) {
      const std::size_t k = static_cast<std::size_t>(r0 + dr[q]) * g.width + (c0 + dc[q]);
      const double coef = sign * w[q] / (2.0 * s);
      int at = 0;
      while (at < n && c[at].first != k) ++at;
      if (at == n) c[n++] = {k, 0.0};
      c[at].second += coef;
    }
  }
  double var = 0.0;
  for (int i = 0; i < n; ++i) {
    const double sigma = g.sigma_m[c[i].first];
    var += c[i].second * c[i].second * sigma * sigma;
  }
  return var;
}

// Information of the directions `keep` (indices into [rx ry rz tx ty tz]) with the others
// marginalised out (Schur complement; a ridge keeps a direction the data leave free from
// blowing up the solve, where it then contributes nothing).
Eigen::MatrixXd Marginal(const Matrix6d& information, const std::vector<int>& keep) {
  std::vector<int> other;
  for (int i = 0; i < 6; ++i)
    if (std::find(keep.begin(), keep.end(), i) == keep.end()) other.push_back(i);
  const auto nk = static_cast<Eigen::Index>(keep.size());
  const auto no = static_cast<Eigen::Index>(other.size());
  Eigen::MatrixXd A(nk, nk), B(nk, no), C(no, no);
  for (Eigen::Index i = 0; i < nk; ++i) {
    for (Eigen::Index j = 0; j < nk; ++j) A(i, j) = information(keep[i], keep[j]);
    for (Eigen::Index j = 0; j < no; ++j) B(i, j) = information(keep[i], other[j]);
  }
  for (Eigen::Index i = 0; i < no; ++i)
    for (Eigen::Index j = 0; j < no; ++j) C(i, j) = information(other[i], other[j]);
  if (no == 0) return A;
  const double ridge = 1e-12 * std::max(1.0, C.diagonal().cwiseAbs().maxCoeff());
  C.diagonal().array() += ridge;
  return A - B * C.ldlt().solve(B.transpose());
}

}  // namespace

void Validate(const ReferenceOptions& o) {
  auto fail = [](const char* key, const char* rule) {
    throw std::invalid_argument(std::string("reference.") + key + " must be " + rule);
  };
  if (!(o.every_m > 0.0)) fail("every_m", "> 0");
  if (!(o.window_m > 0.0)) fail("window_m", "> 0");
  if (!(o.sigma_m > 0.0)) fail("sigma_m", "> 0");
  if (!(o.search_m >= 0.0)) fail("search_m", ">= 0");
  if (!(o.search_yaw_deg >= 0.0)) fail("search_yaw_deg", ">= 0");
  if (!(o.min_relief_ratio >= 1.0)) fail("min_relief_ratio", ">= 1");
  if (!(o.ambiguity_ratio >= 1.0)) fail("ambiguity_ratio", ">= 1");
  if (!(o.max_sigma_m > 0.0)) fail("max_sigma_m", "> 0");
  if (!(o.max_sigma_deg > 0.0)) fail("max_sigma_deg", "> 0");
  if (!(o.covariance_scale >= 1.0)) fail("covariance_scale", ">= 1");
  if (o.min_posts < 10) fail("min_posts", ">= 10");
  if (!(o.max_post_sigma_m > 0.0)) fail("max_post_sigma_m", "> 0");
  if (!(o.horizontal_sigma_m > 0.0)) fail("horizontal_sigma_m", "> 0");
}

ReferenceMatch MatchReference(const std::vector<Post>& posts, const io::ReferenceDem& reference,
                              std::size_t first_frame, const std::vector<Eigen::Isometry3d>& poses,
                              const Eigen::Isometry3d& seed, const ReferenceOptions& options,
                              const registration::RegistrationOptions& registration) {
  Eigen::AlignedBox2d box;
  for (const Post& post : posts) box.extend(post.p.head<2>());
  io::ReferenceGrid grid;
  if (!box.isEmpty()) {
    const double margin = options.search_m + 3.0 * reference.post_spacing_m() +
                          box.diagonal().norm() * std::sin(options.search_yaw_deg / kRadToDeg);
    // The patch in the frame the seed places it in: the box moved by the seed, widened.
    Eigen::AlignedBox2d placed;
    for (int corner = 0; corner < 4; ++corner) {
      const Eigen::Vector2d c = box.corner(static_cast<Eigen::AlignedBox2d::CornerType>(corner));
      placed.extend((seed * Eigen::Vector3d(c.x(), c.y(), 0.0)).head<2>());
    }
    const Eigen::Vector2d pad = Eigen::Vector2d::Constant(margin);
    grid = reference.Resample(placed.min() - pad, placed.max() + pad);
  }
  ReferenceMatch out =
      MatchPosts(posts, grid, first_frame, poses, seed, options, registration,
                 "no reference height under the window (outside the reference DEM)");
  out.placement_sigma_m = options.horizontal_sigma_m;
  return out;
}

io::ReferenceGrid GridOfPosts(const std::vector<Post>& posts, double spacing_m, double sigma_m) {
  io::ReferenceGrid grid;
  grid.spacing_m = spacing_m;
  Eigen::AlignedBox2d box;
  for (const Post& post : posts) box.extend(post.p.head<2>());
  if (box.isEmpty() || !(spacing_m > 0.0)) return grid;
  grid.origin_world = (box.min() / spacing_m).array().round().matrix() * spacing_m;
  grid.width =
      static_cast<int>(std::lround((box.max().x() - grid.origin_world.x()) / spacing_m)) + 1;
  grid.height =
      static_cast<int>(std::lround((box.max().y() - grid.origin_world.y()) / spacing_m)) + 1;
  const auto n = static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height);
  grid.z_m.assign(n, std::numeric_limits<float>::quiet_NaN());
  grid.sigma_m.assign(n, std::numeric_limits<float>::quiet_NaN());
  for (const Post& post : posts) {
    const long col = std::lround((post.p.x() - grid.origin_world.x()) / spacing_m);
    const long row = std::lround((post.p.y() - grid.origin_world.y()) / spacing_m);
    if (col < 0 || row < 0 || col >= grid.width || row >= grid.height) continue;
    const std::size_t k =
        static_cast<std::size_t>(row) * grid.width + static_cast<std::size_t>(col);
    grid.z_m[k] = static_cast<float>(post.p.z());
    grid.sigma_m[k] = static_cast<float>(sigma_m);
  }
  return grid;
}

ReferenceMatch MatchPosts(const std::vector<Post>& posts, const io::ReferenceGrid& grid,
                          std::size_t first_frame, const std::vector<Eigen::Isometry3d>& poses,
                          const Eigen::Isometry3d& seed, const ReferenceOptions& options,
                          const registration::RegistrationOptions& registration,
                          const std::string& no_grid) {
  const auto start = std::chrono::steady_clock::now();
  ReferenceMatch out;
  out.first_frame = first_frame;
  out.last_frame = first_frame + (poses.empty() ? 0 : poses.size() - 1);
  out.frame = out.last_frame;
  auto done = [&](std::string reason) {
    out.reason = std::move(reason);
    out.ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return out;
  };
  if (poses.empty()) return done("no frames in the window");
  if (posts.empty()) return done("no points of the window's frames");
  if (grid.ValidNodes() == 0) return done(no_grid);
  const double s = grid.spacing_m;
  out.posts = posts.size();

  // Local coordinates about the patch's centre: rotations turn the patch about itself.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const Post& post : posts) origin += post.p;
  if (!posts.empty()) origin /= static_cast<double>(posts.size());
  Local local{origin, origin};
  const Fit at_seed = FitOf(posts, grid, local, local.FromWorld(seed));
  if (std::isfinite(at_seed.median_m)) local.target.z() -= at_seed.median_m;
  const Eigen::Isometry3d seed_local = local.FromWorld(seed);
  const Fit before = FitOf(posts, grid, local, seed_local);
  out.rms_before_m = before.rms_m;
  if (before.covered < static_cast<std::size_t>(options.min_posts)) {
    return done(std::to_string(before.covered) + " of the window's " +
                std::to_string(posts.size()) +
                " posts over the reference DEM, fewer than reference.min_posts " +
                std::to_string(options.min_posts));
  }

  // Source: the rover's posts; target: the reference's nodes with data, both local.
  registration::PointCloud source, target;
  for (const Post& post : posts) {
    source.points.push_back(post.p - origin);
    // The rover's posts weigh alike in the matcher; their scatter enters the match's σ through
    // the RMS height difference (HeightInformation).
    source.covariances.push_back(
        Eigen::Vector3d(1e-6, 1e-6, kPostSigmaM * kPostSigmaM).asDiagonal());
  }
  const double footprint = s * s / 12.0;  // a post stands for its cell
  for (int row = 0; row < grid.height; ++row) {
    for (int col = 0; col < grid.width; ++col) {
      const std::size_t k = static_cast<std::size_t>(row) * grid.width + col;
      if (!std::isfinite(grid.z_m[k])) continue;
      const Eigen::Vector2d xy = grid.Node(col, row);
      target.points.push_back(Eigen::Vector3d(xy.x(), xy.y(), grid.z_m[k]) - local.target);
      const double v = static_cast<double>(grid.sigma_m[k]) * grid.sigma_m[k];
      target.covariances.push_back(Eigen::Vector3d(footprint, footprint, v).asDiagonal());
    }
  }
  registration::RegistrationOptions reg = registration;
  reg.residual = registration::Residual::kPointToPlane;
  reg.use_uncertainty = true;
  const registration::IndexedCloud source_cloud(std::move(source), reg, s);
  const registration::IndexedCloud target_cloud(std::move(target), reg, s);

  // Starts over the search region: every 1.5 posts within search_m, heading −, 0, +.
  struct Solution {
    Eigen::Isometry3d T;
    Fit fit;
    registration::RegistrationResult result;
  };
  std::vector<Solution> solutions;
  // Starts every 1.5 posts, or a quarter of the search where it is wide (a revisit after a long
  // drift): at most 9 x 9 per heading.
  const double step = std::max(1.5 * s, 0.25 * options.search_m);
  const int reach = static_cast<int>(std::floor(options.search_m / step));
  std::vector<double> yaws = {0.0};
  if (options.search_yaw_deg > 0.0) {
    yaws.push_back(-options.search_yaw_deg);
    yaws.push_back(options.search_yaw_deg);
  }
  for (const double yaw_deg : yaws) {
    for (int i = -reach; i <= reach; ++i) {
      for (int j = -reach; j <= reach; ++j) {
        const Eigen::Vector2d d = step * Eigen::Vector2d(i, j);
        if (d.norm() > options.search_m + 1e-9) continue;
        Eigen::Isometry3d T_init =
            Eigen::Translation3d(d.x(), d.y(), 0.0) *
            Eigen::AngleAxisd(yaw_deg / kRadToDeg, Eigen::Vector3d::UnitZ()) * seed_local;
        // Started at the median height difference: the reference's vertical datum may be
        // metres away, and the weighted match gates pairs by their σ.
        T_init.translation().z() -= FitOf(posts, grid, local, T_init).median_m;
        const registration::RegistrationResult r =
            registration::Register(source_cloud, target_cloud, T_init, reg);
        ++out.starts;
        const bool usable = r.status == registration::RegistrationStatus::kConverged ||
                            r.status == registration::RegistrationStatus::kMaxIterations;
        if (!usable) continue;
        const Fit fit = FitOf(posts, grid, local, r.T_target_source);
        // A placement that slides the posts off the ground under them is not a match: it keeps
        // at least half the cover of the start (of a revisit's partial overlap, not of all).
        if (fit.covered < static_cast<std::size_t>(options.min_posts) ||
            fit.covered < before.covered / 2)
          continue;
        solutions.push_back({r.T_target_source, fit, r});
      }
    }
  }
  if (solutions.empty())
    return done("the matcher converged from none of " + std::to_string(out.starts) + " starts");
  std::sort(solutions.begin(), solutions.end(),
            [](const Solution& a, const Solution& b) { return a.fit.rms_m < b.fit.rms_m; });
  const Solution& best = solutions.front();
  out.rms_after_m = best.fit.rms_m;
  out.correction = local.ToWorld(best.T);

  // Conditioning: heading, x and y against what the heights' noise alone gives them. The height
  // goes with them: relative to the reference's vertical datum, or absolute when trusted.
  const std::vector<int> keep = {2, 3, 4, 5};
  Matrix6d height_noise;
  const Matrix6d height_info =
      HeightInformation(posts, grid, local, best.T, std::max(best.fit.rms_m, 1e-3), &height_noise);
  const Eigen::MatrixXd info = Marginal(height_info, keep);
  Eigen::MatrixXd noise = Marginal(height_noise, keep);
  // The slopes' noise does not reach the height (∂r/∂z = 1): a token share keeps the
  // generalised eigenproblem definite, and z then keeps its whole information.
  noise(3, 3) += 1e-9 * std::max(info(3, 3), 1e-12);
  const char* names[6] = {"roll", "pitch", "heading", "x", "y", "z"};
  // The relief's own information is what the match has beyond the noise's: with noisy posts
  // (an orbital DTM's 0.2 m on 1 m posts) the normals' errors alone give a plain as much x and y
  // information as gentle relief does, and that part places nothing.
  Eigen::MatrixXd relief = info;
  out.relief_ratio = std::numeric_limits<double>::infinity();
  {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> noise_eig(noise);
    if (noise_eig.info() == Eigen::Success && noise_eig.eigenvalues().minCoeff() > 0.0) {
      // Generalised eigenvalues of (info, noise): W I W with W = N^-1/2; relief = N^1/2 (W I W
      // − 1)₊ N^1/2.
      const Eigen::MatrixXd V = noise_eig.eigenvectors();
      const Eigen::MatrixXd w =
          V * noise_eig.eigenvalues().cwiseSqrt().cwiseInverse().asDiagonal() * V.transpose();
      const Eigen::MatrixXd root =
          V * noise_eig.eigenvalues().cwiseSqrt().asDiagonal() * V.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(w * info * w);
      out.relief_ratio = eig.eigenvalues()(0);
      if (!(out.relief_ratio >= options.min_relief_ratio)) {
        const Eigen::VectorXd v = w * eig.eigenvectors().col(0);
        Eigen::Index worst = 0;
        v.cwiseAbs().maxCoeff(&worst);
        return done(
            "ill-conditioned: " + std::string(names[keep[static_cast<std::size_t>(worst)]]) +
            " holds " + Figure(out.relief_ratio, 1) +
            "x the information of the heights' noise alone (needs "
            "reference.min_relief_ratio " +
            Figure(options.min_relief_ratio, 1) + ")");
      }
      const Eigen::VectorXd excess = (eig.eigenvalues().array() - 1.0).cwiseMax(0.0).matrix();
      relief =
          root * eig.eigenvectors() * excess.asDiagonal() * eig.eigenvectors().transpose() * root;
    }
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(relief);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) {
    return done("ill-conditioned: the window's relief does not constrain x, y and heading");
  }
  const Eigen::MatrixXd covariance =
      options.covariance_scale *
      ldlt.solve(Eigen::MatrixXd::Identity(relief.rows(), relief.cols()));
  out.sigma_yaw_deg = std::sqrt(covariance(0, 0)) * kRadToDeg;
  out.sigma_x_m = std::sqrt(covariance(1, 1));
  out.sigma_y_m = std::sqrt(covariance(2, 2));
  if (!(std::max(out.sigma_x_m, out.sigma_y_m) <= options.max_sigma_m)) {
    return done("ill-conditioned: sigma of x, y " + Figure(out.sigma_x_m, 2) + ", " +
                Figure(out.sigma_y_m, 2) + " m exceeds reference.max_sigma_m " +
                Figure(options.max_sigma_m, 2));
  }
  if (!(out.sigma_yaw_deg <= options.max_sigma_deg)) {
    return done("ill-conditioned: sigma of heading " + Figure(out.sigma_yaw_deg, 2) +
                " deg exceeds reference.max_sigma_deg " + Figure(options.max_sigma_deg, 2));
  }

  // Ambiguity: another placement two posts or more away (at the patch's centre) that fits
  // nearly as well is the same relief repeated (dunes of one wavelength), not a second noisy
  // estimate. Nearer ones are the same minimum, reached less exactly from a farther start (the
  // match's σ says how well it is determined).
  for (const Solution& other : solutions) {
    const double apart = (other.T.translation() - best.T.translation()).head<2>().norm();
    const double turn =
        Eigen::AngleAxisd(other.T.linear() * best.T.linear().transpose()).angle() * kRadToDeg;
    if (apart >= 2.0 * s && other.fit.rms_m < options.ambiguity_ratio * best.fit.rms_m) {
      return done("ambiguous: a placement " + Figure(apart, 1) + " m and " + Figure(turn, 1) +
                  " deg away fits nearly as well (RMS " + Figure(other.fit.rms_m, 3) + " against " +
                  Figure(best.fit.rms_m, 3) + " m)");
    }
  }

  // The factor: on the frame nearest the patch's centre, its information moved from the
  // patch's centre (the correction's rotation point) to that frame's position.
  const std::size_t nearest = NearestPose(poses, origin.head<2>());
  out.frame = out.first_frame + nearest;
  // The measurement holds heading, x, y and z: its roll and pitch are the chain's, so that the
  // directions it does not hold carry no residual for the graph to turn into a tilt (the
  // match's own tilt is the patch's fit, not the rover's attitude).
  const Eigen::Matrix3d& Rc = out.correction.linear();
  const double dyaw = std::atan2(Rc(1, 0), Rc(0, 0));
  out.T_world_body = poses[nearest];
  out.T_world_body.linear() = Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                              poses[nearest].linear();
  out.T_world_body.translation() = out.correction * poses[nearest].translation();
  out.vertical_absolute = options.vertical_trusted;
  Matrix6d info_origin = Matrix6d::Zero();
  const Eigen::MatrixXd info_scaled = relief / options.covariance_scale;
  for (std::size_t i = 0; i < keep.size(); ++i)
    for (std::size_t j = 0; j < keep.size(); ++j)
      info_origin(keep[i], keep[j]) =
          info_scaled(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  // The match's perturbation turns about the patch's centre in the reference (the target's
  // origin): δt_frame = δt − [d]× δθ with d = t_frame − centre, so J⁻¹ = [I 0; [d]× I].
  Matrix6d J_inv = Matrix6d::Identity();
  J_inv.bottomLeftCorner<3, 3>() = core::Skew(out.T_world_body.translation() - local.target);
  out.information = J_inv.transpose() * info_origin * J_inv;
  out.matched = true;
  return done("");
}

std::string CoverageProblem(const io::ReferenceDem& reference,
                            const std::vector<io::StampedPose>& odometry) {
  Eigen::AlignedBox2d traverse;
  for (const io::StampedPose& p : odometry) traverse.extend(p.T_world_body.translation().head<2>());
  if (traverse.isEmpty()) return "";
  const Eigen::Vector2d pad = Eigen::Vector2d::Constant(10.0);
  const Eigen::AlignedBox2d widened(traverse.min() - pad, traverse.max() + pad);
  const Eigen::AlignedBox2d& f = reference.footprint_world();
  if (f.intersects(widened)) return "";
  auto box = [](const Eigen::AlignedBox2d& b) {
    return "x " + Figure(b.min().x(), 0) + ".." + Figure(b.max().x(), 0) + ", y " +
           Figure(b.min().y(), 0) + ".." + Figure(b.max().y(), 0) + " m";
  };
  return reference.file() + ": reference DEM does not cover the traverse (its footprint " + box(f) +
         " in the world frame, the traverse's " + box(traverse) + ")";
}

ReferenceTrack::ReferenceTrack(const io::ReferenceDem& reference, const ReferenceOptions& options,
                               const registration::RegistrationOptions& registration)
    : reference_(reference), options_(options), registration_(registration) {
  Validate(options_);
}

std::optional<ReferenceMatch> ReferenceTrack::AfterFrame(const Mapper& mapper,
                                                         const FrameBins& bins) {
  const std::vector<FrameResult>& results = mapper.results();
  if (results.empty()) return std::nullopt;
  const std::size_t last = results.size() - 1;
  const std::size_t first =
      patches_.Advance(last, results[last].step.T_world_body, bins, options_.window_m);
  if (patches_.path_m() - last_match_m_ < options_.every_m) return std::nullopt;
  last_match_m_ = patches_.path_m();
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t k = first; k <= last; ++k) poses.push_back(results[k].step.T_world_body);
  ReferenceMatch match = MatchReference(
      patches_.Window(first, last, reference_.post_spacing_m(), options_.max_post_sigma_m),
      reference_, first, poses, seed_, options_, registration_);
  if (match.matched) seed_ = match.correction;
  matches_.push_back(match);
  return match;
}

}  // namespace rovermap::mapper
