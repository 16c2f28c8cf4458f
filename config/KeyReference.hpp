#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace rovermap::config {

/// A preset configuration file: `name` as the page shows it ("config/presets/fast.yaml"),
/// `path` where it is read from.
struct PresetFile {
  std::string name;
  std::filesystem::path path;
};

/// The presets in `source_dir`/config/presets (every *.yaml), by name.
std::vector<PresetFile> FindPresets(const std::filesystem::path& source_dir);

/// Writes the configuration reference, docs/configuration.md, as Markdown: one section per key
/// group with a table of every key (default as DumpYaml prints it, unit, valid values, help),
/// all from the key registry behind LoadConfig, then each preset with the keys it changes.
/// @throw ConfigError if a preset does not load.
void WriteKeyReference(std::ostream& out, const std::vector<PresetFile>& presets);

/// "a \| b": `text` fit for a Markdown table cell (pipes escaped, line breaks as spaces).
std::string TableCell(const std::string& text);

}  // namespace rovermap::config
