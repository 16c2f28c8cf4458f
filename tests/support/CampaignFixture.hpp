#pragma once
// Four recordings for campaign tests, simulated once per test binary: three cloud traverses
// over one terrain from different start poses, each with its own odometry errors, and a copy
// of the first with a frame file missing (its replay fails).

#include <filesystem>
#include <string>
#include <vector>

#include "tests/support/CommandFixture.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::testing {

class CampaignFixture : public CommandFixture {
 protected:
  static void SetUpTestSuite() {
    recordings_ = ScratchDir();
    const std::string common =
        " --set sim.sensor=cloud --set sim.frames=12 --set sim.terrain_size_m=20 "
        "--set sim.rocks=100 --set sim.craters=4 ";
    const std::vector<std::pair<std::string, std::string>> traverses = {
        {"a", ""},
        {"b",
         "--set sim.start_x_m=1.5 --set sim.start_y_m=-2.5 --set sim.start_yaw_deg=60 "
         "--set sim.odometry_seed=2"},
        {"c",
         "--set sim.start_x_m=6 --set sim.start_y_m=1 --set sim.start_yaw_deg=180 "
         "--set sim.odometry_seed=3"}};
    for (const auto& [name, sets] : traverses) {
      const std::string cmd = std::string(ROVERMAP_EXECUTABLE) + " simulate --out " +
                              (recordings_ / name).string() + common + sets + " >/dev/null 2>&1";
      ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    }
    std::filesystem::copy(recordings_ / "a", recordings_ / "bad",
                          std::filesystem::copy_options::recursive);
    std::filesystem::remove(recordings_ / "bad" / "frames" / "000003.ply");
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(recordings_); }

  /// The four recordings, the bad one third: "a b bad c".
  static std::string Recordings() {
    std::string out;
    for (const char* name : {"a", "b", "bad", "c"}) out += (recordings_ / name).string() + " ";
    return out;
  }
  static std::filesystem::path Recording(const std::string& name) { return recordings_ / name; }

  /// Small tiles, so that the mosaic has several rows of them for the parts.
  static constexpr const char* kMosaicSets = "--set mosaic.tile_cells=64";

  /// The outputs that are the same wherever and however a campaign runs (drift.csv and the
  /// replays' summary.json hold timings).
  static std::vector<std::string> DeterministicOutputs() {
    return {"summary.json",
            "mosaic.tif",
            "mosaic.json",
            "mosaic_terrain.tif",
            "config.yaml",
            "campaign.json",
            "traverses/000-a/dem.tif",
            "traverses/000-a/trajectory.tum",
            "traverses/001-b/dem.tif",
            "traverses/001-b/map.bt",
            "traverses/003-c/dem.tif",
            "traverses/003-c/trajectory.tum"};
  }

  static inline std::filesystem::path recordings_;
};

}  // namespace rovermap::testing
