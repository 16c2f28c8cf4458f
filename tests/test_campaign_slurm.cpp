// The campaign through a real Slurm cluster: submitted with sbatch as job arrays, awaited, and
// its files identical to the same campaign run with --local. Needs a cluster: `make test-slurm`
// starts a single-node one (scripts/slurm/cluster.sh) and runs the tests labelled "slurm".
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/CampaignFixture.hpp"
#include "tests/support/ErrorText.hpp"

namespace rovermap {
namespace {

namespace fs = std::filesystem;
using testing::CampaignFixture;
using testing::CommandResult;
using testing::Contains;
using testing::Slurp;

using CampaignSlurm = CampaignFixture;

TEST_F(CampaignSlurm, JobArraysGiveTheFilesOfALocalRun) {
  const char* conf = std::getenv("SLURM_CONF");
  ASSERT_TRUE(conf != nullptr && fs::exists(conf))
      << "no Slurm cluster (SLURM_CONF): run this test with `make test-slurm`";
  const fs::path slurm = dir_ / "slurm";
  const fs::path local = dir_ / "local";
  const std::string sets =
      " --set campaign.mosaic_tasks=3 --set campaign.memory_mb=1024 " + std::string(kMosaicSets);
  const CommandResult s =
      Rovermap("campaign " + Recordings() + "--slurm --wait --out " + slurm.string() + sets);
  // The bad traverse fails under Slurm as it does here: exit 1, the rest in the mosaic.
  EXPECT_EQ(s.status, 1) << s.err;
  EXPECT_TRUE(Contains(s.err, "replay: job "));
  EXPECT_TRUE(Contains(s.err, "002-bad failed, left out"));
  const CommandResult l = Rovermap("campaign " + Recordings() + "--out " + local.string() + sets);
  EXPECT_EQ(l.status, 1) << l.err;
  EXPECT_EQ(s.out, l.out);  // summary.json

  for (const std::string& file : DeterministicOutputs()) {
    ASSERT_TRUE(fs::exists(slurm / file)) << file;
    EXPECT_EQ(Slurp(slurm / file), Slurp(local / file)) << file;
  }
  // Slurm ran the arrays: one scheduler log per array task, none per task of a local run.
  for (const char* log :
       {"replay-0.out", "replay-3.out", "mosaic-plan.out", "mosaic-part-2.out", "finish.out"}) {
    EXPECT_TRUE(fs::exists(slurm / "slurm" / log)) << log;
  }
  EXPECT_FALSE(fs::exists(local / "slurm" / "replay-0.out"));
  const nlohmann::json summary = nlohmann::json::parse(Slurp(slurm / "summary.json"));
  EXPECT_EQ(summary["succeeded"], 3);
  EXPECT_EQ(summary["mosaic"]["status"], "ok");
}

}  // namespace
}  // namespace rovermap
