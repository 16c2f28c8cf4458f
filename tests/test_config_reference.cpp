#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "config/Config.hpp"
#include "config/KeyReference.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::config {
namespace {

namespace fs = std::filesystem;

std::string Reference(const std::vector<PresetFile>& presets = {}) {
  std::ostringstream page;
  WriteKeyReference(page, presets);
  return page.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

// The table row of `key` (the lines that start with its cell), one expected.
std::vector<std::string> RowsOf(const std::string& page, const std::string& key) {
  std::vector<std::string> rows;
  for (const std::string& line : Lines(page)) {
    if (line.rfind("| `" + key + "` |", 0) == 0) rows.push_back(line);
  }
  return rows;
}

// A row's cells, split on the pipes that are not escaped.
std::vector<std::string> Cells(const std::string& row) {
  std::vector<std::string> cells;
  std::string cell;
  for (std::size_t i = 1; i < row.size(); ++i) {
    if (row[i] == '|' && row[i - 1] != '\\') {
      cells.push_back(cell.substr(1, cell.size() - 2));  // the spaces around
      cell.clear();
    } else {
      cell += row[i];
    }
  }
  return cells;
}

// (dotted key, value) from DumpYaml's layout: "section:" lines, then "  leaf: value  # doc".
std::map<std::string, std::string> DumpedValues() {
  std::map<std::string, std::string> values;
  std::string section;
  for (const std::string& line : Lines(DumpYaml(Config{}))) {
    if (line.empty()) continue;
    if (line[0] != ' ') {
      section = line.substr(0, line.find(':'));
      continue;
    }
    const auto colon = line.find(':');
    std::string value = line.substr(colon + 2, line.find("  #") - colon - 2);
    value.erase(value.find_last_not_of(' ') + 1);
    values[section + "." + line.substr(2, colon - 2)] = value;
  }
  return values;
}

TEST(KeyReference, ListsEveryKeyExactlyOnce) {
  const std::string page = Reference();
  for (const std::string& key : KnownKeys()) {
    EXPECT_EQ(RowsOf(page, key).size(), 1u) << key;
  }
}

TEST(KeyReference, EveryRowHasItsFiveCells) {
  const std::string page = Reference();
  for (const std::string& key : KnownKeys()) {
    for (const std::string& row : RowsOf(page, key)) EXPECT_EQ(Cells(row).size(), 5u) << row;
  }
}

TEST(KeyReference, OneHeadingPerSectionInRegistryOrder) {
  std::vector<std::string> sections;
  for (const std::string& key : KnownKeys()) {
    const std::string section = key.substr(0, key.find('.'));
    if (std::find(sections.begin(), sections.end(), section) == sections.end())
      sections.push_back(section);
  }
  std::vector<std::string> headings;
  for (const std::string& line : Lines(Reference())) {
    if (line.rfind("## ", 0) == 0 && line != "## Presets") headings.push_back(line.substr(3));
  }
  EXPECT_EQ(headings, sections);
}

TEST(KeyReference, DefaultsAreWhatDumpYamlPrints) {
  const std::string page = Reference();
  const auto values = DumpedValues();
  ASSERT_EQ(values.size(), KnownKeys().size());
  for (const auto& [key, value] : values) {
    const auto rows = RowsOf(page, key);
    ASSERT_EQ(rows.size(), 1u) << key;
    EXPECT_EQ(Cells(rows[0]).at(1), "`" + value + "`") << key;
  }
}

TEST(KeyReference, ShowsUnitsRangesAndNames) {
  const std::string page = Reference();
  auto cells = [&](const std::string& key) {
    const auto rows = RowsOf(page, key);
    return rows.size() == 1 ? Cells(rows[0]) : std::vector<std::string>{};
  };
  // A bounded number, an integer, an enumeration, a switch, a list, a name.
  EXPECT_EQ(cells("registration.histogram_valley_ratio").at(2), "ratio");
  EXPECT_EQ(cells("registration.histogram_valley_ratio").at(3), "in (0, 1]");
  EXPECT_EQ(cells("registration.max_iterations").at(3), "integer > 0");
  EXPECT_EQ(cells("registration.reference_distance").at(2), "m");
  EXPECT_EQ(cells("registration.reference_distance").at(3), ">= 0");
  EXPECT_EQ(cells("sim.origin_altitude_m").at(3), "any number");
  EXPECT_EQ(cells("mapper.reference").at(3), "one of: previous, local_map");
  EXPECT_EQ(cells("mapper.reference").at(2), "");
  EXPECT_EQ(cells("octomap.enabled").at(3), "true or false");
  EXPECT_EQ(cells("eval.segment_lengths_m").at(3), "list of numbers, each > 0");
  EXPECT_EQ(cells("bag.groundtruth_topic").at(3),
            "topic or frame name (letters, digits, _ / . -) or \"\"");
  // The help without the unit and range DumpYaml puts around it.
  EXPECT_EQ(cells("registration.max_iterations").at(4), "iteration cap");
}

TEST(KeyReference, AddsTheRulesBetweenKeys) {
  const std::string page = Reference();
  const auto row = RowsOf(page, "stereo.num_disparities");
  ASSERT_EQ(row.size(), 1u);
  EXPECT_EQ(Cells(row[0]).at(3), "integer >= 0; a multiple of 16");
  const auto block = RowsOf(page, "stereo.block_size");
  ASSERT_EQ(block.size(), 1u);
  EXPECT_EQ(Cells(block[0]).at(3), "integer >= 1; odd; in [5, 255] with algorithm: bm");
}

TEST(KeyReference, EscapesPipesInCells) {
  EXPECT_EQ(TableCell("|step| / |value|"), "\\|step\\| / \\|value\\|");
  EXPECT_EQ(TableCell("two\nlines"), "two lines");
  // registration.relative_tolerance's help has pipes: its row still has five cells.
  const auto row = RowsOf(Reference(), "registration.relative_tolerance");
  ASSERT_EQ(row.size(), 1u);
  EXPECT_EQ(Cells(row[0]).size(), 5u);
  EXPECT_NE(row[0].find("\\|step\\|"), std::string::npos) << row[0];
}

TEST(KeyReference, SaysItIsGeneratedAndHowToRegenerateIt) {
  const std::string page = Reference();
  EXPECT_NE(page.find("generated from the key registry"), std::string::npos);
  EXPECT_NE(page.find("cmake --build BUILD --target docs-config"), std::string::npos);
}

TEST(KeyReference, ListsWhatEachPresetChanges) {
  const fs::path dir = rovermap::testing::ScratchDir();
  std::ofstream(dir / "few.yaml") << "registration:\n  max_iterations: 7\n  geometry: surface\n"
                                     "dem:\n  cell_size_m: 0.25\n";
  std::ofstream(dir / "none.yaml") << "# nothing\n";
  const std::string page =
      Reference({{"config/presets/few.yaml", dir / "few.yaml"}, {"none.yaml", dir / "none.yaml"}});
  const std::string presets = page.substr(page.find("## Presets"));
  EXPECT_NE(presets.find("### config/presets/few.yaml"), std::string::npos);
  const auto row = RowsOf(presets, "registration.max_iterations");
  ASSERT_EQ(row.size(), 1u);
  const Config defaults;
  EXPECT_EQ(Cells(row[0]), (std::vector<std::string>{
                               "`registration.max_iterations`", "`7`",
                               "`" + std::to_string(defaults.registration.max_iterations) + "`"}));
  EXPECT_EQ(RowsOf(presets, "dem.cell_size_m").size(), 1u);
  // Every key the file sets, in its order, even one set to its default; no other key.
  EXPECT_EQ(RowsOf(presets, "registration.geometry").size(), 1u);
  EXPECT_TRUE(RowsOf(presets, "registration.solver").empty());
  EXPECT_LT(presets.find("`registration.max_iterations`"), presets.find("`registration.geometry`"));
  EXPECT_LT(presets.find("`registration.geometry`"), presets.find("`dem.cell_size_m`"));
  EXPECT_NE(presets.find("### none.yaml\n\nIt sets no key."), std::string::npos);
}

TEST(KeyReference, APresetThatDoesNotLoadIsAnError) {
  const fs::path dir = rovermap::testing::ScratchDir();
  std::ofstream(dir / "bad.yaml") << "registration:\n  max_iteration: 7\n";
  std::ostringstream page;
  EXPECT_THROW(WriteKeyReference(page, {{"bad.yaml", dir / "bad.yaml"}}), ConfigError);
}

TEST(KeyReference, FindsTheRepositorysPresets) {
  const auto presets = FindPresets(ROVERMAP_SOURCE_DIR);
  std::set<std::string> names;
  for (const PresetFile& preset : presets) names.insert(preset.name);
  EXPECT_EQ(names.count("config/presets/fast.yaml"), 1u);
  EXPECT_TRUE(
      std::is_sorted(presets.begin(), presets.end(),
                     [](const PresetFile& a, const PresetFile& b) { return a.name < b.name; }));
}

}  // namespace
}  // namespace rovermap::config
