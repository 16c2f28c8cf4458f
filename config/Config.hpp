#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config/ConfigError.hpp"
#include "dem/ElevationMap.hpp"
#include "dem/OctoMapOptions.hpp"
#include "eval/EvalOptions.hpp"
#include "mapper/MapperOptions.hpp"
#include "mapper/ServeOptions.hpp"
#include "registration/Options.hpp"
#include "sim/SimOptions.hpp"
#include "stereo/StereoOptions.hpp"

namespace rovermap::config {

/// Every module's options, one plain struct per section. Defaults live in the structs; the
/// keys (`<section>.<field>`) are listed in config/default.yaml and by KnownKeys().
struct Config {
  registration::RegistrationOptions registration;
  stereo::StereoOptions stereo;
  sim::SimOptions sim;
  dem::ElevationMapOptions dem;
  dem::OctoMapOptions octomap;
  eval::EvalOptions eval;
  mapper::MapperOptions mapper;
  mapper::ServeOptions serve;
};

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
