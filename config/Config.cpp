#include "config/Config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <sstream>

#include "config/Keys.hpp"
#include "io/Rpy.hpp"

namespace rovermap::config {
namespace {

using detail::KeyEntry;
using detail::Registry;

// Where the values being applied come from, for messages and duplicate detection.
struct Source {
  std::string file;                  // empty for overrides
  std::map<std::string, int> lines;  // key -> line it was first set on (file only)
};

std::string Where(const Source& source, const YAML::Mark& mark) {
  if (source.file.empty()) return "";
  if (mark.is_null()) return source.file + ": ";
  return source.file + ":" + std::to_string(mark.line + 1) + ": ";
}

const KeyEntry* FindKey(const std::string& key) {
  for (const KeyEntry& entry : Registry()) {
    if (entry.key == key) return &entry;
  }
  return nullptr;
}

// "registration" is a section: some key starts with "registration.".
bool IsSection(const std::string& prefix) {
  return std::any_of(Registry().begin(), Registry().end(), [&](const KeyEntry& entry) {
    return entry.key.compare(0, prefix.size() + 1, prefix + ".") == 0;
  });
}

std::vector<std::string> SectionsOf(const std::string& key) {
  std::vector<std::string> parts;
  std::stringstream stream(key);
  for (std::string part; std::getline(stream, part, '.');) parts.push_back(part);
  parts.pop_back();  // the leaf
  return parts;
}

std::string LastPart(const std::string& key) { return key.substr(key.rfind('.') + 1); }

std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// " (did you mean registration.max_iterations?)" for a near miss or a missing section, else "".
std::string Suggestion(const std::string& unknown) {
  std::vector<std::string> candidates;
  for (const KeyEntry& entry : Registry()) {
    candidates.push_back(entry.key);
    for (const std::string& section : SectionsOf(entry.key)) candidates.push_back(section);
  }
  std::string best;
  std::size_t best_distance = unknown.size() / 3 + 1;
  for (const std::string& candidate : candidates) {
    // A missing section or a truncated name is as good a hint as a typo.
    const bool same_leaf = LastPart(candidate) == LastPart(unknown);
    const bool truncated = candidate.compare(0, unknown.size(), unknown) == 0;
    const std::size_t distance = same_leaf ? 0 : (truncated ? 1 : EditDistance(unknown, candidate));
    if (distance < best_distance) {
      best = candidate;
      best_distance = distance;
    }
  }
  return best.empty() ? "" : " (did you mean " + best + "?)";
}

std::string Got(const YAML::Node& node) {
  if (node.IsScalar()) return " (got " + node.Scalar() + ")";
  if (node.IsSequence()) return " (got a list)";
  return "";
}

// Applies `value` to `key`: a key's value, or a section's mapping walked key by key.
void Apply(Config& config, Source& source, const std::string& key, const YAML::Node& value,
           const YAML::Mark& key_mark) {
  const YAML::Mark value_mark = value.Mark().is_null() ? key_mark : value.Mark();
  if (const KeyEntry* entry = FindKey(key)) {
    if (!source.file.empty()) {
      const auto [first, inserted] = source.lines.emplace(key, value_mark.line + 1);
      if (!inserted) {
        throw ConfigError(Where(source, key_mark) + key + ": set twice (first on line " +
                          std::to_string(first->second) + ")");
      }
    }
    try {
      entry->parse(value, config);
    } catch (const detail::ValueError& error) {
      throw ConfigError(Where(source, value_mark) + key + ": " + error.what());
    }
    return;
  }
  if (!IsSection(key)) {
    const char* what = value.IsMap() ? ": unknown section" : ": unknown key";
    throw ConfigError(Where(source, key_mark) + key + what + Suggestion(key));
  }
  if (value.IsNull()) return;  // an empty section keeps its defaults
  if (!value.IsMap()) {
    throw ConfigError(Where(source, value_mark) + key +
                      ": is a section, expected a mapping of its keys" + Got(value));
  }
  for (const auto& item : value) {
    if (!item.first.IsScalar()) {
      throw ConfigError(Where(source, item.first.Mark()) + key + ": keys must be plain names");
    }
    Apply(config, source, key + "." + item.first.Scalar(), item.second, item.first.Mark());
  }
}

std::string ReadConfigFile(const std::filesystem::path& file) {
  std::error_code error;
  const auto status = std::filesystem::status(file, error);
  // Only "not found" means missing: a directory we may not enter (EACCES) hides the file.
  if (error && error != std::errc::no_such_file_or_directory) {
    throw ConfigError(file.string() + ": cannot access config file (" + error.message() + ")");
  }
  if (!std::filesystem::exists(status)) throw ConfigError(file.string() + ": no such config file");
  if (std::filesystem::is_directory(status)) {
    throw ConfigError(file.string() + ": is a directory, not a config file");
  }
  std::optional<std::string> text = detail::ReadText(file);
  if (!text) {
    throw ConfigError(file.string() + ": cannot read config file (" + std::strerror(errno) + ")");
  }
  return std::move(*text);
}

// Returns the keys the file set, each with its line.
std::map<std::string, int> ApplyYaml(Config& config, std::string_view yaml,
                                     const std::filesystem::path& file) {
  Source source{file.string(), {}};
  YAML::Node root;
  try {
    root = YAML::Load(std::string(yaml));
  } catch (const YAML::Exception& e) {
    const std::string where = e.mark.is_null()
                                  ? source.file
                                  : source.file + ":" + std::to_string(e.mark.line + 1) + ":" +
                                        std::to_string(e.mark.column + 1);
    throw ConfigError(where + ": invalid YAML: " + e.msg);
  }
  if (root.IsNull()) return {};  // an empty file keeps the defaults
  if (!root.IsMap()) {
    throw ConfigError(Where(source, root.Mark()) +
                      "expected a mapping of sections (e.g. registration:) at the top level" +
                      Got(root));
  }
  for (const auto& item : root) {
    if (!item.first.IsScalar()) {
      throw ConfigError(Where(source, item.first.Mark()) + "section names must be plain names");
    }
    Apply(config, source, item.first.Scalar(), item.second, item.first.Mark());
  }
  return source.lines;
}

std::string Trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

void ApplyOverride(Config& config, const std::string& text) {
  const auto equals = text.find('=');
  const std::string key = Trim(text.substr(0, equals));
  if (equals == std::string::npos || key.empty()) {
    throw ConfigError("override \"" + text + "\": expected key=value");
  }
  const std::string value_text = text.substr(equals + 1);
  YAML::Node value;
  try {
    value = YAML::Load(value_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(key + ": cannot parse value \"" + value_text + "\": " + e.msg);
  }
  Source source;
  Apply(config, source, key, value, YAML::Mark::null_mark());
}

}  // namespace

namespace detail {

const std::vector<KeyRule>& Rules() {
  using Broken = std::optional<std::string>;
  // "must be VALID (got VALUE)", the message of most rules.
  auto must_be = [](const std::string& valid, const std::string& got = "") -> Broken {
    return "must be " + valid + (got.empty() ? "" : " (got " + got + ")");
  };
  auto three_numbers = [](const std::vector<double>& list) -> Broken {
    if (list.size() == 3) return std::nullopt;
    return "expected a list of 3 numbers (got " + std::to_string(list.size()) + ")";
  };
  static const std::vector<KeyRule> rules = {
      {"registration.residual", "not point_to_plane with geometry: curve",
       [](const Config& c) -> Broken {
         if (c.registration.geometry != registration::Geometry::kCurve ||
             c.registration.residual != registration::Residual::kPointToPlane) {
           return std::nullopt;
         }
         return "point_to_plane needs surface normals; with geometry: curve set "
                "registration.residual=auto or point_to_point";
       }},
      {"stereo.num_disparities", "a multiple of 16",
       [must_be](const Config& c) -> Broken {
         const int n = c.stereo.num_disparities;
         return n % 16 == 0 ? std::nullopt : must_be("a multiple of 16", std::to_string(n));
       }},
      {"stereo.block_size", "odd",
       [must_be](const Config& c) -> Broken {
         const int n = c.stereo.block_size;
         return n % 2 != 0 ? std::nullopt : must_be("odd", std::to_string(n));
       }},
      {"stereo.subpixel_window_px", "0 or odd and >= 3",
       [must_be](const Config& c) -> Broken {
         const int n = c.stereo.subpixel_window_px;
         if (n == 0 || (n >= 3 && n % 2 != 0)) return std::nullopt;
         return must_be("0 or odd and >= 3", std::to_string(n));
       }},
      {"stereo.block_size", "in [5, 255] with algorithm: bm",
       [must_be](const Config& c) -> Broken {
         const auto& st = c.stereo;
         const bool fits = st.block_size >= 5 && st.block_size <= 255;
         if (st.algorithm != stereo::Algorithm::kBm || fits) return std::nullopt;
         return must_be("in [5, 255] with algorithm: bm");
       }},
      {"stereo.p2", "> stereo.p1 when both are > 0",
       [must_be](const Config& c) -> Broken {
         const auto& st = c.stereo;
         if (st.p1 > 0 && st.p2 > 0 && st.p2 <= st.p1) return must_be("> stereo.p1");
         return std::nullopt;
       }},
      {"stereo.max_range_m", "> stereo.min_range_m",
       [must_be](const Config& c) -> Broken {
         if (c.stereo.max_range_m > c.stereo.min_range_m) return std::nullopt;
         return must_be("> stereo.min_range_m");
       }},
      {"sim.image_height",
       "sim.image_width x sim.image_height <= " + std::to_string(kMaxImagePixels) + " pixels",
       [](const Config& c) -> Broken {
         const long long pixels = static_cast<long long>(c.sim.image_width) * c.sim.image_height;
         if (pixels <= kMaxImagePixels) return std::nullopt;
         return "sim.image_width x sim.image_height = " + std::to_string(pixels) +
                " pixels, more than " + std::to_string(kMaxImagePixels);
       }},
      {"bag.T_body_sensor_translation", "exactly 3 of them",
       [three_numbers](const Config& c) { return three_numbers(c.bag.T_body_sensor_translation); }},
      {"bag.T_body_sensor_rpy_deg", "exactly 3 of them",
       [three_numbers](const Config& c) { return three_numbers(c.bag.T_body_sensor_rpy_deg); }},
      {"sim.reference_offset_m", "exactly 2 of them",
       [](const Config& c) -> Broken {
         if (c.sim.reference_offset_m.size() == 2) return std::nullopt;
         return "expected a list of 2 numbers (got " +
                std::to_string(c.sim.reference_offset_m.size()) + ")";
       }},
      {"graph.gnss_antenna_m", "exactly 3 of them",
       [three_numbers](const Config& c) { return three_numbers(c.graph.gnss_antenna_m); }},
      {"sim.terrain_cell_m", "sim.terrain_size_m / sim.terrain_cell_m < 20000",
       [](const Config& c) -> Broken {
         if (c.sim.terrain_size_m / c.sim.terrain_cell_m < 20000) return std::nullopt;
         return "too small for sim.terrain_size_m (more than 20000 samples along an edge)";
       }},
  };
  return rules;
}

std::vector<std::string> KeysSetIn(const std::filesystem::path& file) {
  Config config;
  const std::map<std::string, int> lines = ApplyYaml(config, ReadConfigFile(file), file);
  std::vector<std::string> keys;
  for (const auto& [key, line] : lines) keys.push_back(key);
  std::stable_sort(keys.begin(), keys.end(), [&](const std::string& a, const std::string& b) {
    return lines.at(a) < lines.at(b);
  });
  return keys;
}

}  // namespace detail

// Checks between keys, after every source has been applied: the first broken rule.
static void ValidateCombinations(const Config& config) {
  for (const detail::KeyRule& rule : detail::Rules()) {
    if (const std::optional<std::string> broken = rule.check(config)) {
      throw ConfigError(rule.key + ": " + *broken);
    }
  }
}

Config LoadConfig(const std::optional<std::filesystem::path>& file,
                  const std::vector<std::string>& overrides) {
  if (file) return ParseConfig(ReadConfigFile(*file), *file, overrides);
  return ParseConfig("", {}, overrides);  // empty YAML: the defaults
}

Config ParseConfig(std::string_view yaml, const std::filesystem::path& path,
                   const std::vector<std::string>& overrides) {
  Config config;
  ApplyYaml(config, yaml, path);
  for (const std::string& override_text : overrides) ApplyOverride(config, override_text);
  ValidateCombinations(config);
  return config;
}

std::string DumpYaml(const Config& config) {
  // Section headers open as the dotted path changes (the registry keeps sections together);
  // the comments of a top-level section line up.
  struct Line {
    std::string text;
    std::string comment;
  };
  std::vector<std::vector<Line>> blocks;
  std::vector<std::string> open;
  for (const KeyEntry& entry : Registry()) {
    const std::vector<std::string> sections = SectionsOf(entry.key);
    std::size_t common = 0;
    while (common < open.size() && common < sections.size() && open[common] == sections[common]) {
      ++common;
    }
    if (common == 0) blocks.emplace_back();
    for (std::size_t depth = common; depth < sections.size(); ++depth) {
      blocks.back().push_back({std::string(2 * depth, ' ') + sections[depth] + ":", ""});
    }
    open = sections;
    blocks.back().push_back(
        {std::string(2 * sections.size(), ' ') + LastPart(entry.key) + ": " + entry.print(config),
         entry.doc});
  }

  std::string yaml;
  for (const std::vector<Line>& block : blocks) {
    std::size_t width = 0;
    for (const Line& line : block) width = std::max(width, line.text.size());
    if (!yaml.empty()) yaml += "\n";
    for (const Line& line : block) {
      yaml += line.text;
      if (!line.comment.empty()) {
        yaml += std::string(width - line.text.size() + 2, ' ') + "# " + line.comment;
      }
      yaml += "\n";
    }
  }
  return yaml;
}

io::BagOptions BagOptionsFrom(const BagConfig& bag) {
  io::BagOptions options = bag;
  const std::vector<double>& t = bag.T_body_sensor_translation;
  const std::vector<double>& rpy = bag.T_body_sensor_rpy_deg;
  options.T_body_sensor.translation() = Eigen::Vector3d(t.at(0), t.at(1), t.at(2));
  options.T_body_sensor.linear() = io::RotationFromRpyDeg(rpy.at(0), rpy.at(1), rpy.at(2));
  options.default_origin = {bag.origin_latitude_deg, bag.origin_longitude_deg,
                            bag.origin_altitude_m};
  if (bag.origin_given) options.origin = options.default_origin;
  return options;
}

std::vector<std::string> KnownKeys() {
  std::vector<std::string> keys;
  for (const KeyEntry& entry : Registry()) keys.push_back(entry.key);
  return keys;
}

}  // namespace rovermap::config
