#include "mapper/DemWarp.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>

#include "core/Skew.hpp"

namespace rovermap::mapper {

namespace {

// The vertical variance a pose covariance Σ (right perturbation in the body frame, order
// rx ry rz tx ty tz) gives a point (dx, dy) from the body's position: as Mapper::Fuse's
// FrameContext::pose_covariance, J = (dy, −dx, 0, 0, 0, 1) against the left perturbation in the
// world about the body, Ad([R, 0]) Σ Ad([R, 0])ᵀ. Kept as the 3 × 3 form in (dy, −dx, 1).
Eigen::Matrix3d VerticalShareForm(const Eigen::Isometry3d& T_world_body,
                                  const Eigen::Matrix<double, 6, 6>& covariance) {
  Eigen::Isometry3d about_body = T_world_body;
  about_body.translation().setZero();
  const Eigen::Matrix<double, 6, 6> A = core::Adjoint(about_body);
  const Eigen::Matrix<double, 6, 6> left = A * covariance * A.transpose();
  const int idx[3] = {0, 1, 5};
  Eigen::Matrix3d q;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) q(r, c) = left(idx[r], idx[c]);
  return q;
}

struct FrameMove {
  bool solved = false;
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();  // T_graph · T_chain⁻¹
  Eigen::Vector3d body_chain = Eigen::Vector3d::Zero();
  Eigen::Matrix3d share_chain = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d share_graph = Eigen::Matrix3d::Zero();
};

struct MovedCell {
  double gx, gy;  // [m] grid frame
  float z, variance, count;
  std::uint32_t frame;
};

// A moved cell's bilinear share of an output pixel.
struct Share {
  std::size_t pixel;
  double b;
  const MovedCell* cell;
};

}  // namespace

std::vector<std::optional<Eigen::Isometry3d>> GraphCorrections(
    const std::vector<FrameResult>& results, const GraphOutcome& graph) {
  std::vector<std::optional<Eigen::Isometry3d>> out;
  if (!graph.solution.solved) return out;
  for (const FrameResult& r : results) {
    if (r.index >= graph.solution.T_world_body.size()) continue;
    if (out.size() <= r.step.index) out.resize(r.step.index + 1);
    out[r.step.index] = graph.solution.T_world_body[r.index] * r.step.T_world_body.inverse();
  }
  return out;
}

io::DemLayers WarpDemToGraph(const io::DemLayers& dem, const std::vector<FrameResult>& results,
                             const GraphOutcome& graph, DemWarpStats* stats) {
  DemWarpStats local;
  DemWarpStats& st = stats ? *stats : local;
  st = {};
  const std::size_t pixels =
      static_cast<std::size_t>(dem.width) * static_cast<std::size_t>(dem.height);
  if (!graph.solution.solved || dem.frame.size() != pixels || dem.elevation_m.size() != pixels ||
      dem.cell_size_m <= 0.0) {
    st.cells_in = st.cells_out = dem.valid_cells;
    return dem;
  }
  const std::vector<std::optional<Eigen::Isometry3d>> corrections =
      GraphCorrections(results, graph);
  std::unordered_map<std::uint32_t, FrameMove> moves;
  for (const FrameResult& r : results) {
    FrameMove m;
    const ChainStep reported = ReportedStep(r, &graph);
    m.solved = r.step.index < corrections.size() && corrections[r.step.index].has_value();
    if (m.solved) m.correction = *corrections[r.step.index];
    m.body_chain = r.step.T_world_body.translation();
    m.share_chain = VerticalShareForm(r.step.T_world_body, r.step.covariance);
    m.share_graph = VerticalShareForm(reported.T_world_body, reported.covariance);
    moves[static_cast<std::uint32_t>(r.step.index)] = m;
  }

  const double s = dem.cell_size_m;
  const double c = std::cos(dem.grid_rotation_rad), sn = std::sin(dem.grid_rotation_rad);
  std::vector<MovedCell> moved;
  moved.reserve(dem.valid_cells);
  std::vector<double> shifts;
  shifts.reserve(dem.valid_cells);
  for (int row = 0; row < dem.height; ++row) {
    for (int col = 0; col < dem.width; ++col) {
      const std::size_t o = static_cast<std::size_t>(row) * dem.width + col;
      const float z = dem.elevation_m[o];
      if (std::isnan(z)) continue;
      ++st.cells_in;
      const double gx = (static_cast<double>(dem.min.x + col) + 0.5) * s;
      const double gy = (static_cast<double>(dem.max.y - row) + 0.5) * s;
      const float sd = dem.stddev_m[o];
      double variance = std::isfinite(sd) ? static_cast<double>(sd) * sd : 0.0;
      MovedCell cell{gx, gy, z, 0.0f, dem.count[o], dem.frame[o]};
      const auto it = moves.find(dem.frame[o]);
      if (it != moves.end() && it->second.solved) {
        const FrameMove& m = it->second;
        // Grid to world: the inverse of DemLayers::WorldToGrid's rotation.
        const Eigen::Vector3d p(c * gx + sn * gy, -sn * gx + c * gy, z);
        const Eigen::Vector3d q = m.correction * p;
        const Eigen::Vector2d g = dem.WorldToGrid(q.x(), q.y());
        cell.gx = g.x();
        cell.gy = g.y();
        cell.z = static_cast<float>(q.z());
        shifts.push_back((q - p).head<2>().norm());
        // The chain's pose share out, the graph's in. The fusion averaged the share over the
        // cell's frames, so subtracting it whole can overshoot: then the variance is scaled by
        // the ratio of the two shares instead (exact when the share is all there is).
        const Eigen::Vector3d v(p.y() - m.body_chain.y(), -(p.x() - m.body_chain.x()), 1.0);
        const double chain = std::max(0.0, v.dot(m.share_chain * v));
        const double graph_share = std::max(0.0, v.dot(m.share_graph * v));
        if (graph_share >= chain) {
          variance += graph_share - chain;
        } else if (chain > 0.0) {
          variance = std::max(variance - (chain - graph_share), variance * graph_share / chain);
        }
        ++st.cells_moved;
      }
      cell.variance = static_cast<float>(std::max(variance, 1e-12));
      moved.push_back(cell);
    }
  }
  if (!shifts.empty()) {
    st.max_shift_m = *std::max_element(shifts.begin(), shifts.end());
    auto mid = shifts.begin() + static_cast<std::ptrdiff_t>(shifts.size() / 2);
    std::nth_element(shifts.begin(), mid, shifts.end());
    st.median_shift_m = *mid;
  }

  if (moved.empty()) return dem;  // nothing published
  io::DemLayers out;
  out.cell_size_m = dem.cell_size_m;
  out.grid_rotation_rad = dem.grid_rotation_rad;
  // A moved cell's centre at (u + 0.5) s spreads over the four cells around it.
  std::int64_t min_x = std::numeric_limits<std::int64_t>::max(), min_y = min_x;
  std::int64_t max_x = std::numeric_limits<std::int64_t>::min(), max_y = max_x;
  for (const MovedCell& m : moved) {
    const double u = m.gx / s - 0.5, w = m.gy / s - 0.5;
    const auto ix = static_cast<std::int64_t>(std::floor(u));
    const auto iy = static_cast<std::int64_t>(std::floor(w));
    min_x = std::min(min_x, ix);
    max_x = std::max(max_x, u > static_cast<double>(ix) ? ix + 1 : ix);
    min_y = std::min(min_y, iy);
    max_y = std::max(max_y, w > static_cast<double>(iy) ? iy + 1 : iy);
  }
  // A raster far larger than the chain's means corrections that tear the map apart (a graph
  // gone wrong): the chain's DEM is kept rather than a raster of that size allocated.
  const double width = static_cast<double>(max_x - min_x + 1);
  const double height = static_cast<double>(max_y - min_y + 1);
  if (width * height > std::max(4.0 * static_cast<double>(pixels), 1e7)) {
    st.cells_moved = 0;
    st.cells_out = dem.valid_cells;
    st.refused = "the moved DEM would span " + std::to_string(static_cast<long long>(width)) +
                 " x " + std::to_string(static_cast<long long>(height)) +
                 " cells, more than 4 times the chain's";
    return dem;
  }
  out.min = {min_x, min_y};
  out.max = {max_x, max_y};
  out.width = static_cast<int>(width);
  out.height = static_cast<int>(height);
  const std::size_t n = static_cast<std::size_t>(out.width) * out.height;
  // Four shares per moved cell, gathered by output pixel: a sparse sum, as a DEM's published
  // cells are a small part of its raster (docs/serve.md: dense sums took four times as long).
  std::vector<Share> shares;
  shares.reserve(4 * moved.size());
  for (const MovedCell& m : moved) {
    const double u = m.gx / s - 0.5, w = m.gy / s - 0.5;
    const auto ix = static_cast<std::int64_t>(std::floor(u));
    const auto iy = static_cast<std::int64_t>(std::floor(w));
    const double fx = u - static_cast<double>(ix), fy = w - static_cast<double>(iy);
    for (int dy = 0; dy < 2; ++dy) {
      for (int dx = 0; dx < 2; ++dx) {
        const double b = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);
        if (b <= 0.0) continue;
        const auto col = static_cast<std::size_t>(ix + dx - min_x);
        const auto row = static_cast<std::size_t>(max_y - (iy + dy));
        shares.push_back({row * static_cast<std::size_t>(out.width) + col, b, &m});
      }
    }
  }
  std::stable_sort(shares.begin(), shares.end(),
                   [](const Share& a, const Share& b) { return a.pixel < b.pixel; });
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  out.elevation_m.assign(n, kNaN);
  out.stddev_m.assign(n, kNaN);
  out.count.assign(n, 0.0f);
  out.frame.assign(n, 0);
  for (std::size_t i = 0; i < shares.size();) {
    const std::size_t o = shares[i].pixel;
    double sum_b = 0.0, sum_w = 0.0, sum_wz = 0.0, sum_bcount = 0.0, best_b = 0.0;
    std::uint32_t best_frame = 0;
    for (; i < shares.size() && shares[i].pixel == o; ++i) {
      const double b = shares[i].b;
      const MovedCell& m = *shares[i].cell;
      const double wi = b / m.variance;
      sum_b += b;
      sum_w += wi;
      sum_wz += wi * m.z;
      sum_bcount += b * m.count;
      if (b > best_b) {
        best_b = b;
        best_frame = m.frame;
      }
    }
    if (sum_b < 0.5) continue;  // less than half a cell's worth reached it
    out.elevation_m[o] = static_cast<float>(sum_wz / sum_w);
    out.stddev_m[o] = static_cast<float>(std::sqrt(sum_b / sum_w));
    out.count[o] = static_cast<float>(sum_bcount / sum_b);
    out.frame[o] = best_frame;
    ++out.valid_cells;
  }
  st.cells_out = out.valid_cells;
  return out;
}

}  // namespace rovermap::mapper
