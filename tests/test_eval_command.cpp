// `rovermap eval` end to end: the JSON of docs/design.md §8 for trajectories (KITTI and TUM) and
// DEMs, --plot PNGs, config keys, and the exit statuses and messages on bad input.
#include <cpl_conv.h>
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <sys/wait.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/support/CommandFixture.hpp"

namespace fs = std::filesystem;

namespace {

using rovermap::testing::CommandResult;
using rovermap::testing::Slurp;

const fs::path kKitti00 = fs::path(ROVERMAP_DATASETS_DIR) / "kitti_odometry_00" / "KITTI_00_gt.txt";

class EvalCommand : public rovermap::testing::CommandFixture {
 protected:
  // A 1 m grid of `width` × `height` cells at UTM (500000, 4000000), value = f(col, row).
  std::string GeoTiff(const std::string& name, int width, int height, int epsg,
                      float (*f)(int, int)) {
    GDALAllRegister();
    const fs::path p = dir_ / name;
    GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(
        p.c_str(), width, height, 1, GDT_Float32, nullptr);
    double transform[6] = {500000.0, 1.0, 0.0, 4000000.0, 0.0, -1.0};
    ds->SetGeoTransform(transform);
    OGRSpatialReference srs;
    srs.importFromEPSG(epsg);
    char* wkt = nullptr;
    srs.exportToWkt(&wkt);
    ds->SetProjection(wkt);
    CPLFree(wkt);
    std::vector<float> values;
    for (int row = 0; row < height; ++row)
      for (int col = 0; col < width; ++col) values.push_back(f(col, row));
    EXPECT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, width, height, values.data(), width,
                                             height, GDT_Float32, 0, 0),
              CE_None);
    GDALClose(ds);
    return p.string();
  }

  void ExpectPng(const fs::path& p) {
    const std::string bytes = Slurp(p);
    ASSERT_GT(bytes.size(), 1000u) << p;
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << p;
  }

  void ExpectNoTemporaries(const fs::path& d) {
    for (const auto& entry : fs::recursive_directory_iterator(d))
      EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
};

// KITTI 00's ground truth against itself and against a copy with every translation × 1.01.
TEST_F(EvalCommand, Kitti00SelfAndScaledWithPlots) {
  std::ifstream in(kKitti00);
  std::ostringstream scaled;
  scaled.precision(10);
  for (std::string line; std::getline(in, line);) {
    std::istringstream numbers(line);
    double v[12];
    for (double& x : v) numbers >> x;
    for (int k = 0; k < 12; ++k)
      scaled << (k % 4 == 3 ? 1.01 * v[k] : v[k]) << (k < 11 ? " " : "\n");
  }
  const std::string est = Write("scaled.txt", scaled.str());
  const CommandResult r =
      Rovermap("eval --estimate " + kKitti00.string() + " --estimate " + est + " --groundtruth " +
               kKitti00.string() + " --plot " + (dir_ / "plots").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["estimates"].size(), 2u);
  for (const auto& e : j["estimates"]) {
    for (const char* key :
         {"file", "ate_rmse_m", "ate_rmse_origin_m", "rpe_trans_rmse_m", "rpe_rot_rmse_deg",
          "kitti_trans_percent", "kitti_rot_deg_per_m", "pairs", "length_m"})
      EXPECT_TRUE(e.contains(key)) << key;
    EXPECT_EQ(e["pairs"], 4541);
    EXPECT_EQ(e["association"], "index");
    EXPECT_NEAR(e["length_m"].get<double>(), 3724.187, 1e-3);  // awk over the file
  }
  const auto& self = j["estimates"][0];
  EXPECT_LT(self["ate_rmse_m"].get<double>(), 1e-9);
  EXPECT_LT(self["kitti_trans_percent"].get<double>(), 1e-9);
  const auto& off = j["estimates"][1];
  EXPECT_NEAR(off["kitti_trans_percent"].get<double>(), 1.0, 0.02);  // a 1 % scale error
  EXPECT_LT(off["kitti_rot_deg_per_m"].get<double>(), 1e-6);         // rotations untouched
  EXPECT_GT(off["ate_rmse_origin_m"].get<double>(), off["ate_rmse_m"].get<double>());
  EXPECT_EQ(j["options"]["segment_lengths_m"], nlohmann::json({5.0, 10.0, 20.0, 50.0}));
  ExpectPng(dir_ / "plots" / "trajectories.png");
  ExpectPng(dir_ / "plots" / "error_vs_distance.png");
  ExpectNoTemporaries(dir_ / "plots");
}

// TUM files, lateral drift of 0.1 m per metre (hand values as in test_eval_trajectory), with the
// eval.* keys set on the command line.
TEST_F(EvalCommand, TumWithConfigKeys) {
  std::ostringstream gt, est;
  for (int k = 0; k <= 10; ++k) {
    gt << 0.1 * k << " " << k << " 0 0 0 0 0 1\n";
    est << 0.1 * k + 0.005 << " " << k << " " << 0.1 * k << " 0 0 0 0 1\n";
  }
  const CommandResult r =
      Rovermap("eval --estimate " + Write("est.tum", est.str()) + " --groundtruth " +
               Write("gt.tum", gt.str()) +
               " --set eval.rpe_delta_m=1 --set \"eval.segment_lengths_m=[2, 5]\"");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json e = nlohmann::json::parse(r.out)["estimates"][0];
  EXPECT_EQ(e["association"], "timestamp");
  EXPECT_EQ(e["pairs"], 11);
  EXPECT_NEAR(e["ate_rmse_origin_m"].get<double>(), 0.1 * std::sqrt(35.0), 1e-9);
  EXPECT_NEAR(e["rpe_trans_rmse_m"].get<double>(), 0.1, 1e-9);
  EXPECT_NEAR(e["kitti_trans_percent"].get<double>(), 100.0 * 1.8 / 13.0, 1e-9);
  ASSERT_EQ(e["kitti_segments"].size(), 2u);
  EXPECT_NEAR(e["kitti_segments"][0]["trans_percent"].get<double>(), 15.0, 1e-9);

  // A clock offset of 0.03 s, beyond the default tolerance (0.02 s): exit 1, the JSON says why.
  std::ostringstream late;
  for (int k = 0; k <= 10; ++k) late << 0.1 * k + 0.03 << " " << k << " 0 0 0 0 0 1\n";
  const std::string late_file = Write("late.tum", late.str());
  CommandResult bad =
      Rovermap("eval --estimate " + late_file + " --groundtruth " + (dir_ / "gt.tum").string());
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("late.tum"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("gt.tum"), std::string::npos) << bad.err;
  EXPECT_EQ(nlohmann::json::parse(bad.out)["estimates"][0]["status"], "no_pairs");
  bad = Rovermap("eval --estimate " + late_file + " --groundtruth " + (dir_ / "gt.tum").string() +
                 " --set eval.association_tolerance_s=0.04");
  EXPECT_EQ(bad.status, 0) << bad.err;
}

TEST_F(EvalCommand, ParseErrorsNameFileAndLineExitOne) {
  const std::string gt = Write("gt.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n");
  const std::string bad = Write("bad.tum", "0 0 0 0 0 0 0 1\n# comment\n1 x 0 0 0 0 0 1\n");
  CommandResult r = Rovermap("eval --estimate " + bad + " --groundtruth " + gt);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad.tum:3"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
  r = Rovermap("eval --estimate " + gt + " --groundtruth " + (dir_ / "nowhere.txt").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("nowhere.txt"), std::string::npos) << r.err;
  r = Rovermap("eval --estimate " + gt + " --groundtruth " + gt + " --format kitti");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("gt.tum:1"), std::string::npos) << r.err;
}

TEST_F(EvalCommand, UsageErrorsExitTwo) {
  const std::string gt = Write("gt.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n");
  EXPECT_EQ(Rovermap("eval").status, 2);
  EXPECT_EQ(Rovermap("eval --estimate " + gt).status, 2);
  EXPECT_EQ(Rovermap("eval --groundtruth " + gt).status, 2);
  EXPECT_EQ(Rovermap("eval --dem " + gt).status, 2);
  EXPECT_EQ(Rovermap("eval --estimate " + gt + " --groundtruth " + gt + " --dem a.tif").status, 2);
  EXPECT_EQ(Rovermap("eval --estimate " + gt + " --groundtruth " + gt + " --format euroc").status,
            2);
  CommandResult r =
      Rovermap("eval --estimate " + gt + " --groundtruth " + gt + " --set eval.rpe_delta_m=-1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("eval.rpe_delta_m"), std::string::npos) << r.err;
  r = Rovermap("eval --estimate " + gt + " --groundtruth " + gt +
               " --set eval.segment_lengths_m=[]");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("eval.segment_lengths_m"), std::string::npos) << r.err;
  r = Rovermap("eval --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("--estimate"), std::string::npos);
  EXPECT_NE(r.out.find("--reference"), std::string::npos);
}

float Flat(int, int) { return 10.0f; }
float Raised(int col, int) { return col < 4 ? 10.5f : std::nanf(""); }  // west half, +0.5 m

TEST_F(EvalCommand, DemComparisonJsonAndPlot) {
  const std::string reference = GeoTiff("terrain.tif", 8, 6, 32633, Flat);
  const std::string dem = GeoTiff("dem.tif", 8, 6, 32633, Raised);
  const CommandResult r = Rovermap("eval --dem " + dem + " --reference " + reference + " --plot " +
                                   (dir_ / "plots").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["cells"], 24);
  EXPECT_NEAR(j["rmse_m"].get<double>(), 0.5, 1e-6);
  EXPECT_NEAR(j["bias_m"].get<double>(), 0.5, 1e-6);
  EXPECT_NEAR(j["p95_abs_m"].get<double>(), 0.5, 1e-6);
  EXPECT_DOUBLE_EQ(j["coverage"].get<double>(), 0.5);
  EXPECT_TRUE(j["within_2sigma"].is_null());  // one band: no stated σ
  ExpectPng(dir_ / "plots" / "dem_error.png");
  ExpectNoTemporaries(dir_ / "plots");

  const std::string other = GeoTiff("utm34.tif", 8, 6, 32634, Flat);
  const CommandResult crs = Rovermap("eval --dem " + dem + " --reference " + other);
  EXPECT_EQ(crs.status, 1);
  EXPECT_NE(crs.err.find("coordinate reference"), std::string::npos) << crs.err;
  EXPECT_NE(crs.err.find("utm34.tif"), std::string::npos) << crs.err;
  const CommandResult missing =
      Rovermap("eval --dem " + (dir_ / "none.tif").string() + " --reference " + reference);
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.err.find("none.tif"), std::string::npos) << missing.err;
}

}  // namespace
