#pragma once
// Where the local ENU world frame (docs/design.md §3) lies on its body, and the projected CRS of
// the map products (docs/design.md §6).
//
// Earth: the UTM zone of the origin (EPSG 326zz north, 327zz south; UPS 32661/32761 beyond
// UTM's latitude limits), on WGS 84. Moon and Mars: a transverse Mercator centred on the origin
// (scale 1, false easting/northing 0) on the IAU sphere, radius 1737400 m / 3396190 m.
//
// ENU -> projection. At the origin the projection is ENU rotated by the meridian convergence γ
// (grid north is γ clockwise from true north) and scaled by s = k·R/(R + h0), the point scale k
// of the projection times the reduction of the origin's altitude h0 to the surface:
//   (E, N) = (E0, N0) + s·R(γ)·(x, y).
// γ and s are the linear part of GeographicLib's exact chain (LocalCartesian -> UTMUPS or
// TransverseMercator) at the origin, taken by central differences.
// ElevationMap lays its cells out in that rotated grid (ElevationMapOptions::grid_rotation_rad
// = convergence_rad()), so the GeoTIFF is north-up in the projection with an affine
// geotransform and no resampling. The remaining error is second order in the distance d from
// the origin (d²/R); GridToProjected vs the exact GeographicLib chain is measured in
// tests/test_geotiff.cpp (millimetres at a few hundred metres).
//
// Heights: map elevations are world z, i.e. height above the origin's altitude (its
// ellipsoidal height on Earth, height above the sphere elsewhere) along the origin's up axis.
// No curvature correction: the surface of the body drops d²/(2R) below the plane (8 mm at
// 320 m, 8 cm at 1 km on Earth).

#include <Eigen/Core>
#include <string>

namespace rovermap::io {

/// The body the sequence was recorded on (sequence.yaml `body:`).
enum class Body { kEarth, kMoon, kMars };

/// "earth", "moon", "mars" -> Body. @throw std::invalid_argument naming the value otherwise.
Body ParseBody(const std::string& name);
/// Mean radius of the IAU sphere used for Moon/Mars [m]; Earth: WGS 84 equatorial radius.
double BodyRadiusM(Body body);

/// The geodetic origin of the world frame.
struct GeodeticOrigin {
  double latitude_deg = 0.0;   ///< [deg] in [-90, 90]
  double longitude_deg = 0.0;  ///< [deg] in [-180, 180]
  double altitude_m = 0.0;     ///< [m] ellipsoidal height (Earth) or above the sphere
};

/// The projected CRS of one sequence and the mapping of its ENU frame into it. Cheap to copy.
class Georeference {
 public:
  /// @throw std::invalid_argument if the origin is not finite or out of range.
  explicit Georeference(const GeodeticOrigin& origin, Body body = Body::kEarth);

  const GeodeticOrigin& origin() const { return origin_; }
  Body body() const { return body_; }
  /// EPSG code of the CRS on Earth (32601..32660, 32701..32760, 32661, 32761); 0 elsewhere.
  int epsg() const { return epsg_; }
  /// UTM zone (1..60) on Earth, 0 for UPS or other bodies.
  int utm_zone() const { return zone_; }
  bool north() const { return north_; }
  /// The CRS as OGC WKT (what the GeoTIFF carries).
  const std::string& wkt() const { return wkt_; }
  /// Meridian convergence at the origin [rad]: the counter-clockwise angle from ENU to the
  /// projection's grid axes. Give it to ElevationMapOptions::grid_rotation_rad.
  double convergence_rad() const { return convergence_rad_; }
  /// Projected metres per ENU metre at the origin [ratio]: point scale × altitude reduction.
  double scale_factor() const { return scale_; }
  /// Projected coordinates of the origin (E0, N0) [m].
  const Eigen::Vector2d& origin_projected() const { return origin_projected_; }

  /// Affine map from grid-frame coordinates (ElevationMap::WorldToGrid with this convergence)
  /// to projected coordinates: (E0, N0) + k·g [m]. Never fails.
  Eigen::Vector2d GridToProjected(const Eigen::Vector2d& grid_m) const {
    return origin_projected_ + scale_ * grid_m;
  }

  /// Exact chain through GeographicLib: ENU (x, y, z) -> geodetic -> projection [m], in this
  /// CRS's zone. For checks and eval; not used for writing rasters.
  Eigen::Vector2d EnuToProjectedExact(double x_m, double y_m, double z_m = 0.0) const;
  /// ENU -> (latitude deg, longitude deg, height m) through GeographicLib.
  Eigen::Vector3d EnuToGeodetic(double x_m, double y_m, double z_m = 0.0) const;
  /// (latitude deg, longitude deg, height m) -> ENU [m] through GeographicLib: a GNSS fix in
  /// the world frame.
  Eigen::Vector3d GeodeticToEnu(double latitude_deg, double longitude_deg, double height_m) const;

 private:
  Eigen::Vector2d ProjectGeodetic(double lat_deg, double lon_deg) const;

  GeodeticOrigin origin_;
  Body body_ = Body::kEarth;
  int epsg_ = 0;
  int zone_ = 0;
  bool north_ = true;
  std::string wkt_;
  double convergence_rad_ = 0.0;
  double scale_ = 1.0;
  Eigen::Vector2d origin_projected_ = Eigen::Vector2d::Zero();
  double radius_m_ = 0.0;  // sphere radius for Moon/Mars
};

}  // namespace rovermap::io
