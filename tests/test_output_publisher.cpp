// The daemon's background publications: an OutputState is the mapper as it was when taken (the
// frames processed after it do not leak into the files, the OctoMap's bytes included, which its
// own thread serialises), the layers it rasterises are the map's published cells, and a
// publication's error comes back to the caller once.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "config/Config.hpp"
#include "dem/OcTreeBytes.hpp"
#include "dem/OctoMapFusion.hpp"
#include "io/DemLayers.hpp"
#include "io/IoError.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/OctoMapWorker.hpp"
#include "service/OutputPublisher.hpp"
#include "service/OutputState.hpp"
#include "service/Outputs.hpp"
#include "tests/support/CommandFixture.hpp"
#include "tests/support/ScratchDir.hpp"

namespace fs = std::filesystem;
using namespace rovermap;
using rovermap::testing::Slurp;

namespace {

const fs::path kTinyCloud = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_cloud";  // 5 frames

std::unique_ptr<mapper::Mapper> MapperAfter(std::size_t frames) {
  const config::Config c;
  io::SequenceReader reader(kTinyCloud);
  auto m = std::make_unique<mapper::Mapper>(
      reader.info(),
      mapper::PipelineOptions{c.mapper, c.registration, c.stereo, c.dem, c.octomap, c.terrain});
  io::Frame frame;
  for (std::size_t k = 0; k < frames && reader.Next(&frame); ++k) m->ProcessFrame(frame);
  return m;
}

TEST(DemLayers, HoldExactlyThePublishedCells) {
  const auto m = MapperAfter(5);
  const dem::ElevationMap& map = m->elevation_map();
  const io::DemLayers layers = io::RasteriseDem(map);
  ASSERT_GT(layers.valid_cells, 100u);
  EXPECT_EQ(layers.valid_cells, map.PublishedCellCount());
  EXPECT_EQ(static_cast<std::size_t>(layers.width) * static_cast<std::size_t>(layers.height),
            layers.elevation_m.size());
  // Brute force: every pixel against the map's own published height at the cell's centre.
  std::size_t seen = 0;
  for (int row = 0; row < layers.height; ++row) {
    for (int col = 0; col < layers.width; ++col) {
      const dem::CellIndex cell{layers.min.x + col, layers.max.y - row};
      const Eigen::Vector2d centre = map.CellCenterWorld(cell);
      const std::size_t i = static_cast<std::size_t>(row) * layers.width + col;
      const double height = map.HeightAt(centre.x(), centre.y());
      if (std::isnan(height)) {
        EXPECT_TRUE(std::isnan(layers.elevation_m[i]));
        EXPECT_EQ(layers.count[i], 0.0f);
        continue;
      }
      ++seen;
      EXPECT_FLOAT_EQ(layers.elevation_m[i], static_cast<float>(height));
      EXPECT_FLOAT_EQ(layers.stddev_m[i],
                      static_cast<float>(std::sqrt(map.VarianceAt(centre.x(), centre.y()))));
      EXPECT_GT(layers.count[i], 0.0f);
    }
  }
  EXPECT_EQ(seen, layers.valid_cells);
}

TEST(OutputState, IsTheMapperAsItWasWhenTaken) {
  const fs::path dir = rovermap::testing::ScratchDir();
  auto m = MapperAfter(3);
  const mapper::OutputState state(*m);
  fs::create_directories(dir / "then");
  fs::create_directories(dir / "state");
  mapper::WriteOutputs(dir / "then", *m, {}, eval::EvalOptions{});
  // Two more frames change the map, the OctoMap and the chain; the state must not see them.
  io::SequenceReader reader(kTinyCloud);
  io::Frame frame;
  for (int k = 0; k < 5 && reader.Next(&frame); ++k) {
    if (k >= 3) m->ProcessFrame(frame);
  }
  ASSERT_EQ(m->results().size(), 5u);
  mapper::OutputPublisher publisher;
  publisher.Publish(dir / "state", state, {}, eval::EvalOptions{});
  publisher.Wait();
  EXPECT_GT(publisher.last_write_ms(), 0.0);
  for (const char* name : {"trajectory.tum", "odometry.tum", "drift.csv", "dem.tif", "map.bt"}) {
    EXPECT_EQ(Slurp(dir / "state" / name), Slurp(dir / "then" / name)) << name;
  }
  const auto summary = nlohmann::json::parse(Slurp(dir / "state" / "summary.json"));
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_EQ(summary["dem"]["cells"], state.dem.valid_cells);
  EXPECT_GT(summary["octomap"]["leaves"].get<std::size_t>(), 0u);
}

// The OctoMap's bytes asked for after frame k are the tree after exactly k frames, whether the
// request finds frame k still queued, being inserted, or done, and however many frames follow.
TEST(OctoMapWorker, SerialisesTheTreeAsItWasWhenAsked) {
  dem::OctoMapOptions options;
  options.resolution_m = 0.2;
  mapper::OctoMapWorker worker(options);
  dem::OctoMapFusion serial(options);
  const auto frame = [](int k) {
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 2000; ++i)
      points.emplace_back(0.5 * k + 0.01 * (i % 100), 0.02 * (i / 100), 0.1 * std::sin(i + k));
    return points;
  };
  const Eigen::Vector3d origin(0.0, 0.0, 1.5);
  std::vector<std::shared_future<std::optional<mapper::OctoMapWorker::TreeBytes>>> asked;
  std::vector<std::string> expected;
  for (int k = 0; k < 6; ++k) {
    worker.Insert(frame(k), origin, static_cast<std::uint32_t>(k));
    serial.InsertFrame(frame(k), origin);
    if (k % 2 == 1 || k == 4) {
      asked.push_back(worker.SerialiseWhenQueuedIn(/*with_ot=*/k == 3));
      expected.push_back(dem::BinaryOcTreeBytes(*serial.tree()));
      if (k == 3) expected.push_back(dem::FullOcTreeBytes(*serial.tree()));
    }
  }
  asked.push_back(worker.SerialiseWhenQueuedIn(false));  // twice in a row, nothing between
  asked.push_back(worker.SerialiseWhenQueuedIn(false));
  expected.push_back(dem::BinaryOcTreeBytes(*serial.tree()));
  std::size_t e = 0;
  for (std::size_t i = 0; i < asked.size(); ++i) {
    const auto& bytes = asked[i].get();
    ASSERT_TRUE(bytes.has_value());
    const std::string& want = expected[std::min(e, expected.size() - 1)];
    EXPECT_EQ(bytes->bt, want) << "request " << i;
    ++e;
    if (!bytes->ot.empty()) {
      EXPECT_EQ(bytes->ot, expected[e++]) << "request " << i;
    }
  }
  dem::OctoMapOptions off;
  off.enabled = false;
  EXPECT_FALSE(mapper::OctoMapWorker(off).SerialiseWhenQueuedIn(true).get().has_value());
}

TEST(OutputPublisher, AFailedPublicationIsReportedOnceNamingTheFile) {
  const fs::path dir = rovermap::testing::ScratchDir();
  const auto m = MapperAfter(2);
  mapper::OutputPublisher publisher;
  publisher.Publish(dir / "missing", mapper::OutputState(*m), {}, eval::EvalOptions{});
  try {
    publisher.Wait();
    FAIL() << "no error";
  } catch (const io::IoError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "missing").string()), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(publisher.Wait());  // once

  // Poll never blocks and reports a finished failure, then nothing.
  publisher.Publish(dir / "missing", mapper::OutputState(*m), {}, eval::EvalOptions{});
  bool thrown = false;
  for (int k = 0; k < 500 && !thrown; ++k) {
    try {
      publisher.Poll();
    } catch (const io::IoError&) {
      thrown = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(thrown);
  EXPECT_NO_THROW(publisher.Wait());

  // And the next publication goes through.
  fs::create_directories(dir / "ok");
  publisher.Publish(dir / "ok", mapper::OutputState(*m), {}, eval::EvalOptions{});
  publisher.Wait();
  EXPECT_TRUE(fs::exists(dir / "ok" / "summary.json"));
}

}  // namespace
