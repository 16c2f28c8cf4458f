// `rovermap register` end to end: JSON on good input, exit statuses and messages naming the
// file (and line) on bad input, never a crash or a hang (CTest's timeout guards hangs).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/support/CommandFixture.hpp"

namespace fs = std::filesystem;

namespace {

using rovermap::testing::CommandResult;
using rovermap::testing::Slurp;

class RegisterCommand : public rovermap::testing::CommandFixture {
 protected:
  // A small valid cloud (a bumpy grid) to pair with a bad one.
  std::string GoodXyz() {
    std::ostringstream s;
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j)
        s << 0.1 * i << " " << 0.1 * j << " " << 0.05 * ((i * j) % 3) << "\n";
    return Write("good.xyz", s.str());
  }
};

const std::string kBunny = std::string(ROVERMAP_DATASETS_DIR) + "/stanford_bunny/";

}  // namespace

TEST_F(RegisterCommand, BunnyPairPrintsTheJsonContract) {
  // Reference bun045 -> bun000 is a 34.3° rotation about y: start 5° and 3 mm off it.
  const std::string png = (dir_ / "preview.png").string();
  const CommandResult r =
      Rovermap("register " + kBunny + "bun045.ply " + kBunny +
               "bun000.ply --init \"0 0.5111 0 -0.049 0 -0.011\" --preview " + png);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  for (const char* key : {"matrix", "rotation_vector", "translation", "converged", "iterations",
                          "inliers", "rms", "time_ms", "covariance", "trace", "status"})
    EXPECT_TRUE(j.contains(key)) << key;
  ASSERT_EQ(j["matrix"].size(), 4u);
  EXPECT_EQ(j["matrix"][3], nlohmann::json({0.0, 0.0, 0.0, 1.0}));
  EXPECT_TRUE(j["converged"].get<bool>());
  // Reference: R(0,0) = 0.82635, t = (-0.05202, -0.00038, -0.01092).
  EXPECT_NEAR(j["matrix"][0][0].get<double>(), 0.826350588, 2e-3);
  EXPECT_NEAR(j["translation"][0].get<double>(), -0.0520211, 5e-4);
  EXPECT_NEAR(j["translation"][2].get<double>(), -0.0109223, 5e-4);
  EXPECT_EQ(j["covariance"].size(), 6u);
  // The preview is a real PNG (signature), written atomically (no temporary left behind).
  const std::string bytes = Slurp(png);
  ASSERT_GT(bytes.size(), 1000u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST_F(RegisterCommand, FastPresetMatchesAVoxelSample) {
  const CommandResult r = Rovermap("register " + kBunny + "bun045.ply " + kBunny +
                                   "bun000.ply --init \"0 0.5111 0 -0.049 0 -0.011\" "
                                   "--config " +
                                   std::string(ROVERMAP_SOURCE_DIR) + "/config/presets/fast.yaml");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["converged"].get<bool>());
  // bun045 has 40 097 points; a 3·D voxel keeps about one in four.
  EXPECT_LT(j["sample_points"].get<std::size_t>(), 40097u / 3);
  EXPECT_LE(j["inliers"].get<std::size_t>(), j["sample_points"].get<std::size_t>());
  EXPECT_NEAR(j["matrix"][0][0].get<double>(), 0.826350588, 2e-3);
  EXPECT_NEAR(j["translation"][0].get<double>(), -0.0520211, 5e-4);
}

TEST_F(RegisterCommand, UnwritablePreviewIsNamed) {
  const std::string good = GoodXyz();
  const CommandResult r = Rovermap("register " + good + " " + good + " --preview " +
                                   (dir_ / "no_such_dir" / "p.png").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("p.png"), std::string::npos) << r.err;
}

TEST_F(RegisterCommand, CurvesFromXyzChains) {
  // Two chains (a circle and a line segment); the source is the target moved by 2 cm in x.
  std::ostringstream target, source;
  for (int chain = 0; chain < 2; ++chain) {
    for (int i = 0; i < 200; ++i) {
      const double s = 0.03 * i;
      const double x = chain == 0 ? std::cos(s) : 2.0 + 0.01 * i;
      const double y = chain == 0 ? std::sin(s) : 0.3 * std::sin(3 * s);
      const double z = chain == 0 ? 0.1 * std::sin(2 * s) : 0.002 * i;
      target << x << " " << y << " " << z << "\n";
      source << x - 0.02 << " " << y << " " << z << "\n";
    }
    target << "\n";
    source << "\n";
  }
  const std::string files =
      "register " + Write("s.xyz", source.str()) + " " + Write("t.xyz", target.str());
  const CommandResult r = Rovermap(files +
                                   " --set registration.geometry=curve --set "
                                   "registration.residual=point_to_point"
                                   " --set registration.orientation_threshold_deg=60");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["translation"][0].get<double>(), 0.02, 1e-3);

  // The residual follows the geometry: geometry=curve alone registers point to point.
  const CommandResult alone = Rovermap(files + " --set registration.geometry=curve");
  ASSERT_EQ(alone.status, 0) << alone.err;
  const nlohmann::json a = nlohmann::json::parse(alone.out);
  EXPECT_TRUE(a["converged"].get<bool>());
  EXPECT_NEAR(a["translation"][0].get<double>(), 0.02, 1e-3);
  EXPECT_NEAR(a["translation"][1].get<double>(), 0.0, 1e-3);

  // Set explicitly, point_to_plane is still refused with curves (exit 2, naming the key).
  const CommandResult plane = Rovermap(files +
                                       " --set registration.geometry=curve"
                                       " --set registration.residual=point_to_plane");
  EXPECT_EQ(plane.status, 2);
  EXPECT_NE(plane.err.find("registration.residual"), std::string::npos) << plane.err;
}

TEST_F(RegisterCommand, HelpExitsZero) {
  const CommandResult r = Rovermap("register --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("--init"), std::string::npos);
  EXPECT_NE(r.out.find("--set"), std::string::npos);
  EXPECT_EQ(Rovermap("--help").status, 0);
}

TEST_F(RegisterCommand, UsageErrorsExitTwo) {
  const std::string good = GoodXyz();
  EXPECT_EQ(Rovermap("").status, 2);
  EXPECT_EQ(Rovermap("register " + good).status, 2);
  EXPECT_EQ(Rovermap("register " + good + " " + good + " --bogus").status, 2);
  CommandResult r = Rovermap("register " + good + " " + good + " --init \"1 2 3\"");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--init"), std::string::npos) << r.err;
  r = Rovermap("register " + good + " " + good + " --set registration.max_iteration=3");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("registration.max_iteration"), std::string::npos) << r.err;
  r = Rovermap("register " + good + " " + good + " --set registration.max_iterations=abc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("registration.max_iterations"), std::string::npos) << r.err;
  r = Rovermap("register " + good + " " + good + " --set registration.max_iterations=-4");
  EXPECT_EQ(r.status, 2);
  r = Rovermap("register " + good + " " + good + " --config " + (dir_ / "missing.yaml").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("missing.yaml"), std::string::npos) << r.err;
  const std::string bad_yaml = Write("bad.yaml", "registration:\n  solver: quaternions\n");
  r = Rovermap("register " + good + " " + good + " --config " + bad_yaml);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("registration.solver"), std::string::npos) << r.err;
}

// Each bad file: exit 1, a message naming the file (and the line for text), empty stdout.
TEST_F(RegisterCommand, BadInputFilesAreNamed) {
  const std::string good = GoodXyz();
  struct Case {
    std::string name;
    std::string content;
    std::string expect;  // in the message besides the file name
  };
  std::string truncated_binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  truncated_binary += std::string(12 * 10, '\0');
  const std::vector<Case> cases = {
      {"empty.xyz", "", ""},
      {"text.xyz", "0 0 0\n1 0 0\n1 abc 0\n", "text.xyz:3"},
      {"nan.xyz", "0 0 0\n1 0 0\nnan 1 0\n0 1 1\n", "nan.xyz:3"},
      {"inf.xyz", "0 0 0\n1 0 0\n0 1 0\n0 inf 1\n", "inf.xyz:4"},
      {"two.xyz", "0 0 0\n1 0 0\n", "3 points"},
      {"lying.ply",
       "ply\nformat ascii 1.0\nelement vertex 10\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
       "10"},
      {"truncated.ply", truncated_binary, "truncated"},
      {"points.txt", "0 0 0\n", ""},
  };
  for (const Case& c : cases) {
    const std::string path = Write(c.name, c.content);
    const CommandResult r = Rovermap("register " + path + " " + good);
    EXPECT_EQ(r.status, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.name), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.name << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << c.name;
  }
  const CommandResult missing =
      Rovermap("register " + (dir_ / "nowhere.ply").string() + " " + good);
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.err.find("nowhere.ply"), std::string::npos) << missing.err;
}

TEST_F(RegisterCommand, FailedRegistrationExitsOneWithJson) {
  // Source 100 m away from the target with no initial estimate: no pairs within Dmax.
  std::ostringstream far;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) far << 100 + 0.1 * i << " " << 0.1 * j << " 0\n";
  const CommandResult r = Rovermap("register " + Write("far.xyz", far.str()) + " " + GoodXyz());
  EXPECT_EQ(r.status, 1);
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["converged"].get<bool>());
  EXPECT_EQ(j["status"], "too_few_pairs");
  EXPECT_NE(r.err.find("registration failed"), std::string::npos);
}
