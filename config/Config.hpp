#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "campaign/CampaignOptions.hpp"
#include "config/ConfigError.hpp"
#include "dem/ElevationMap.hpp"
#include "dem/OctoMapOptions.hpp"
#include "eval/EvalOptions.hpp"
#include "io/BagOptions.hpp"
#include "mapper/GraphOptions.hpp"
#include "mapper/ReferenceOptions.hpp"
#include "mapper/MapperOptions.hpp"
#include "mapper/ServeOptions.hpp"
#include "mosaic/MosaicOptions.hpp"
#include "registration/Options.hpp"
#include "sim/SimOptions.hpp"
#include "stereo/StereoOptions.hpp"
#include "terrain/TerrainOptions.hpp"

namespace rovermap::config {

/// `bag.`: io::BagOptions as keys, plus what BagOptionsFrom turns into its transform and
/// origin.
struct BagConfig : io::BagOptions {
  std::vector<double> T_body_sensor_translation = {0.0, 0.0, 0.0};  ///< [m] x y z
  /// [deg] R_body_sensor = Rz(y)·Ry(p)·Rx(r) (docs/design.md §4): a level, forward-looking camera.
  std::vector<double> T_body_sensor_rpy_deg = {-90.0, 0.0, -90.0};
  double origin_latitude_deg = 0.0;   ///< [deg]
  double origin_longitude_deg = 0.0;  ///< [deg]
  double origin_altitude_m = 0.0;     ///< [m]
  bool origin_given = false;          ///< an origin key was set (file or --set)
};

/// Every module's options, one plain struct per section. Defaults live in the structs; the
/// keys (`<section>.<field>`) are listed in config/default.yaml and by KnownKeys().
struct Config {
  registration::RegistrationOptions registration;
  stereo::StereoOptions stereo;
  sim::SimOptions sim;
  dem::ElevationMapOptions dem;
  dem::OctoMapOptions octomap;
  terrain::TerrainOptions terrain;
  eval::EvalOptions eval;
  mapper::MapperOptions mapper;
  mapper::ServeOptions serve;
  mapper::GraphOptions graph;
  mapper::ReferenceOptions reference;
  mapper::RevisitOptions revisit;
  BagConfig bag;
  mosaic::MosaicOptions mosaic;
  campaign::CampaignOptions campaign;
};

/// The options a bag is read with: T_body_sensor from its translation and angles, the origin
/// keys as the origin when one was given (else as the fallback after a NavSatFix).
io::BagOptions BagOptionsFrom(const BagConfig& bag);

/// Builds a Config: the struct defaults, then `file` (nested YAML, one mapping per section),
/// then each override `key=value` in order (the value is parsed as YAML), so later wins.
/// @throw ConfigError if the file is missing or is not valid YAML (message: file and line), a
///        key is unknown (with the closest known key), a value has the wrong type or is out of
///        range (message: the key, and file and line when from the file), or an override has no
///        '='.
Config LoadConfig(const std::optional<std::filesystem::path>& file,
                  const std::vector<std::string>& overrides);

/// LoadConfig with the file's text already read; `path` only names it in messages.
/// @throw ConfigError as LoadConfig.
Config ParseConfig(std::string_view yaml, const std::filesystem::path& path,
                   const std::vector<std::string>& overrides);

/// Every key with its current value and a `# [unit] doc` comment, grouped by section: the
/// layout of config/default.yaml, and loadable by LoadConfig to give `config` back.
std::string DumpYaml(const Config& config);

/// Every dotted key, in the order of DumpYaml.
std::vector<std::string> KnownKeys();

}  // namespace rovermap::config
