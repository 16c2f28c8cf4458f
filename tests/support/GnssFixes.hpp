#pragma once
// GNSS fixes made from a ground truth, for the tests that write a gnss.csv.

#include <Eigen/Core>

#include "io/Georeference.hpp"
#include "io/Gnss.hpp"
#include "io/Tum.hpp"

namespace rovermap::testing {

/// A fix of `pose`'s body origin moved by `offset` [m, ENU], reporting σ `sigma_m` everywhere.
inline io::GnssFix FixOf(const io::StampedPose& pose, const io::Georeference& georef,
                         const Eigen::Vector3d& offset, double sigma_m) {
  const Eigen::Vector3d p = pose.T_world_body.translation() + offset;
  const Eigen::Vector3d geo = georef.EnuToGeodetic(p.x(), p.y(), p.z());
  io::GnssFix f;
  f.timestamp = pose.timestamp;
  f.latitude_deg = geo.x();
  f.longitude_deg = geo.y();
  f.altitude_m = geo.z();
  f.sigma_enu_m = Eigen::Vector3d::Constant(sigma_m);
  return f;
}

}  // namespace rovermap::testing
