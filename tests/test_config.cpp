#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "config/Config.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::config {
namespace {

namespace fs = std::filesystem;
using registration::Convergence;
using registration::Criterion;
using registration::Geometry;
using registration::RegistrationOptions;
using registration::Residual;
using registration::Solver;

const fs::path kDefaultYaml = fs::path(ROVERMAP_SOURCE_DIR) / "config" / "default.yaml";

// EXPECT_TRUE(Contains(text, part)) prints both on failure (no gmock here).
::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "\"" << text << "\"\n does not contain \"" << part << "\"";
}

// Writes `text` to a fresh file in the test's temporary directory.
fs::path WriteFile(const std::string& name, const std::string& text) {
  const fs::path dir = rovermap::testing::ScratchDir();
  fs::create_directories(dir);
  const fs::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream stream(path);
  std::stringstream text;
  text << stream.rdbuf();
  return text.str();
}

// The message of the ConfigError that `load` throws, or a test failure.
std::string ErrorOf(const std::function<void()>& load) {
  return rovermap::testing::ErrorOf<ConfigError>(load);
}

std::string OverrideError(const std::string& override_text) {
  return ErrorOf([&] { LoadConfig(std::nullopt, {override_text}); });
}

std::string FileError(const std::string& name, const std::string& text) {
  const fs::path path = WriteFile(name, text);
  return ErrorOf([&] { LoadConfig(path, {}); });
}

// Reads DumpYaml's layout back into (dotted key, value) pairs, in order: sections are "name:"
// lines, two spaces of indent per level, comments after "  #". Deliberately not yaml-cpp, which
// only config/ uses.
std::vector<std::pair<std::string, std::string>> ParseDump(const std::string& yaml) {
  std::vector<std::pair<std::string, std::string>> entries;
  std::vector<std::string> sections;
  std::istringstream stream(yaml);
  for (std::string line; std::getline(stream, line);) {
    const auto indent = line.find_first_not_of(' ');
    if (indent == std::string::npos || line[indent] == '#') continue;
    std::string content = line.substr(indent, line.find("  #") - indent);
    content.erase(content.find_last_not_of(' ') + 1);
    const auto colon = content.find(':');
    const std::string name = content.substr(0, colon);
    const std::string value = colon + 1 < content.size() ? content.substr(colon + 2) : "";
    sections.resize(indent / 2);
    if (value.empty()) {
      sections.push_back(name);
      continue;
    }
    std::string key;
    for (const std::string& section : sections) key += section + ".";
    entries.emplace_back(key + name, value);
  }
  return entries;
}

std::map<std::string, std::string> Values(const Config& config) {
  const auto entries = ParseDump(DumpYaml(config));
  return {entries.begin(), entries.end()};
}

void ExpectSameRegistration(const RegistrationOptions& a, const RegistrationOptions& b) {
  EXPECT_EQ(a.geometry, b.geometry);
  EXPECT_EQ(a.criterion, b.criterion);
  EXPECT_EQ(a.solver, b.solver);
  EXPECT_EQ(a.residual, b.residual);
  EXPECT_EQ(a.reference_distance_m, b.reference_distance_m);
  EXPECT_EQ(a.dmax_initial_factor, b.dmax_initial_factor);
  EXPECT_EQ(a.histogram_bins, b.histogram_bins);
  EXPECT_EQ(a.histogram_valley_ratio, b.histogram_valley_ratio);
  EXPECT_EQ(a.max_iterations, b.max_iterations);
  EXPECT_EQ(a.convergence, b.convergence);
  EXPECT_EQ(a.relative_tolerance, b.relative_tolerance);
  EXPECT_EQ(a.translation_tolerance_m, b.translation_tolerance_m);
  EXPECT_EQ(a.rotation_tolerance_deg, b.rotation_tolerance_deg);
  EXPECT_EQ(a.acceleration, b.acceleration);
  EXPECT_EQ(a.anderson_depth, b.anderson_depth);
  EXPECT_EQ(a.orientation_threshold_deg, b.orientation_threshold_deg);
  EXPECT_EQ(a.normal_neighbors, b.normal_neighbors);
  EXPECT_EQ(a.sample_voxel_factor, b.sample_voxel_factor);
  EXPECT_EQ(a.coarse_to_fine, b.coarse_to_fine);
  EXPECT_EQ(a.coarse_iterations, b.coarse_iterations);
  EXPECT_EQ(a.coarse_step, b.coarse_step);
  EXPECT_EQ(a.use_uncertainty, b.use_uncertainty);
  EXPECT_EQ(a.mahalanobis_gate, b.mahalanobis_gate);
  EXPECT_EQ(a.seed_rotation_sigma_deg, b.seed_rotation_sigma_deg);
  EXPECT_EQ(a.seed_translation_sigma_m, b.seed_translation_sigma_m);
  EXPECT_EQ(a.min_pairs, b.min_pairs);
  EXPECT_EQ(a.reuse_closest_points, b.reuse_closest_points);
}

// Counts an aggregate's fields: the most initialisers T{...} accepts.
struct AnyField {
  template <typename T>
  operator T() const;
};
template <typename T, typename... A>
constexpr auto BraceConstructible(int) -> decltype(T{std::declval<A>()...}, true) {
  return true;
}
template <typename T, typename... A>
constexpr bool BraceConstructible(long) {
  return false;
}
template <typename T, typename... A>
constexpr std::size_t CountFields() {
  if constexpr (BraceConstructible<T, A..., AnyField>(0)) {
    return CountFields<T, A..., AnyField>();
  } else {
    return sizeof...(A);
  }
}

// ---- default.yaml can never go stale ------------------------------------------------------

TEST(DefaultYaml, LoadsToExactlyTheStructDefaults) {
  const Config loaded = LoadConfig(kDefaultYaml, {});
  ExpectSameRegistration(loaded.registration, RegistrationOptions{});
  EXPECT_EQ(DumpYaml(loaded), DumpYaml(Config{}));
}

TEST(DefaultYaml, ListsEveryKnownKeyInOrder) {
  std::vector<std::string> listed;
  for (const auto& [key, value] : ParseDump(ReadFile(kDefaultYaml))) listed.push_back(key);
  EXPECT_EQ(listed, KnownKeys());
}

TEST(DefaultYaml, BodyIsTheDumpOfTheDefaults) {
  // Everything after the leading comment block, comments and alignment included.
  const std::string text = ReadFile(kDefaultYaml);
  std::istringstream stream(text);
  std::string body;
  bool in_header = true;
  for (std::string line; std::getline(stream, line);) {
    if (in_header && (line.empty() || line[0] == '#')) continue;
    in_header = false;
    body += line + "\n";
  }
  EXPECT_EQ(body, DumpYaml(Config{})) << "config/default.yaml is stale: its body must be this "
                                         "dump of the defaults";
}

// ---- the key table ---------------------------------------------------------------------------

TEST(Keys, EveryRegistrationFieldHasAKey) {
  const auto keys = KnownKeys();
  const auto registration_keys = std::count_if(keys.begin(), keys.end(), [](const std::string& k) {
    return k.rfind("registration.", 0) == 0;
  });
  EXPECT_EQ(static_cast<std::size_t>(registration_keys), CountFields<RegistrationOptions>())
      << "a RegistrationOptions field has no key: add one line to config/Keys.cpp";
}

TEST(Keys, ContractNamesFromDesign) {
  const auto keys = KnownKeys();
  for (const char* key :
       {"registration.geometry", "registration.criterion", "registration.reference_distance",
        "registration.max_iterations", "registration.orientation_threshold_deg",
        "registration.coarse_to_fine", "registration.solver", "registration.use_uncertainty"}) {
    EXPECT_NE(std::find(keys.begin(), keys.end(), key), keys.end()) << key;
  }
}

TEST(Keys, DumpListsEveryKeyOnce) {
  std::vector<std::string> dumped;
  for (const auto& [key, value] : ParseDump(DumpYaml(Config{}))) dumped.push_back(key);
  EXPECT_EQ(dumped, KnownKeys());
}

// Each key writes its own field and prints it back: changing one key changes that line only.
TEST(Keys, EveryKeyWritesAndPrintsItsOwnField) {
  const std::vector<std::string> candidates = {
      "true",
      "false",
      "7",
      "3",
      "0.5",
      "0.25",
      "2",
      "curve",
      "symmetric",
      "dual_quaternion",
      "point_to_plane",
      "point_to_point",
      "relative",
      "sgbm",
      "32",
      "straight",
      "cloud",
      "64",
      "0.75",
      "none",
      "local_map",  // octomap.prob_hit: in (0.5, 1); acceleration; reference
      "tf",
      "tf_static",
      "moon",
      "[1.0, 2.0, 3.0]",  // bag.odometry_source, T_body_sensor_source, body, 3-vectors
      "[1.0, 2.0]",       // 2-vectors (sim.reference_offset_m)
      "0.01"};            // sim.baseline_error: in [0, 0.2]
  for (const std::string& key : KnownKeys()) {
    // geometry=curve is only valid with point_to_point residuals: start from there.
    std::vector<std::string> base;
    if (key == "registration.geometry") base.push_back("registration.residual=point_to_point");
    const auto defaults = Values(LoadConfig(std::nullopt, base));
    bool changed = false;
    for (const std::string& value : candidates) {
      Config config;
      try {
        std::vector<std::string> overrides = base;
        overrides.push_back(key + "=" + value);
        config = LoadConfig(std::nullopt, overrides);
      } catch (const ConfigError&) {
        continue;  // not a valid value for this key
      }
      auto values = Values(config);
      if (values.at(key) == defaults.at(key)) continue;
      values[key] = defaults.at(key);
      EXPECT_EQ(values, defaults) << key << "=" << value << " changed another key";
      changed = true;
      break;
    }
    EXPECT_TRUE(changed) << key << " could not be changed";
  }
}

TEST(Keys, BagKeysMapToBagOptions) {
  const Config defaults;
  io::BagOptions options = BagOptionsFrom(defaults.bag);
  EXPECT_EQ(options.left_image_topic, io::BagOptions().left_image_topic);
  EXPECT_FALSE(options.origin.has_value());  // no origin key: the bag's NavSatFix first
  // The default T_body_sensor: a level, forward-looking OpenCV camera (z forward = body x).
  EXPECT_TRUE(options.T_body_sensor.linear().col(2).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE(options.T_body_sensor.linear().col(0).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));

  const Config config = LoadConfig(
      std::nullopt, {"bag.sensor=cloud", "bag.cloud_topic=/velodyne_points",
                     "bag.odometry_source=tf", "bag.odometry_parent_frame=map",
                     "bag.T_body_sensor_source=tf_static", "bag.groundtruth_topic=/vicon/rover",
                     "bag.pair_tolerance_s=0.02", "bag.T_body_sensor_translation=[0.5, 0, 1.2]",
                     "bag.origin_altitude_m=12.5", "bag.body=mars"});
  options = BagOptionsFrom(config.bag);
  EXPECT_EQ(options.sensor_type, io::SensorType::kCloud);
  EXPECT_EQ(options.cloud_topic, "/velodyne_points");
  EXPECT_TRUE(options.odometry_from_tf);
  EXPECT_EQ(options.odometry_parent_frame, "map");
  EXPECT_TRUE(options.T_body_sensor_from_tf_static);
  EXPECT_EQ(options.groundtruth_topic, "/vicon/rover");
  EXPECT_EQ(options.pair_tolerance_s, 0.02);
  EXPECT_EQ(options.T_body_sensor.translation(), Eigen::Vector3d(0.5, 0.0, 1.2));
  EXPECT_EQ(options.body, "mars");
  // One origin key given: the keys are the origin, over any NavSatFix.
  ASSERT_TRUE(options.origin.has_value());
  EXPECT_EQ(options.origin->altitude_m, 12.5);
  EXPECT_EQ(options.origin->latitude_deg, 0.0);
  // An empty ground-truth topic is none.
  EXPECT_TRUE(LoadConfig(std::nullopt, {"bag.groundtruth_topic="}).bag.groundtruth_topic.empty());
}

TEST(ConfigErrors, BagKeysAreValidatedNamingTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"bag.pair_tolerance_s=-0.1", "bag.pair_tolerance_s: must be >= 0 (got -0.1)"},
      {"bag.odometry_source=imu", "bag.odometry_source: must be one of topic|tf (got imu)"},
      {"bag.left_image_topic=", "bag.left_image_topic: must not be empty"},
      {"bag.odometry_topic=odom topic", "bag.odometry_topic: not a topic or frame name"},
      {"bag.T_body_sensor_rpy_deg=[0, 0]",
       "bag.T_body_sensor_rpy_deg: expected a list of 3 numbers (got 2)"},
      {"bag.origin_latitude_deg=91", "bag.origin_latitude_deg: must be in [-90, 90] (got 91)"},
      {"bag.left_image=/x", "bag.left_image: unknown key (did you mean bag.left_image_topic?)"},
  };
  for (const auto& [override_text, message] : cases) {
    const std::string got =
        rovermap::testing::ErrorOf<ConfigError>([&] { LoadConfig(std::nullopt, {override_text}); });
    EXPECT_TRUE(rovermap::testing::Contains(got, message)) << override_text;
  }
}

// ---- loading -------------------------------------------------------------------------------

TEST(LoadConfig, NoFileNoOverridesGivesDefaults) {
  ExpectSameRegistration(LoadConfig(std::nullopt, {}).registration, RegistrationOptions{});
}

TEST(LoadConfig, FileSetsNestedKeysAndKeepsTheRest) {
  const fs::path path = WriteFile("nested.yaml",
                                  "registration:\n"
                                  "  max_iterations: 50\n"
                                  "  reference_distance: 0.25\n"
                                  "  coarse_to_fine: true\n"
                                  "  solver: dual_quaternion\n");
  const Config config = LoadConfig(path, {});
  EXPECT_EQ(config.registration.max_iterations, 50);
  EXPECT_EQ(config.registration.reference_distance_m, 0.25);
  EXPECT_TRUE(config.registration.coarse_to_fine);
  EXPECT_EQ(config.registration.solver, Solver::kDualQuaternion);
  EXPECT_EQ(config.registration.min_pairs, RegistrationOptions{}.min_pairs);
}

TEST(LoadConfig, EmptyFileAndEmptySectionKeepDefaults) {
  EXPECT_EQ(DumpYaml(LoadConfig(WriteFile("empty.yaml", "# nothing\n"), {})), DumpYaml(Config{}));
  EXPECT_EQ(DumpYaml(LoadConfig(WriteFile("section.yaml", "registration:\n"), {})),
            DumpYaml(Config{}));
}

TEST(LoadConfig, OverridesBeatTheFile) {
  const fs::path path = WriteFile("base.yaml", "registration: {max_iterations: 50, solver: svd}\n");
  const Config config = LoadConfig(path, {"registration.max_iterations=70"});
  EXPECT_EQ(config.registration.max_iterations, 70);
  EXPECT_EQ(config.registration.solver, Solver::kSvd);
}

TEST(LoadConfig, LaterOverridesBeatEarlierOnes) {
  const Config config =
      LoadConfig(std::nullopt, {"registration.max_iterations=5", "registration.max_iterations = 9",
                                "registration.solver=dual_quaternion", "registration.solver=svd"});
  EXPECT_EQ(config.registration.max_iterations, 9);
  EXPECT_EQ(config.registration.solver, Solver::kSvd);
}

TEST(LoadConfig, OverrideCanSetASectionAsAMapping) {
  const Config config =
      LoadConfig(std::nullopt, {"registration={max_iterations: 12, geometry: curve, "
                                "residual: point_to_point}"});
  EXPECT_EQ(config.registration.max_iterations, 12);
  EXPECT_EQ(config.registration.geometry, Geometry::kCurve);
}

TEST(LoadConfig, ScalarSpellings) {
  const Config config = LoadConfig(
      std::nullopt, {"registration.dmax_initial_factor=20", "registration.reference_distance=+2.5",
                     "registration.rotation_tolerance_deg=1e-3", "registration.use_uncertainty=yes",
                     "registration.coarse_to_fine=True", "registration.min_pairs=+4"});
  EXPECT_EQ(config.registration.dmax_initial_factor, 20.0);
  EXPECT_EQ(config.registration.reference_distance_m, 2.5);
  EXPECT_EQ(config.registration.rotation_tolerance_deg, 1e-3);
  EXPECT_TRUE(config.registration.use_uncertainty);
  EXPECT_TRUE(config.registration.coarse_to_fine);
  EXPECT_EQ(config.registration.min_pairs, 4);
}

TEST(LoadConfig, EnumsRoundTrip) {
  const auto check = [](const std::string& key, const std::string& name, auto expected,
                        auto RegistrationOptions::*field) {
    // Curves have no normals: point_to_plane is only valid with surfaces (checked below).
    const Config config =
        LoadConfig(std::nullopt, {"registration.residual=point_to_point", key + "=" + name});
    EXPECT_EQ(config.registration.*field, expected) << name;
    EXPECT_EQ(Values(config).at(key), name);
  };
  using R = RegistrationOptions;
  check("registration.geometry", "surface", Geometry::kSurface, &R::geometry);
  check("registration.geometry", "curve", Geometry::kCurve, &R::geometry);
  check("registration.criterion", "nonsymmetric", Criterion::kNonSymmetric, &R::criterion);
  check("registration.criterion", "symmetric", Criterion::kSymmetric, &R::criterion);
  check("registration.solver", "svd", Solver::kSvd, &R::solver);
  check("registration.solver", "dual_quaternion", Solver::kDualQuaternion, &R::solver);
  check("registration.residual", "auto", Residual::kAuto, &R::residual);
  check("registration.residual", "point_to_point", Residual::kPointToPoint, &R::residual);
  check("registration.residual", "point_to_plane", Residual::kPointToPlane, &R::residual);
  check("registration.convergence", "absolute", Convergence::kAbsolute, &R::convergence);
  check("registration.convergence", "relative", Convergence::kRelative, &R::convergence);
}

TEST(DumpYaml, LoadsBackToTheSameConfig) {
  const Config changed = LoadConfig(
      std::nullopt,
      {"registration.geometry=curve", "registration.criterion=symmetric",
       "registration.residual=point_to_point", "registration.convergence=relative",
       "registration.reference_distance=0.1", "registration.histogram_valley_ratio=0.3333333333333",
       "registration.rotation_tolerance_deg=1e-7", "registration.max_iterations=42",
       "registration.coarse_to_fine=true", "registration.use_uncertainty=true"});
  const Config reloaded = LoadConfig(WriteFile("dump.yaml", DumpYaml(changed)), {});
  ExpectSameRegistration(reloaded.registration, changed.registration);
  EXPECT_EQ(DumpYaml(reloaded), DumpYaml(changed));
}

// ---- errors --------------------------------------------------------------------------------

TEST(ConfigErrors, CurveGeometryRejectsPointToPlane) {
  EXPECT_EQ(ErrorOf([] {
              LoadConfig(std::nullopt,
                         {"registration.geometry=curve", "registration.residual=point_to_plane"});
            }),
            "registration.residual: point_to_plane needs surface normals; with geometry: curve set "
            "registration.residual=auto or point_to_point");
  EXPECT_NO_THROW(LoadConfig(
      std::nullopt, {"registration.geometry=curve", "registration.residual=point_to_point"}));
}

// The residual follows the geometry unless it is set: geometry=curve alone is accepted and
// registers point to point; surfaces stay point to plane.
TEST(LoadConfig, ResidualFollowsTheGeometryUnlessSet) {
  using rovermap::registration::EffectiveResidual;
  const Config curve = LoadConfig(std::nullopt, {"registration.geometry=curve"});
  EXPECT_EQ(curve.registration.residual, Residual::kAuto);
  EXPECT_EQ(EffectiveResidual(curve.registration), Residual::kPointToPoint);
  const Config surface = LoadConfig(std::nullopt, {});
  EXPECT_EQ(EffectiveResidual(surface.registration), Residual::kPointToPlane);
  const Config explicit_p2p = LoadConfig(std::nullopt, {"registration.residual=point_to_point"});
  EXPECT_EQ(EffectiveResidual(explicit_p2p.registration), Residual::kPointToPoint);
}

TEST(ConfigErrors, SubpixelWindowIsZeroOrOddAndAtLeastThree) {
  for (const char* bad : {"stereo.subpixel_window_px=4", "stereo.subpixel_window_px=1"}) {
    EXPECT_NE(OverrideError(bad).find("stereo.subpixel_window_px: must be 0 or odd and >= 3"),
              std::string::npos)
        << bad;
  }
  EXPECT_NO_THROW(LoadConfig(std::nullopt, {"stereo.subpixel_window_px=0"}));
  EXPECT_NO_THROW(LoadConfig(std::nullopt, {"stereo.subpixel_window_px=5"}));
}

TEST(ConfigErrors, UnknownKeyIsNamedWithASuggestion) {
  EXPECT_EQ(OverrideError("registration.max_iteration=5"),
            "registration.max_iteration: unknown key (did you mean registration.max_iterations?)");
  EXPECT_TRUE(
      Contains(OverrideError("max_iterations=5"), "did you mean registration.max_iterations?"));
  EXPECT_EQ(OverrideError("nonsense.key=1"), "nonsense.key: unknown key");

  const std::string error = FileError("unknown.yaml", "registration:\n  max_iterationz: 5\n");
  EXPECT_TRUE(Contains(error, "unknown.yaml:2: registration.max_iterationz: unknown key"));
  EXPECT_TRUE(Contains(error, "did you mean registration.max_iterations?"));
  EXPECT_TRUE(
      Contains(FileError("section.yaml", "registation:\n  max_iterations: 5\n"),
               "section.yaml:1: registation: unknown section (did you mean registration?)"));
}

TEST(ConfigErrors, WrongTypeNamesTheKey) {
  EXPECT_EQ(OverrideError("registration.max_iterations=abc"),
            "registration.max_iterations: expected an integer (got abc)");
  EXPECT_EQ(OverrideError("registration.max_iterations=1.5"),
            "registration.max_iterations: expected an integer (got 1.5)");
  EXPECT_EQ(OverrideError("registration.reference_distance=far"),
            "registration.reference_distance: expected a number (got far)");
  EXPECT_TRUE(Contains(OverrideError("registration.reference_distance=.nan"),
                       "registration.reference_distance:"));
  EXPECT_EQ(OverrideError("registration.use_uncertainty=maybe"),
            "registration.use_uncertainty: expected true or false (got maybe)");
  EXPECT_EQ(OverrideError("registration.solver=lu"),
            "registration.solver: must be one of svd|dual_quaternion (got lu)");
  EXPECT_EQ(OverrideError("registration.solver=[svd]"),
            "registration.solver: expected a single value (got a list)");
  EXPECT_EQ(OverrideError("registration.max_iterations="),
            "registration.max_iterations: missing value");
  EXPECT_TRUE(Contains(OverrideError("registration.max_iterations=99999999999"),
                       "registration.max_iterations: too large"));
}

TEST(ConfigErrors, OutOfRangeNamesKeyBoundAndValue) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"registration.max_iterations=-3", "registration.max_iterations: must be > 0 (got -3)"},
      {"registration.max_iterations=0", "registration.max_iterations: must be > 0 (got 0)"},
      {"registration.histogram_bins=1", "registration.histogram_bins: must be >= 2 (got 1)"},
      {"registration.coarse_iterations=-1", "registration.coarse_iterations: must be >= 0"},
      {"registration.coarse_step=0", "registration.coarse_step: must be >= 1 (got 0)"},
      {"registration.normal_neighbors=2", "registration.normal_neighbors: must be >= 3 (got 2)"},
      {"registration.min_pairs=2", "registration.min_pairs: must be >= 3 (got 2)"},
      {"registration.reference_distance=-0.1", "registration.reference_distance: must be >= 0"},
      {"registration.translation_tolerance_m=-1", "translation_tolerance_m: must be >= 0"},
      {"registration.rotation_tolerance_deg=-1", "rotation_tolerance_deg: must be >= 0"},
      {"registration.dmax_initial_factor=0", "dmax_initial_factor: must be > 0 (got 0)"},
      {"registration.histogram_valley_ratio=0", "histogram_valley_ratio: must be in (0, 1]"},
      {"registration.histogram_valley_ratio=1.5", "histogram_valley_ratio: must be in (0, 1]"},
      {"registration.relative_tolerance=0", "relative_tolerance: must be > 0"},
      {"registration.orientation_threshold_deg=180", "must be in [0, 180) (got 180)"},
      {"registration.orientation_threshold_deg=-5", "must be in [0, 180) (got -5)"},
      {"registration.mahalanobis_gate=0", "mahalanobis_gate: must be > 0"},
  };
  for (const auto& [override_text, expected] : cases) {
    EXPECT_TRUE(Contains(OverrideError(override_text), expected)) << override_text;
  }
  // The bounds themselves are valid.
  EXPECT_NO_THROW(LoadConfig(std::nullopt, {"registration.histogram_valley_ratio=1",
                                            "registration.orientation_threshold_deg=0",
                                            "registration.coarse_iterations=0"}));
}

TEST(ConfigErrors, FileErrorsNameFileLineAndKey) {
  EXPECT_EQ(FileError("range.yaml", "# header\nregistration:\n  max_iterations: -3\n"),
            (rovermap::testing::ScratchDir() / "range.yaml").string() +
                ":3: registration.max_iterations: must be > 0 (got -3)");
  EXPECT_TRUE(Contains(FileError("type.yaml", "registration:\n  solver: lu\n"),
                       "type.yaml:2: registration.solver: must be one of"));
  EXPECT_TRUE(Contains(FileError("twice.yaml", "registration:\n  min_pairs: 4\n  min_pairs: 5\n"),
                       "twice.yaml:3: registration.min_pairs: set twice (first on line 2)"));
  EXPECT_TRUE(Contains(FileError("mapvalue.yaml", "registration:\n  min_pairs: {a: 1}\n"),
                       "mapvalue.yaml:2: registration.min_pairs: expected a single value"));
  EXPECT_TRUE(Contains(FileError("scalarsection.yaml", "registration: 5\n"),
                       "scalarsection.yaml:1: registration: is a section"));
}

TEST(ConfigErrors, BadOverrideSyntax) {
  EXPECT_EQ(OverrideError("registration.max_iterations"),
            "override \"registration.max_iterations\": expected key=value");
  EXPECT_EQ(OverrideError("=5"), "override \"=5\": expected key=value");
  EXPECT_TRUE(Contains(OverrideError("registration.solver=[svd"),
                       "registration.solver: cannot parse value \"[svd\""));
}

TEST(ConfigErrors, MissingFileIsNamed) {
  const fs::path missing = fs::path(::testing::TempDir()) / "no_such_dir" / "config.yaml";
  EXPECT_EQ(ErrorOf([&] { LoadConfig(missing, {}); }), missing.string() + ": no such config file");
  EXPECT_TRUE(
      Contains(ErrorOf([] { LoadConfig(fs::path(::testing::TempDir()), {}); }), "is a directory"));
}

TEST(ConfigErrors, MalformedYamlGivesFileAndLine) {
  const std::string error = FileError("malformed.yaml",
                                      "registration:\n"
                                      "  max_iterations: 5\n"
                                      "  solver: svd: x\n");
  EXPECT_TRUE(Contains(error, "malformed.yaml:3:14: invalid YAML: illegal map value"));
  EXPECT_TRUE(Contains(FileError("indent.yaml", "registration:\n  max_iterations: 5\n bad: 1\n"),
                       "indent.yaml:3:2: invalid YAML"));
}

TEST(ConfigErrors, TopLevelMustBeAMapping) {
  EXPECT_TRUE(Contains(FileError("list.yaml", "- registration\n- solver\n"),
                       "list.yaml:1: expected a mapping of sections"));
  EXPECT_TRUE(Contains(FileError("scalar.yaml", "just text\n"),
                       "scalar.yaml:1: expected a mapping of sections"));
}

}  // namespace
}  // namespace rovermap::config
