#include "core/Units.hpp"
#include "sim/Terrain.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rovermap::sim {
namespace {

using core::kDegToRad;

std::uint64_t Mix(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double Smooth(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }  // quintic fade

}  // namespace

double Hash01(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
  const std::uint64_t h = Mix(Mix(Mix(Mix(a) ^ b) ^ c) ^ d);
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

double HashNormal(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
  const double u1 = std::max(Hash01(a, b, c, d), 1e-300);
  const double u2 = Hash01(a, b, c, d ^ 0x5bd1e995ULL);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

double Terrain::FractalNoise(double x, double y, double wavelength, int octaves, double persistence,
                             std::uint64_t salt, double min_wavelength) const {
  double sum = 0.0, amplitude = 1.0;
  for (int o = 0; o < octaves && wavelength >= min_wavelength; ++o) {
    const double fx = x / wavelength, fy = y / wavelength;
    const double ix = std::floor(fx), iy = std::floor(fy);
    const double tx = Smooth(fx - ix), ty = Smooth(fy - iy);
    auto lattice = [&](double i, double j) {
      return 2.0 * Hash01(seed_, salt + o, static_cast<std::uint64_t>(static_cast<std::int64_t>(i)),
                          static_cast<std::uint64_t>(static_cast<std::int64_t>(j))) -
             1.0;
    };
    const double a = lattice(ix, iy), b = lattice(ix + 1, iy);
    const double c = lattice(ix, iy + 1), d = lattice(ix + 1, iy + 1);
    sum += amplitude * ((a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty);
    amplitude *= persistence;
    wavelength *= 0.5;
  }
  return sum;
}

Terrain::Terrain(const SimOptions& o, const std::vector<Eigen::Vector2d>& path_xy)
    : seed_(static_cast<std::uint64_t>(o.seed)),
      half_size_(0.5 * o.terrain_size_m),
      cell_(o.terrain_cell_m),
      n_(static_cast<int>(std::floor(o.terrain_size_m / o.terrain_cell_m)) + 1) {
  heights_.assign(static_cast<std::size_t>(n_) * n_, 0.0f);
  rock_.assign(heights_.size(), 0.0f);
  const double sx = std::tan(o.slope_x_deg * kDegToRad);
  const double sy = std::tan(o.slope_y_deg * kDegToRad);
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      const double x = -half_size_ + i * cell_, y = -half_size_ + j * cell_;
      heights_[static_cast<std::size_t>(j) * n_ + i] = static_cast<float>(
          sx * x + sy * y +
          o.relief_m * FractalNoise(x, y, o.relief_wavelength_m, o.octaves, o.roughness, 100, 0));
    }
  }
  // Craters: a parabolic bowl (depth 0.2 R) with a raised rim (0.04 R) fading outside
  // (simple fresh-crater profile).
  for (int k = 0; k < o.craters; ++k) {
    const double cx = (2 * Hash01(seed_, 200, k, 0) - 1) * half_size_ * 0.8;
    const double cy = (2 * Hash01(seed_, 200, k, 1) - 1) * half_size_ * 0.8;
    const double radius = o.crater_max_radius_m * (0.3 + 0.7 * Hash01(seed_, 200, k, 2));
    const int reach = static_cast<int>(std::ceil(2.0 * radius / cell_));
    const int ci = static_cast<int>(std::lround((cx + half_size_) / cell_));
    const int cj = static_cast<int>(std::lround((cy + half_size_) / cell_));
    for (int j = std::max(0, cj - reach); j <= std::min(n_ - 1, cj + reach); ++j) {
      for (int i = std::max(0, ci - reach); i <= std::min(n_ - 1, ci + reach); ++i) {
        const double r = std::hypot(-half_size_ + i * cell_ - cx, -half_size_ + j * cell_ - cy);
        double dz = 0.04 * radius * std::exp(-std::pow((r - radius) / (0.3 * radius), 2));
        if (r < radius) dz += 0.2 * radius * ((r / radius) * (r / radius) - 1.0);
        heights_[static_cast<std::size_t>(j) * n_ + i] += static_cast<float>(dz);
      }
    }
  }
  // Rocks: half-ellipsoids (height 0.6 r), not on the rover's path.
  for (int k = 0, placed = 0; placed < o.rocks && k < 20 * o.rocks + 20; ++k) {
    const double rx = (2 * Hash01(seed_, 300, k, 0) - 1) * half_size_ * 0.9;
    const double ry = (2 * Hash01(seed_, 300, k, 1) - 1) * half_size_ * 0.9;
    // Many small rocks, few large ones.
    const double radius =
        o.rock_max_radius_m * (0.15 + 0.85 * std::pow(Hash01(seed_, 300, k, 2), 3));
    bool clear = true;
    for (const Eigen::Vector2d& p : path_xy) {
      if (std::hypot(p.x() - rx, p.y() - ry) < o.keep_out_m + radius) {
        clear = false;
        break;
      }
    }
    if (!clear) continue;
    ++placed;
    const int reach = static_cast<int>(std::ceil(radius / cell_)) + 1;
    const int ci = static_cast<int>(std::lround((rx + half_size_) / cell_));
    const int cj = static_cast<int>(std::lround((ry + half_size_) / cell_));
    for (int j = std::max(0, cj - reach); j <= std::min(n_ - 1, cj + reach); ++j) {
      for (int i = std::max(0, ci - reach); i <= std::min(n_ - 1, ci + reach); ++i) {
        const double d = std::hypot(-half_size_ + i * cell_ - rx, -half_size_ + j * cell_ - ry);
        if (d >= radius) continue;
        const std::size_t idx = static_cast<std::size_t>(j) * n_ + i;
        heights_[idx] +=
            static_cast<float>(0.6 * radius * std::sqrt(1.0 - (d / radius) * (d / radius)));
        rock_[idx] = 1.0f;
      }
    }
  }
}

double Terrain::Height(double x, double y) const {
  const double fx = (x + half_size_) / cell_, fy = (y + half_size_) / cell_;
  if (!(fx >= 0 && fy >= 0 && fx <= n_ - 1 && fy <= n_ - 1)) return std::nan("");
  const int i = std::min(static_cast<int>(fx), n_ - 2), j = std::min(static_cast<int>(fy), n_ - 2);
  const double tx = fx - i, ty = fy - j;
  const double a = Sample(i, j), b = Sample(i + 1, j), c = Sample(i, j + 1),
               d = Sample(i + 1, j + 1);
  return (a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty;
}

Eigen::Vector3d Terrain::Normal(double x, double y) const {
  const double h = 0.5 * cell_;
  const double dzdx = (Height(x + h, y) - Height(x - h, y)) / (2 * h);
  const double dzdy = (Height(x, y + h) - Height(x, y - h)) / (2 * h);
  Eigen::Vector3d n(-dzdx, -dzdy, 1.0);
  if (!n.allFinite()) return Eigen::Vector3d::UnitZ();
  return n.normalized();
}

double Terrain::Albedo(double x, double y, double footprint_m) const {
  // Regolith: soft mottling plus fine grain down to 1 cm; rocks darker and smoother.
  const double min_wavelength = std::max(2.0 * footprint_m, 0.01);
  const double grain = FractalNoise(x, y, 0.32, 6, 0.75, 400, min_wavelength);
  const double mottle = FractalNoise(x, y, 3.0, 3, 0.5, 500, 0);
  const int i = static_cast<int>(std::lround((x + half_size_) / cell_));
  const int j = static_cast<int>(std::lround((y + half_size_) / cell_));
  const bool rock =
      i >= 0 && j >= 0 && i < n_ && j < n_ && rock_[static_cast<std::size_t>(j) * n_ + i] > 0;
  const double base = rock ? 0.30 : 0.50;
  return std::clamp(base + 0.08 * mottle + 0.16 * grain, 0.02, 1.0);
}

bool Terrain::Raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double max_t,
                      double* t_hit) const {
  // March with a step of half the height above ground (at least one cell, so a feature
  // narrower than a cell may be missed at grazing angles),
  // then bisect the bracketing interval.
  double t_prev = 0.0;
  double t = 0.0;
  double above_prev = origin.z() - Height(origin.x(), origin.y());
  if (!(above_prev > 0)) return false;
  while (t < max_t) {
    const double step = std::clamp(0.5 * above_prev, cell_, 0.5);
    t_prev = t;
    t = std::min(t + step, max_t);
    const Eigen::Vector3d p = origin + t * direction;
    const double ground = Height(p.x(), p.y());
    if (std::isnan(ground)) return false;
    const double above = p.z() - ground;
    if (above <= 0) {
      double lo = t_prev, hi = t;
      for (int k = 0; k < 30; ++k) {
        const double mid = 0.5 * (lo + hi);
        const Eigen::Vector3d q = origin + mid * direction;
        (q.z() - Height(q.x(), q.y()) > 0 ? lo : hi) = mid;
      }
      *t_hit = 0.5 * (lo + hi);
      return true;
    }
    above_prev = above;
    if (t >= max_t) break;
  }
  return false;
}

}  // namespace rovermap::sim
