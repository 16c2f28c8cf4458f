// `rovermap replay --reference-dem FILE` and revisits (docs/graph.md): a simulated 300 m cratered
// traverse whose dead reckoning errs by 5 % of its distance, matched every 20 m against a 1 m/post
// reference DEM of the true terrain with 0.2 m of noise and a 0.5 m georeferencing error. The
// graph's ATE is at most 0.3× the frame-to-frame one and does not grow along the traverse; on
// a plain the matches are refused and the result is the frame-to-frame one; a reference that
// cannot be used is reported and left out, or stops the run when it is required.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "io/GeoTiff.hpp"
#include "io/Georeference.hpp"
#include "io/Sequence.hpp"
#include "io/Tum.hpp"
#include "mapper/Mapper.hpp"
#include "tests/support/CommandFixture.hpp"
#include "tests/support/DriftCsv.hpp"
#include "tests/support/PipelineDefaults.hpp"
#include "tests/support/Sanitizers.hpp"
#include "tests/support/ScratchDir.hpp"

namespace fs = std::filesystem;
using rovermap::testing::CommandResult;
using rovermap::testing::ReadCsv;
using rovermap::testing::RunRovermapIn;
using rovermap::testing::Slurp;

namespace {

const fs::path kTinyCloud = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_cloud";

// The 300 m loop of test_gnss_graph, on cratered ground (planetary relief at the reference's
// scale), `extra` simulator keys on top.
const std::string kTraverse =
    " --set sim.sensor=cloud --set sim.frames=150 --set sim.frame_rate_hz=1"
    " --set sim.speed_m_s=2 --set sim.terrain_size_m=400 --set sim.terrain_cell_m=0.2"
    " --set sim.turn_radius_m=40 --set sim.path=loop --set sim.start_y_m=-40"
    " --set sim.odom_scale_error=0.05 --set sim.reference_post_m=1 --set dem.cell_size_m=0.2";
const std::string kMaps = " --set dem.cell_size_m=0.2 --set octomap.enabled=false";
// The reference's own effect: the loop's revisit (after 251 m) and the cratered traverse's GNSS
// fixes (too few fixes: gnss.csv left out) left out.
const std::string kReplay =
    kMaps + " --set revisit.enabled=false --set graph.min_gnss_fixes=1000000";

// Per frame, the horizontal error of `estimate` against the truth after removing their mean
// difference (the reference's georeferencing error moves the whole trajectory).
std::vector<double> HorizontalErrors(const fs::path& estimate, const fs::path& truth) {
  const auto e = rovermap::io::ReadTum(estimate);
  const auto t = rovermap::io::ReadTum(truth);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < e.size(); ++k)
    mean += (e[k].T_world_body.translation() - t[k].T_world_body.translation()).head<2>();
  mean /= static_cast<double>(e.size());
  std::vector<double> out;
  for (std::size_t k = 0; k < e.size(); ++k)
    out.push_back(
        ((e[k].T_world_body.translation() - t[k].T_world_body.translation()).head<2>() - mean)
            .norm());
  return out;
}

double Rms(const std::vector<double>& v, std::size_t from, std::size_t to) {
  double s = 0.0;
  for (std::size_t k = from; k < to; ++k) s += v[k] * v[k];
  return std::sqrt(s / static_cast<double>(to - from));
}

// The replay's pipeline options for the out-and-back (its --set keys).
rovermap::mapper::PipelineOptions OutAndBackOptions() {
  rovermap::mapper::PipelineOptions o = rovermap::testing::PipelineDefaults();
  o.dem.cell_size_m = 0.2;
  o.octomap.enabled = false;
  return o;
}

// The DEM of frames [first, last] of `seq` alone, each fused where `trajectory` puts it with the
// chain's covariance (`results`, the replay's own), as replay fuses it again from the graph.
void PassDem(const fs::path& seq, const std::vector<rovermap::mapper::FrameResult>& results,
             const fs::path& trajectory, std::size_t first, std::size_t last, const fs::path& tif,
             bool pose_sigma) {
  namespace rm = rovermap::mapper;
  const auto poses = rovermap::io::ReadTum(trajectory);
  rovermap::io::SequenceReader reader(seq);
  rm::Mapper pass(reader.info(), OutAndBackOptions());
  for (std::size_t k = first; k <= last; ++k) {
    if (results[k].status == rm::FrameStatus::kBadFrame) continue;
    const rm::PreparedFrame prepared = pass.Prepare(reader.Read(k));
    ASSERT_TRUE(prepared.loaded.ok) << k;
    rm::ChainStep step = results[k].step;
    step.T_world_body = poses[k].T_world_body;
    if (!pose_sigma) step.covariance.setZero();
    pass.FuseAgain(prepared, step);
  }
  rovermap::io::WriteDemGeoTiff(tif, pass.elevation_map(), pass.georeference());
}

class ReferenceGraph : public ::testing::Test {
 protected:
  void SetUp() override {
    if (rovermap::testing::kSanitizedBuild) GTEST_SKIP() << "statistics: the Release suite";
  }
  static void SetUpTestSuite() {
    dir_ = new fs::path(rovermap::testing::ScratchDir());
    if (rovermap::testing::kSanitizedBuild) return;
    const std::string seq = (*dir_ / "seq").string();
    const CommandResult sim =
        RunRovermapIn(*dir_, "simulate --out " + seq + kTraverse +
                                 " --set sim.craters=800 --set sim.crater_max_radius_m=10"
                                 " --set sim.gnss_every_frames=5");
    ASSERT_EQ(sim.status, 0) << sim.err;
    // The reference with GNSS fixes beside it: the fixes place the reference.
    const CommandResult both = RunRovermapIn(
        *dir_, "replay " + seq + " --out " + (*dir_ / "both").string() + " --reference-dem " + seq +
                   "/reference_dem.tif" + kMaps + " --set revisit.enabled=false");
    ASSERT_EQ(both.status, 0) << both.err;
    const CommandResult with =
        RunRovermapIn(*dir_, "replay " + seq + " --out " + (*dir_ / "graph").string() +
                                 " --reference-dem " + seq + "/reference_dem.tif" + kReplay);
    ASSERT_EQ(with.status, 0) << with.err;
    *err_ = with.err;
    // The same ground without craters: the default relief, which 1 m posts of 0.2 m noise
    // cannot place (docs/graph.md).
    const std::string plain = (*dir_ / "plain").string();
    ASSERT_EQ(RunRovermapIn(*dir_, "simulate --out " + plain + kTraverse).status, 0);
    const CommandResult refused =
        RunRovermapIn(*dir_, "replay " + plain + " --out " + (*dir_ / "plain_out").string() +
                                 " --reference-dem " + plain + "/reference_dem.tif" + kReplay);
    ASSERT_EQ(refused.status, 0) << refused.err;
    *plain_err_ = refused.err;
    const CommandResult without = RunRovermapIn(
        *dir_, "replay " + plain + " --out " + (*dir_ / "plain_f2f").string() + kReplay);
    ASSERT_EQ(without.status, 0) << without.err;
    // The same loop with its revisit (the defaults): the last 50 m come back over the first.
    const CommandResult revisit = RunRovermapIn(
        *dir_, "replay " + plain + " --out " + (*dir_ / "plain_revisit").string() + kMaps);
    ASSERT_EQ(revisit.status, 0) << revisit.err;
    *revisit_err_ = revisit.err;
    // Out and back: 98 m east, a U-turn of 2 m radius, 98 m back 4 m beside the way out.
    const std::string oab = (*dir_ / "oab").string();
    ASSERT_EQ(RunRovermapIn(*dir_, "simulate --out " + oab +
                                       " --set sim.sensor=cloud --set sim.frames=101"
                                       " --set sim.frame_rate_hz=1 --set sim.speed_m_s=2"
                                       " --set sim.terrain_size_m=240 --set sim.terrain_cell_m=0.2"
                                       " --set sim.path=out_and_back --set sim.turn_radius_m=2"
                                       " --set sim.start_x_m=-100 --set sim.start_y_m=-2"
                                       " --set sim.odom_scale_error=0.05 --set dem.cell_size_m=0.2"
                                       " --set sim.craters=800 --set sim.crater_max_radius_m=10")
                  .status,
              0);
    const CommandResult back =
        RunRovermapIn(*dir_, "replay " + oab + " --out " + (*dir_ / "oab_out").string() + kMaps);
    ASSERT_EQ(back.status, 0) << back.err;
    *oab_err_ = back.err;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static nlohmann::json Summary(const std::string& out) {
    return nlohmann::json::parse(Slurp(*dir_ / out / "summary.json"));
  }
  // The checks, each on the traverses simulated once (gtest_discover_tests runs every TEST in a
  // process of its own, so one TEST holds them all).
  void ThreeHundredMetresOnCrateredGround();
  void OnAPlainEveryMatchIsRefusedAndTheResultIsTheFrameToFrameOne();
  void TheRevisitClosesTheLoop();
  void OutAndBackRevisitsBringThePassesTogether();

  static fs::path* dir_;
  static inline std::string* err_ = new std::string;
  static inline std::string* plain_err_ = new std::string;
  static inline std::string* revisit_err_ = new std::string;
  static inline std::string* oab_err_ = new std::string;
};
fs::path* ReferenceGraph::dir_ = nullptr;

}  // namespace

void ReferenceGraph::ThreeHundredMetresOnCrateredGround() {
  const nlohmann::json s = Summary("graph");
  const nlohmann::json& g = s["graph"];
  ASSERT_TRUE(g["solved"].get<bool>()) << g.dump(2);
  const double ate = s["metrics"]["registered"]["ate_rmse_m"].get<double>();
  const double f2f = s["metrics"]["frame_to_frame"]["ate_rmse_m"].get<double>();
  std::printf("ATE: graph %.3f m, frame to frame %.3f m; matches %zu used of %zu\n", ate, f2f,
              g["reference_used"].get<std::size_t>(), g["reference_matches"].get<std::size_t>());
  // Measured: 0.21 m against 1.83 m, 14 of 15 matches used.
  EXPECT_GT(f2f, 0.8);
  EXPECT_LT(ate, 0.3 * f2f);
  EXPECT_GE(g["reference_used"].get<int>(), 10);
  EXPECT_EQ(g["reference_rejected"], 0);
  // Bounded: the last third of the traverse is no worse than the first (the frame-to-frame
  // error more than doubles over the same frames).
  const auto graph =
      HorizontalErrors(*dir_ / "graph/trajectory.tum", *dir_ / "seq/groundtruth.tum");
  const auto chain =
      HorizontalErrors(*dir_ / "graph/trajectory_f2f.tum", *dir_ / "seq/groundtruth.tum");
  const std::size_t n = graph.size();
  std::printf("horizontal RMS, first and last third: graph %.3f %.3f m, chain %.3f %.3f m\n",
              Rms(graph, 0, n / 3), Rms(graph, n - n / 3, n), Rms(chain, 0, n / 3),
              Rms(chain, n - n / 3, n));
  EXPECT_LT(Rms(graph, n - n / 3, n), std::max(1.5 * Rms(graph, 0, n / 3), 0.3));
  // Each match says what became of it, in drift.csv and summary.json.
  std::size_t used_rows = 0;
  for (const auto& row : ReadCsv(*dir_ / "graph/drift.csv"))
    used_rows += row.at("reference") == "used";
  EXPECT_EQ(used_rows, g["reference_used"].get<std::size_t>());
  for (const auto& m : g["reference"]) {
    EXPECT_TRUE(m.contains("sigma_x_m") && m.contains("relief_ratio") && m.contains("reason"));
  }
  EXPECT_NE(err_->find("replay: reference match, frames"), std::string::npos) << *err_;
  // Against the world, the reference's own misplacement (0.5 m) in every frame's σ through the
  // matches' shared offset: measured 0.993 of frames within 2σ (0.10 without it, mean NEES 53).
  EXPECT_EQ(g["covariance"], "against the world");
  EXPECT_GT(s["pose_uncertainty"]["within_2sigma"].get<double>(), 0.85);
  // With GNSS fixes beside the matches the graph finds where the reference lies: measured
  // (0.51, -0.15) m against the simulator's (0.5, 0) m, 0.993 of frames within 2σ.
  const nlohmann::json b = Summary("both");
  ASSERT_TRUE(b["graph"]["solved"].get<bool>()) << b["graph"].dump(2);
  EXPECT_GE(b["graph"]["gnss_used"].get<int>(), 20);
  const auto offset = b["graph"]["reference_horizontal_offset_m"].get<std::vector<double>>();
  ASSERT_EQ(offset.size(), 2u);
  EXPECT_NEAR(offset[0], 0.5, 0.25);
  EXPECT_NEAR(offset[1], 0.0, 0.25);
  EXPECT_GT(b["pose_uncertainty"]["within_2sigma"].get<double>(), 0.85);
}

void ReferenceGraph::OnAPlainEveryMatchIsRefusedAndTheResultIsTheFrameToFrameOne() {
  const nlohmann::json g = Summary("plain_out")["graph"];
  EXPECT_FALSE(g["solved"].get<bool>());
  EXPECT_GT(g["reference_matches"].get<int>(), 10);
  EXPECT_EQ(g["reference_refused"], g["reference_matches"]);
  for (const auto& m : g["reference"]) {
    EXPECT_EQ(m["status"], "refused");
    EXPECT_NE(m["reason"].get<std::string>().find("ill-conditioned"), std::string::npos) << m;
  }
  EXPECT_EQ(Slurp(*dir_ / "plain_out/trajectory.tum"), Slurp(*dir_ / "plain_f2f/trajectory.tum"));
  EXPECT_NE(plain_err_->find("refused: ill-conditioned"), std::string::npos) << *plain_err_;
  for (const auto& row : ReadCsv(*dir_ / "plain_out/drift.csv")) {
    EXPECT_TRUE(row.at("reference") == "refused" || row.at("reference") == "none");
  }
}

// Revisits: the loop's last 50 m matched onto its first (min_gap_m 100 m); the loop factor holds
// the whole traverse, no reference needed.
void ReferenceGraph::TheRevisitClosesTheLoop() {
  const nlohmann::json s = Summary("plain_revisit");
  const nlohmann::json& g = s["graph"];
  ASSERT_TRUE(g["solved"].get<bool>()) << g.dump(2);
  EXPECT_GE(g["revisits_used"].get<int>(), 1);
  EXPECT_EQ(g["revisits_rejected"], 0);
  const double ate = s["metrics"]["registered"]["ate_rmse_m"].get<double>();
  const double f2f = s["metrics"]["frame_to_frame"]["ate_rmse_m"].get<double>();
  std::printf("ATE with the revisit: graph %.3f m, frame to frame %.3f m\n", ate, f2f);
  // Measured: 0.234 m against 1.258 m, one revisit (frames 121-140 onto frame 15).
  EXPECT_LT(ate, 0.3 * f2f);
  for (const auto& v : g["revisit"])
    EXPECT_GT(v["frame"].get<int>(), v["earlier_frame"].get<int>() + 50);
  std::size_t used = 0;
  for (const auto& row : ReadCsv(*dir_ / "plain_revisit/drift.csv"))
    used += row.at("revisit") == "used";
  EXPECT_EQ(used, g["revisits_used"].get<std::size_t>());
  EXPECT_NE(revisit_err_->find("replay: revisit, frames"), std::string::npos) << *revisit_err_;
}

// Out and back (docs/graph.md, "Revisits"): the way back sees the way out's ground from the other
// side (other slopes lit, other ones hidden) and beside its track, where the frames are sparse.
// The looks find that ground, and the matches are refused (ill-conditioned) rather than used:
// the result stays the chain's. A change that makes them count must show that they are right.
void ReferenceGraph::OutAndBackRevisitsBringThePassesTogether() {
  namespace rm = rovermap::mapper;
  EXPECT_NE(oab_err_->find("replay: revisit, frames"), std::string::npos) << *oab_err_;
  const nlohmann::json s = Summary("oab_out");
  ASSERT_TRUE(s.contains("graph")) << s.dump(2);
  const nlohmann::json& g = s["graph"];
  ASSERT_TRUE(g["solved"].get<bool>()) << g.dump(2);
  EXPECT_GE(g["revisits_used"].get<int>(), 1);
  // The chain's covariances, as the replay had them (the same pipeline, frame by frame).
  const fs::path seq = *dir_ / "oab";
  rovermap::io::SequenceReader reader(seq);
  rm::Mapper chain(reader.info(), OutAndBackOptions());
  rovermap::io::Frame frame;
  while (reader.Next(&frame)) chain.ProcessFrame(frame);
  const std::vector<rm::FrameResult>& results = chain.results();
  const auto f2f = rovermap::io::ReadTum(*dir_ / "oab_out/trajectory_f2f.tum");
  ASSERT_EQ(results.size(), f2f.size());
  EXPECT_LT((results.back().step.T_world_body.translation() - f2f.back().T_world_body.translation())
                .norm(),
            1e-3);
  // Each pass's DEM alone (out: frames 0-48, back: 53-100, the U-turn between), placed by the
  // graph and by the chain; the mosaic counts the cells where the two differ by more than 2σ.
  auto apart = [&](const fs::path& tum, bool pose_sigma) {
    const std::string trajectory = tum.stem().string() + (pose_sigma ? "" : "_nopose");
    const fs::path folder = *dir_ / ("passes_" + trajectory);
    fs::create_directories(folder);
    PassDem(seq, results, tum, 0, 48, folder / "out.tif", pose_sigma);
    PassDem(seq, results, tum, 53, 100, folder / "back.tif", pose_sigma);
    const CommandResult m = RunRovermapIn(*dir_, "mosaic " + (folder / "out.tif").string() + " " +
                                                     (folder / "back.tif").string() + " --out " +
                                                     (folder / "mosaic.tif").string() +
                                                     " --set mosaic.disagreement_sigma=2");
    EXPECT_EQ(m.status, 0) << m.err;
    const nlohmann::json j = nlohmann::json::parse(Slurp(folder / "mosaic.json"));
    const nlohmann::json& back = j["inputs"][1];
    const double cells = back["overlap_cells"].get<double>();
    const double beyond = back["disagreement_before"].get<double>();
    std::printf("passes placed by %s: %.0f of %.0f overlap cells beyond 2 sigma, RMS %.3f m\n",
                trajectory.c_str(), beyond, cells, back["rms_before_m"].get<double>());
    return std::make_tuple(beyond / std::max(cells, 1.0), cells,
                           back["rms_before_m"].get<double>());
  };
  const fs::path graph = *dir_ / "oab_out/trajectory.tum";
  const fs::path chained = *dir_ / "oab_out/trajectory_f2f.tum";
  // With the DEM's σ (the chain's pose covariance in it, as replay fuses): both placements are
  // within 2σ, the chain's because its σ has grown with its drift; the graph's difference is a
  // third of the chain's.
  const auto [graph_beyond, graph_cells, graph_rms] = apart(graph, true);
  const auto [chain_beyond, chain_cells, chain_rms] = apart(chained, true);
  EXPECT_GT(graph_cells, 500.0);
  EXPECT_LT(graph_beyond, 0.02);
  EXPECT_LT(graph_rms, 0.4 * chain_rms);
  // With the points' σ alone (no pose uncertainty): the true poses put the passes within it
  // (the measure holds), the chain almost nowhere, the graph over half the overlap.
  const auto [truth_beyond, truth_cells, truth_rms] = apart(seq / "groundtruth.tum", false);
  const auto [graph_alone, graph_alone_cells, graph_alone_rms] = apart(graph, false);
  const auto [chain_alone, chain_alone_cells, chain_alone_rms] = apart(chained, false);
  // Measured: 0 of 705 and 0 of 356 cells beyond 2σ (RMS 0.203 and 0.665 m); points' σ alone:
  // truth 1 of 541 (0.043 m), graph 217 of 487, chain 302 of 314.
  EXPECT_LT(truth_beyond, 0.05);
  EXPECT_GT(chain_alone, 0.8);
  EXPECT_LT(graph_alone, 0.6 * chain_alone);
}

TEST_F(ReferenceGraph, CrateredGroundIsHeldAndAPlainRefused) {
  {
    SCOPED_TRACE("300 m on cratered ground: ATE at most 0.3x frame to frame, bounded");
    ThreeHundredMetresOnCrateredGround();
  }
  {
    SCOPED_TRACE("on a plain every match refused, the frame-to-frame result");
    OnAPlainEveryMatchIsRefusedAndTheResultIsTheFrameToFrameOne();
  }
  {
    SCOPED_TRACE("the revisit closes the loop");
    TheRevisitClosesTheLoop();
  }
  {
    SCOPED_TRACE("out and back: the revisits bring the DEM's two passes within 2 sigma");
    OutAndBackRevisitsBringThePassesTogether();
  }
}

// A reference that cannot be used: the run goes on without it and says why (exit 0), unless
// reference.required, when it stops before writing anything (exit 1) naming the file.
class ReferenceInput : public rovermap::testing::CommandFixture {
 protected:
  // A raster `width` x `height` of `value` in the tiny sequence's UTM zone, `offset_m` east of
  // its origin, with `wkt` (the sequence's CRS when empty).
  fs::path Raster(const std::string& name, float value, double offset_m, std::string wkt = "") {
    const rovermap::io::SequenceInfo info = rovermap::io::ReadSequenceInfo(kTinyCloud);
    const rovermap::io::Georeference georef(info.origin);
    rovermap::io::RasterFrame frame;
    frame.width = frame.height = 60;
    const Eigen::Vector2d p0 = georef.origin_projected();
    frame.geotransform = {p0.x() - 30.0 + offset_m, 1.0, 0.0, p0.y() + 30.0, 0.0, -1.0};
    frame.wkt = wkt.empty() ? georef.wkt() : wkt;
    const std::vector<float> z(3600, value);
    const fs::path path = dir_ / name;
    rovermap::io::WriteFloatGeoTiff(path, frame, {{&z, "elevation", "m"}});
    return path;
  }
  CommandResult Replay(const fs::path& reference, const std::string& out,
                       const std::string& extra = "") {
    return Rovermap("replay " + kTinyCloud.string() + " --out " + (dir_ / out).string() +
                    " --reference-dem " + reference.string() + " --set octomap.enabled=false" +
                    extra);
  }
};

TEST_F(ReferenceInput, ElsewhereAllNanOrOfAnotherBodyIsLeftOutAndSaid) {
  const std::string mars =
      "GEOGCS[\"Mars 2000\",DATUM[\"D_Mars_2000\",SPHEROID[\"Mars_2000_IAU_IAG\",3396190,0]],"
      "PRIMEM[\"Reference_Meridian\",0],UNIT[\"degree\",0.0174532925199433]]";
  const struct {
    fs::path file;
    std::string why;
  } cases[] = {{Raster("far.tif", 1.0f, 5000.0), "does not cover the traverse"},
               {Raster("nan.tif", NAN, 0.0), "holds no height"},
               {Raster("mars.tif", 1.0f, 0.0, mars), "is of another body"},
               {dir_ / "missing.tif", "missing.tif"}};
  int k = 0;
  for (const auto& c : cases) {
    const std::string out = "out" + std::to_string(k++);
    const CommandResult r = Replay(c.file, out);
    EXPECT_EQ(r.status, 0) << c.file << "\n" << r.err;
    EXPECT_NE(r.err.find("reference DEM left out"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.why), std::string::npos) << r.err;
    const nlohmann::json s = nlohmann::json::parse(Slurp(dir_ / out / "summary.json"));
    EXPECT_NE(s["graph"]["reference_unusable"].get<std::string>().find(c.why), std::string::npos)
        << s["graph"].dump(2);
    EXPECT_FALSE(s["graph"]["solved"].get<bool>());
  }
}

TEST_F(ReferenceInput, RequiredAndUnusableStopsBeforeAnyOutput) {
  const fs::path far = Raster("far.tif", 1.0f, 5000.0);
  const CommandResult r = Replay(far, "out", " --set reference.required=true");
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find(far.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("does not cover the traverse"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "summary.json"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "dem.tif"));
  const CommandResult bad_key = Replay(far, "out2", " --set reference.every_m=0");
  EXPECT_EQ(bad_key.status, 2) << bad_key.err;
  EXPECT_NE(bad_key.err.find("reference.every_m"), std::string::npos) << bad_key.err;
}
