#include "io/ReferenceDem.hpp"

#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <sstream>

#include "io/GeoTiff.hpp"
#include "io/IoError.hpp"
#include "io/TiledGeoTiff.hpp"

namespace rovermap::io {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct TransformDeleter {
  void operator()(OGRCoordinateTransformation* t) const {
    OGRCoordinateTransformation::DestroyCT(t);
  }
};
using TransformPtr = std::unique_ptr<OGRCoordinateTransformation, TransformDeleter>;

[[noreturn]] void Fail(const std::filesystem::path& file, const std::string& what) {
  throw IoError(file.string() + ": reference DEM " + what);
}

std::string Metres(double v) {
  std::ostringstream s;
  s.precision(0);
  s << std::fixed << v;
  return s.str();
}

}  // namespace

double ReferenceGrid::HeightAt(double x_m, double y_m) const {
  if (width < 2 || height < 2 || !(spacing_m > 0.0)) return kNaN;
  const double u = (x_m - origin_world.x()) / spacing_m;
  const double v = (y_m - origin_world.y()) / spacing_m;
  if (!(u >= 0.0 && v >= 0.0 && u <= width - 1 && v <= height - 1)) return kNaN;
  const int c = std::min(static_cast<int>(u), width - 2);
  const int r = std::min(static_cast<int>(v), height - 2);
  const double fu = u - c;
  const double fv = v - r;
  auto at = [&](int cc, int rr) { return z_m[static_cast<std::size_t>(rr) * width + cc]; };
  const double z = (1 - fu) * (1 - fv) * at(c, r) + fu * (1 - fv) * at(c + 1, r) +
                   (1 - fu) * fv * at(c, r + 1) + fu * fv * at(c + 1, r + 1);
  return z;  // NaN when a corner has no data
}

std::size_t ReferenceGrid::ValidNodes() const {
  return static_cast<std::size_t>(
      std::count_if(z_m.begin(), z_m.end(), [](float z) { return std::isfinite(z); }));
}

struct ReferenceDem::Impl {
  std::string file;
  Georeference georef;
  DemRaster raster;
  double sigma_m = 0.5;
  bool sigma_band = false;
  TransformPtr to_raster;    // geographic (lon, lat) -> the file's CRS
  TransformPtr to_geodetic;  // the file's CRS -> geographic (lon, lat)
  double spacing_m = 0.0;
  Eigen::AlignedBox2d footprint;
  // Heights are above this altitude (rovermap's own DEMs: their origin's), else above the
  // file's ellipsoid.
  double datum_altitude_m = 0.0;

  explicit Impl(const Georeference& g) : georef(g) {}

  // World (x, y) of the file's CRS point (X, Y), or nullopt.
  bool RasterToWorld(double X, double Y, Eigen::Vector2d* world) const {
    double x = X, y = Y;
    if (!to_geodetic->Transform(1, &x, &y)) return false;
    const Eigen::Vector3d enu = georef.GeodeticToEnu(y, x, georef.origin().altitude_m);
    if (!enu.allFinite()) return false;
    *world = enu.head<2>();
    return true;
  }
  Eigen::Vector2d PixelCentre(double col, double row) const {
    const auto& g = raster.geotransform;
    return {g[0] + (col + 0.5) * g[1], g[3] + (row + 0.5) * g[5]};
  }
};

ReferenceDem::ReferenceDem(const std::filesystem::path& file, const Georeference& georef,
                           const ReferenceDemOptions& options)
    : impl_(std::make_unique<Impl>(georef)) {
  Impl& m = *impl_;
  m.file = file.string();
  m.raster = ReadDemGeoTiff(file);  // IoError naming the file
  if (m.raster.wkt.empty()) Fail(file, "has no CRS: its heights cannot be placed on the ground");
  OGRSpatialReference srs;
  if (srs.importFromWkt(m.raster.wkt.c_str()) != OGRERR_NONE)
    Fail(file, "has a CRS GDAL cannot read");
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRErr err = OGRERR_NONE;
  const double a = srs.GetSemiMajor(&err);
  const double body_m = BodyRadiusM(georef.body());
  if (err != OGRERR_NONE || !(a > 0.0) || srs.IsLocal()) {
    Fail(file, "has a CRS that cannot be transformed to geographic coordinates (no ellipsoid)");
  }
  if (std::abs(a - body_m) > 0.01 * body_m) {
    Fail(file, "is of another body: its ellipsoid's semi-major axis is " + Metres(a) +
                   " m, the sequence's body's " + Metres(body_m) + " m");
  }
  // Earth: from WGS 84, so that GDAL applies the datum shift to the file's datum; elsewhere the
  // file's own geographic CRS (IAU bodies have one datum each).
  OGRSpatialReference geographic;
  if (georef.body() == Body::kEarth) {
    geographic.SetWellKnownGeogCS("WGS84");
  } else {
    std::unique_ptr<OGRSpatialReference, void (*)(OGRSpatialReference*)> geog(
        srs.CloneGeogCS(),
        [](OGRSpatialReference* s) { OGRSpatialReference::DestroySpatialReference(s); });
    if (!geog) Fail(file, "has a CRS that cannot be transformed to geographic coordinates");
    geographic = *geog;
  }
  geographic.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  {
    QuietGdal quiet;
    m.to_raster.reset(OGRCreateCoordinateTransformation(&geographic, &srs));
    m.to_geodetic.reset(OGRCreateCoordinateTransformation(&srs, &geographic));
  }
  if (!m.to_raster || !m.to_geodetic) {
    Fail(file,
         "has a CRS that cannot be transformed to geographic coordinates" + QuietGdal::Last());
  }

  if (const std::size_t at = m.raster.elevation_datum.find("origin altitude ");
      at != std::string::npos) {
    m.datum_altitude_m = std::strtod(m.raster.elevation_datum.c_str() + at + 16, nullptr);
  }
  m.sigma_band = options.sigma_band && !m.raster.stddev_m.empty();
  m.sigma_m = options.sigma_m;
  std::size_t heights = 0;
  for (std::size_t c = 0; c < m.raster.elevation_m.size(); ++c) {
    if (!std::isfinite(m.raster.elevation_m[c])) continue;
    ++heights;
    const double s = m.sigma_band ? m.raster.stddev_m[c] : m.sigma_m;
    if (!(s > 0.0) || !std::isfinite(s)) {
      const int col = static_cast<int>(c % static_cast<std::size_t>(m.raster.width));
      const int row = static_cast<int>(c / static_cast<std::size_t>(m.raster.width));
      Fail(file, m.sigma_band ? "band 2 (σ) is not > 0 at column " + std::to_string(col) +
                                    ", row " + std::to_string(row) +
                                    " (set reference.sigma_band: false to use reference.sigma_m)"
                              : "σ (reference.sigma_m) is not > 0");
    }
  }
  if (heights == 0) Fail(file, "holds no height (every cell is no data)");

  // Footprint: the raster's edges, every tenth of a side, in the world frame.
  const int w = m.raster.width;
  const int h = m.raster.height;
  for (int k = 0; k <= 10; ++k) {
    const double f = k / 10.0;
    const std::pair<double, double> edges[4] = {
        {f * w, 0.0}, {f * w, 1.0 * h}, {0.0, f * h}, {1.0 * w, f * h}};
    for (const auto& [col, row] : edges) {
      const Eigen::Vector2d X = m.PixelCentre(col - 0.5, row - 0.5);
      Eigen::Vector2d world;
      if (m.RasterToWorld(X.x(), X.y(), &world)) m.footprint.extend(world);
    }
  }
  if (m.footprint.isEmpty()) Fail(file, "cannot be placed in the sequence's world frame");

  // Post spacing: a cell and its neighbour east, near the world origin.
  double X = 0.0, Y = 0.0;
  {
    const Eigen::Vector3d geo = georef.EnuToGeodetic(0.0, 0.0, 0.0);
    double lon = geo.y(), lat = geo.x();
    if (m.to_raster->Transform(1, &lon, &lat)) {
      X = lon;
      Y = lat;
    }
  }
  const auto& g = m.raster.geotransform;
  double col = std::clamp((X - g[0]) / g[1] - 0.5, 0.0, std::max(0.0, w - 2.0));
  double row = std::clamp((Y - g[3]) / g[5] - 0.5, 0.0, std::max(0.0, h - 1.0));
  if (!std::isfinite(col) || !std::isfinite(row)) col = row = 0.0;
  Eigen::Vector2d p0, p1;
  const Eigen::Vector2d A = m.PixelCentre(col, row);
  const Eigen::Vector2d B = m.PixelCentre(col + 1.0, row);
  if (!m.RasterToWorld(A.x(), A.y(), &p0) || !m.RasterToWorld(B.x(), B.y(), &p1) ||
      !((p1 - p0).norm() > 0.0)) {
    Fail(file, "cannot be placed in the sequence's world frame");
  }
  m.spacing_m = (p1 - p0).norm();
}

ReferenceDem::~ReferenceDem() = default;

const std::string& ReferenceDem::file() const { return impl_->file; }
double ReferenceDem::post_spacing_m() const { return impl_->spacing_m; }
const Eigen::AlignedBox2d& ReferenceDem::footprint_world() const { return impl_->footprint; }

ReferenceGrid ReferenceDem::Resample(const Eigen::Vector2d& min_world,
                                     const Eigen::Vector2d& max_world) const {
  const Impl& m = *impl_;
  ReferenceGrid grid;
  grid.spacing_m = m.spacing_m;
  if (!min_world.allFinite() || !max_world.allFinite() || (max_world - min_world).minCoeff() < 0.0)
    return grid;
  const double s = m.spacing_m;
  const Eigen::Vector2d first = (min_world / s).array().floor().matrix() * s;
  const Eigen::Vector2d last = (max_world / s).array().ceil().matrix() * s;
  grid.origin_world = first;
  grid.width = static_cast<int>(std::lround((last.x() - first.x()) / s)) + 1;
  grid.height = static_cast<int>(std::lround((last.y() - first.y()) / s)) + 1;
  const auto n = static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height);
  grid.z_m.assign(n, kNaN);
  grid.sigma_m.assign(n, kNaN);
  std::vector<double> lon(n), lat(n);
  for (int row = 0; row < grid.height; ++row) {
    for (int col = 0; col < grid.width; ++col) {
      const Eigen::Vector2d p = grid.Node(col, row);
      const Eigen::Vector3d geo = m.georef.EnuToGeodetic(p.x(), p.y(), 0.0);
      const std::size_t k = static_cast<std::size_t>(row) * grid.width + col;
      lat[k] = geo.x();
      lon[k] = geo.y();
    }
  }
  std::vector<double> X = lon, Y = lat;
  std::vector<int> ok(n, 0);
  m.to_raster->Transform(static_cast<int>(n), X.data(), Y.data(), nullptr, ok.data());
  const DemRaster& r = m.raster;
  const auto& g = r.geotransform;
  auto cell = [&](const std::vector<float>& band, int c, int rr) {
    return band[static_cast<std::size_t>(rr) * r.width + c];
  };
  for (std::size_t k = 0; k < n; ++k) {
    if (!ok[k]) continue;
    const double u = (X[k] - g[0]) / g[1] - 0.5;
    const double v = (Y[k] - g[3]) / g[5] - 0.5;
    if (!(u >= 0.0 && v >= 0.0 && u <= r.width - 1 && v <= r.height - 1)) continue;
    const int c = std::min(static_cast<int>(u), std::max(r.width - 2, 0));
    const int rr = std::min(static_cast<int>(v), std::max(r.height - 2, 0));
    const int c1 = std::min(c + 1, r.width - 1);
    const int r1 = std::min(rr + 1, r.height - 1);
    const double fu = u - c;
    const double fv = v - rr;
    const double wts[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
    const int cs[4] = {c, c1, c, c1};
    const int rs[4] = {rr, rr, r1, r1};
    double z = 0.0, var = 0.0;
    bool valid = true;
    for (int q = 0; q < 4 && valid; ++q) {
      const float zq = cell(r.elevation_m, cs[q], rs[q]);
      if (!std::isfinite(zq)) valid = false;
      z += wts[q] * zq;
      const double sq = m.sigma_band ? cell(r.stddev_m, cs[q], rs[q]) : m.sigma_m;
      if (!(sq > 0.0)) valid = false;
      var += wts[q] * sq * sq;
    }
    if (!valid) continue;
    // The height above the file's ellipsoid (or sphere) as world z.
    const Eigen::Vector3d enu = m.georef.GeodeticToEnu(lat[k], lon[k], z + m.datum_altitude_m);
    grid.z_m[k] = static_cast<float>(enu.z());
    grid.sigma_m[k] = static_cast<float>(std::sqrt(var));
  }
  return grid;
}

}  // namespace rovermap::io
