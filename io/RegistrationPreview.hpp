#pragma once

#include <Eigen/Geometry>
#include <filesystem>
#include <string>

#include "registration/PointCloud.hpp"

namespace rovermap::io {

struct PreviewOptions {
  int panel_size_px = 600;  ///< width and height of each panel [px]
  std::string title;        ///< written above the panels
};

/// Writes a PNG with two panels, "initial" and "registered": the target (blue) and the
/// source moved by T_init and by T_final (orange), projected onto the plane of the target's
/// two largest principal axes, so a person can see the alignment at a glance.
/// Written atomically. Throws IoError naming the file if it cannot be written, and
/// std::invalid_argument if a cloud is empty.
void WriteRegistrationPreview(const std::filesystem::path& path,
                              const registration::PointCloud& source,
                              const registration::PointCloud& target,
                              const Eigen::Isometry3d& T_init, const Eigen::Isometry3d& T_final,
                              const PreviewOptions& options = {});

}  // namespace rovermap::io
