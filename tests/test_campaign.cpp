// `rovermap campaign`: the local run end to end, its files against `rovermap mosaic`, the batch
// scripts, the plans' round trips and bad input. The same campaign through a real Slurm cluster
// is tests/test_campaign_slurm.cpp (make test-slurm).
#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "campaign/Campaign.hpp"
#include "io/IoError.hpp"
#include "mosaic/Mosaic.hpp"
#include "tests/support/CampaignFixture.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/Sanitizers.hpp"

namespace rovermap {
namespace {

namespace fs = std::filesystem;
using campaign::CampaignLayout;
using campaign::CampaignPlan;
using campaign::Step;
using testing::CampaignFixture;
using testing::CommandResult;
using testing::Contains;
using testing::Slurp;

// Every file under `dir` whose name says it is a temporary (ours: ".tmp-" or a leading dot).
std::vector<std::string> Temporaries(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.find(".tmp-") != std::string::npos || name.front() == '.') {
      found.push_back(entry.path().string());
    }
  }
  return found;
}

using Campaign = CampaignFixture;

TEST_F(Campaign, LocalRunReplaysEveryTraverseAndMosaicsTheOnesThatWorked) {
  const fs::path out = dir_ / "campaign";
  const CommandResult r = Rovermap("campaign " + Recordings() + "--out " + out.string() +
                                   " --set campaign.mosaic_tasks=3 " + kMosaicSets);
  // A failed traverse is reported and left out: exit 1, the mosaic built from the other three.
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "002-bad failed, left out"));
  EXPECT_TRUE(Contains(r.err, "000003.ply"));
  EXPECT_TRUE(Contains(r.err, "mosaic-part 3/3"));  // progress, step by step
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(r.out, Slurp(out / "summary.json"));
  EXPECT_EQ(summary["traverses"], 4);
  EXPECT_EQ(summary["succeeded"], 3);
  EXPECT_EQ(summary["failed"], nlohmann::json::array({"002-bad"}));
  EXPECT_EQ(summary["frames"], 36);
  ASSERT_EQ(summary["traverse"].size(), 4u);
  for (const nlohmann::json& t : summary["traverse"]) {
    if (t["name"] == "002-bad") {
      EXPECT_EQ(t["status"], "failed");
      EXPECT_EQ(t["exit_status"], 1);
      EXPECT_TRUE(Contains(t["error"].get<std::string>(), "000003.ply: missing frame file"));
      continue;
    }
    EXPECT_EQ(t["status"], "ok") << t.dump();
    EXPECT_EQ(t["frames"], 12);
    EXPECT_TRUE(t["ate_rmse_origin_m"]["registered"].is_number());
    EXPECT_TRUE(fs::exists(out / "traverses" / t["name"].get<std::string>() / "dem.tif"));
    // The first is the mosaic's reference; the others were matched onto it, and a correction
    // that hardly helps is refused with its reason (these 12-frame traverses already agree:
    // 001-b's RMS over the overlap 0.0058 -> 0.0052 m, refused; 003-c registered).
    if (t["name"] == "000-a") {
      EXPECT_EQ(t["mosaic"]["status"], "reference");
    } else if (t["mosaic"]["status"] == "refused") {
      EXPECT_FALSE(t["mosaic"]["applied"].get<bool>());
      EXPECT_TRUE(Contains(t["mosaic"]["reason"].get<std::string>(), "disagreement only"))
          << t["mosaic"].dump();
    } else {
      EXPECT_EQ(t["mosaic"]["status"], "registered") << t["mosaic"].dump();
      EXPECT_TRUE(t["mosaic"]["applied"].get<bool>());
    }
  }
  EXPECT_EQ(summary["mosaic"]["status"], "ok");
  EXPECT_EQ(summary["mosaic"]["traverses"], 3);
  EXPECT_GT(summary["mosaic"]["valid_cells"].get<long>(), 5000);
  // The mosaic's terrain layers, beside it (written a row of tiles at a time).
  EXPECT_EQ(summary["mosaic"]["terrain"]["written"], true) << summary["mosaic"].dump();
  EXPECT_GT(summary["mosaic"]["terrain"]["known_cells"].get<long>(), 1000);
  EXPECT_TRUE(fs::exists(out / "mosaic_terrain.tif"));
  EXPECT_TRUE(fs::exists(out / "mosaic_terrain.png"));

  // The mosaic is, to the byte, the one `rovermap mosaic` makes of the same DEMs in one process
  // (the campaign fused it in three parts); mosaic.json names them relative to the campaign.
  const fs::path single = dir_ / "single";
  fs::create_directories(single);
  const fs::path cwd = fs::current_path();
  fs::current_path(out);
  const CommandResult m = Rovermap(
      "mosaic traverses/000-a/dem.tif traverses/001-b/dem.tif traverses/003-c/dem.tif"
      " --out " +
      (single / "mosaic.tif").string() + " " + kMosaicSets);
  fs::current_path(cwd);
  ASSERT_EQ(m.status, 0) << m.err;
  EXPECT_EQ(Slurp(single / "mosaic.tif"), Slurp(out / "mosaic.tif"));
  EXPECT_EQ(Slurp(single / "mosaic.json"), Slurp(out / "mosaic.json"));

  // Every task left its log and status; the parts are gone, and no temporary is left.
  for (const Step step : {Step::kReplay, Step::kMosaicPlan, Step::kMosaicPart, Step::kFinish}) {
    EXPECT_TRUE(fs::exists(CampaignLayout(out).Log(step, 0))) << campaign::ToString(step);
    EXPECT_TRUE(fs::exists(CampaignLayout(out).Status(step, 0))) << campaign::ToString(step);
  }
  for (int part = 0; part < 3; ++part)
    EXPECT_FALSE(fs::exists(CampaignLayout(out).MosaicPart(part)));
  EXPECT_EQ(Temporaries(out), std::vector<std::string>{});
}

// Determinism, not memory: under the sanitizers Campaign.LocalRun... runs the same code once.
TEST_F(Campaign, OneTaskAtATimeAndOtherPartsGiveTheSameFiles) {
  if (rovermap::testing::kSanitizedBuild) GTEST_SKIP() << "determinism: the Release suite";
  const fs::path a = dir_ / "parallel";
  const fs::path b = dir_ / "serial";
  CommandResult r = Rovermap("campaign " + Recordings() + "--out " + a.string() +
                             " --set campaign.mosaic_tasks=2 " + kMosaicSets);
  EXPECT_EQ(r.status, 1) << r.err;
  r = Rovermap("campaign " + Recordings() + "--out " + b.string() +
               " --jobs 1 --set campaign.mosaic_tasks=7 " + kMosaicSets);
  EXPECT_EQ(r.status, 1) << r.err;
  for (const std::string& file : DeterministicOutputs()) {
    if (file == "config.yaml") continue;  // mosaic_tasks differs
    if (file == "campaign.json") continue;
    EXPECT_TRUE(fs::exists(a / file)) << file;
    EXPECT_EQ(Slurp(a / file), Slurp(b / file)) << file;
  }
}

TEST_F(Campaign, AllGoodTraversesExitZero) {
  const fs::path out = dir_ / "good";
  const CommandResult r =
      Rovermap("campaign " + Recording("a").string() + " " + Recording("c").string() + " --out " +
               out.string() + " " + kMosaicSets);
  EXPECT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["succeeded"], 2);
  EXPECT_EQ(summary["failed"], nlohmann::json::array());
}

TEST_F(Campaign, ANoMosaicCampaignSaysWhy) {
  const fs::path out = dir_ / "none";
  const CommandResult r =
      Rovermap("campaign " + Recording("bad").string() + " --out " + out.string());
  EXPECT_EQ(r.status, 1);
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(summary["mosaic"]["status"], "failed");
  EXPECT_TRUE(Contains(summary["mosaic"]["error"].get<std::string>(), "no traverse was replayed"));
  EXPECT_TRUE(Contains(r.err, "no mosaic"));
  EXPECT_FALSE(fs::exists(out / "mosaic.tif"));
}

TEST_F(Campaign, BadInvocationsAreRefusedBeforeAnyOutput) {
  const fs::path out = dir_ / "refused";
  struct Case {
    std::string args;
    int status;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"", 2, "no traverse"},
      {(dir_ / "nowhere").string(), 1, "nowhere: no such recording"},
      {Recording("a").string() + " --list " + (dir_ / "nolist.txt").string(), 1,
       "nolist.txt: cannot read"},
      {Recording("a").string() + " --wait", 2, "--wait goes with --slurm"},
      {Recording("a").string() + " --local --slurm", 2, "exclude each other"},
      {Recording("a").string() + " --set 'campaign.partition=a b'", 2, "campaign.partition"},
      {Recording("a").string() + " --set campaign.mosaic_tasks=0", 2, "campaign.mosaic_tasks"},
      {Recording("a").string() + " --jobs -1", 2, "--jobs"},
  };
  for (const Case& c : cases) {
    const CommandResult r = Rovermap("campaign " + c.args + " --out " + out.string());
    EXPECT_EQ(r.status, c.status) << c.args << "\n" << r.err;
    EXPECT_TRUE(Contains(r.err, c.message)) << c.args;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
  // A folder that holds files is not a campaign's to write into.
  fs::create_directories(out);
  Write("refused/keep.txt", "mine");
  const CommandResult r =
      Rovermap("campaign " + Recording("a").string() + " --out " + out.string());
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Contains(r.err, "not empty"));
  EXPECT_EQ(Slurp(out / "keep.txt"), "mine");
}

TEST_F(Campaign, ListFileNamesTheTraverses) {
  const std::string list = Write("list.txt", "# site 4, sol 12\n\n" + Recording("a").string() +
                                                 "\n  " + Recording("c").string() + "  \n");
  const fs::path out = dir_ / "listed";
  const CommandResult r =
      Rovermap("campaign --list " + list + " --out " + out.string() + " " + kMosaicSets);
  EXPECT_EQ(r.status, 0) << r.err;
  const CampaignPlan plan =
      campaign::ParseCampaignPlan(Slurp(out / "campaign.json"), out / "campaign.json");
  ASSERT_EQ(plan.traverses.size(), 2u);
  EXPECT_EQ(plan.traverses[0].name, "000-a");
  EXPECT_EQ(plan.traverses[1].name, "001-c");
  EXPECT_EQ(plan.traverses[1].input, Recording("c"));
}

TEST_F(Campaign, WithoutSlurmTheScriptsAreLeftAndTheErrorSaysSo) {
  run_as_ = {"/usr/bin/env", "PATH=" + (dir_ / "empty").string()};
  const fs::path out = dir_ / "noslurm";
  const CommandResult r =
      Rovermap("campaign " + Recording("a").string() + " --slurm --out " + out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Contains(r.err, "sbatch: cannot run it"));
  EXPECT_TRUE(Contains(r.err, "is Slurm installed"));
  EXPECT_TRUE(fs::exists(out / "slurm" / "replay.sbatch"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

TEST(CampaignScripts, AskForWhatTheConfigSays) {
  const CampaignLayout layout("/data/site 4/it's");
  campaign::CampaignOptions options;
  options.cpus_per_task = 3;
  options.memory_mb = 5000;
  options.mosaic_memory_mb = 700;
  options.time_limit_min = 90;
  options.partition = "gpu";
  options.mosaic_tasks = 6;
  const CampaignPlan plan = campaign::MakeCampaignPlan({"/r/a", "/r/b.bag", "/r/c d/"}, options);
  EXPECT_EQ(plan.traverses[1].name, "001-b");
  EXPECT_EQ(plan.traverses[2].name, "002-c_d");
  const auto scripts = campaign::SlurmScripts(layout, plan, options, "/opt/rovermap");
  ASSERT_EQ(scripts.size(), 4u);
  const std::string& replay = scripts[0].text;
  EXPECT_TRUE(Contains(replay, "#SBATCH --array=0-2\n"));
  EXPECT_TRUE(Contains(replay, "#SBATCH --cpus-per-task=3\n"));
  EXPECT_TRUE(Contains(replay, "#SBATCH --mem=5000M\n"));
  EXPECT_TRUE(Contains(replay, "#SBATCH --time=90\n"));
  EXPECT_TRUE(Contains(replay, "#SBATCH --partition=gpu\n"));
  EXPECT_TRUE(Contains(replay,
                       "exec '/opt/rovermap' campaign-task replay '/data/site 4/it'\\''s' "
                       "\"$SLURM_ARRAY_TASK_ID\"\n"));
  EXPECT_FALSE(Contains(scripts[1].text, "--array"));
  EXPECT_TRUE(Contains(scripts[1].text, "#SBATCH --mem=700M\n"));
  EXPECT_TRUE(Contains(scripts[2].text, "#SBATCH --array=0-5\n"));
  EXPECT_TRUE(Contains(scripts[2].text, "#SBATCH --cpus-per-task=1\n"));
  EXPECT_TRUE(Contains(scripts[3].text, "campaign-task finish '/data/site 4/it'\\''s' 0\n"));
  EXPECT_FALSE(Contains(replay, "--account"));
}

TEST(CampaignSummary, ATaskThatLeftNoStatusIsReportedAsKilled) {
  const fs::path dir = testing::ScratchDir();
  const CampaignPlan plan = campaign::MakeCampaignPlan({"/r/a"}, {});
  const std::string text =
      campaign::CampaignSummaryJson(CampaignLayout(dir), plan, "mosaic-plan: nothing");
  const nlohmann::json summary = nlohmann::json::parse(text);
  EXPECT_EQ(summary["failed"], nlohmann::json::array({"000-a"}));
  EXPECT_TRUE(Contains(summary["traverse"][0]["error"].get<std::string>(), "killed or never ran"));
  EXPECT_TRUE(summary["traverse"][0]["exit_status"].is_null());
  EXPECT_EQ(summary["mosaic"]["error"], "mosaic-plan: nothing");
  fs::remove_all(dir);
}

TEST(CampaignPlanJson, RoundTrips) {
  const CampaignPlan plan = campaign::MakeCampaignPlan({"/r/a", "/r/b"}, {});
  const CampaignPlan back = campaign::ParseCampaignPlan(campaign::CampaignPlanJson(plan), "p");
  ASSERT_EQ(back.traverses.size(), 2u);
  EXPECT_EQ(back.traverses[1].input, "/r/b");
  EXPECT_EQ(back.mosaic_tasks, plan.mosaic_tasks);
  EXPECT_TRUE(Contains(
      testing::ErrorOf<std::runtime_error>([] { campaign::ParseCampaignPlan("{}", "x.json"); }),
      "x.json: not a campaign plan"));
}

TEST(MosaicPlanJson, CorrectionsRoundTripToTheBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> any(-1e3, 1e3);
  mosaic::MosaicPlan plan;
  for (int i = 0; i < 5; ++i) {
    plan.files.emplace_back("dem" + std::to_string(i) + ".tif");
    Eigen::Matrix4d T;
    for (int k = 0; k < 16; ++k) T(k / 4, k % 4) = any(rng) / 3.0;
    plan.corrections.push_back(T);
    plan.correction_origins.emplace_back(any(rng) / 7.0, any(rng), 1.0 / 3.0);
    mosaic::InputReport report;
    report.file = plan.files.back().string();
    report.rms_after_m = any(rng) / 11.0;
    plan.result.inputs.push_back(report);
  }
  plan.result.width = 17;
  plan.result.height = 19;
  plan.result.geotransform = {any(rng), 0.1, 0, any(rng), 0, -0.1};
  plan.result.wkt = "LOCAL_CS[\"x\"]";
  const mosaic::MosaicPlan back = mosaic::ParseMosaicPlan(mosaic::MosaicPlanJson(plan), "p");
  ASSERT_EQ(back.corrections.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(back.corrections[i], plan.corrections[i]);
    EXPECT_EQ(back.correction_origins[i], plan.correction_origins[i]);
    EXPECT_EQ(back.result.inputs[i].rms_after_m, plan.result.inputs[i].rms_after_m);
  }
  EXPECT_EQ(back.result.geotransform, plan.result.geotransform);
  EXPECT_EQ(back.result.wkt, plan.result.wkt);
  EXPECT_TRUE(
      Contains(testing::ErrorOf<io::IoError>([] { mosaic::ParseMosaicPlan("[1]", "plan.json"); }),
               "plan.json: not a mosaic plan"));
}

TEST(MosaicParts, CoverEveryRowOnceInWholeRowsOfTiles) {
  mosaic::MosaicOptions options;
  options.tile_cells = 64;
  for (const int height : {1, 63, 64, 65, 640, 1000}) {
    mosaic::MosaicPlan plan;
    plan.result.height = height;
    for (const int parts : {1, 2, 3, 7, 20}) {
      int next = 0;
      for (int p = 0; p < parts; ++p) {
        const auto [row0, row1] = mosaic::MosaicPartRows(plan, p, parts, options);
        EXPECT_EQ(row0, next) << height << " " << parts << " " << p;
        EXPECT_LE(row0, row1);
        EXPECT_TRUE(row0 % 64 == 0 || row0 == height);
        next = row1;
      }
      EXPECT_EQ(next, height) << height << " " << parts;
    }
  }
  mosaic::MosaicPlan plan;
  plan.result.height = 10;
  EXPECT_THROW(mosaic::MosaicPartRows(plan, 2, 2, options), std::invalid_argument);
}

}  // namespace
}  // namespace rovermap
