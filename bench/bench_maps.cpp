// Benchmarks of the map products: DEM fusion throughput (points/s, one core), OctoMap insertion per
// stereo-sized frame at 0.1 and 0.05 m, the OctoMap moved onto a pose graph, GeoTIFF write of a
// 2000×2000 map, and memory and per-frame cost over a long synthetic traverse, and the terrain
// layers (terrain/) per megacell against plain per-cell loops.
//   build/bench/bench_maps [--benchmark_filter=...]

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "dem/BatchOcTree.hpp"
#include "dem/ElevationMap.hpp"
#include "dem/OcTreeBytes.hpp"
#include "dem/OctoMapFusion.hpp"
#include "dem/QuietStderr.hpp"
#include "io/GeoTiff.hpp"
#include "io/Georeference.hpp"
#include "io/TerrainOutputs.hpp"
#include "io/TiledGeoTiff.hpp"
#include "terrain/TerrainCache.hpp"
#include "terrain/TerrainLayers.hpp"

namespace {

using namespace rovermap;

double Terrain(double x, double y) {
  return 0.3 * std::sin(0.7 * x) * std::cos(0.5 * y) + 0.05 * std::sin(3.1 * x + 1.7 * y);
}

// A stereo-sized frame: `n` points on the terrain in the footprint of a forward-looking camera
// at (x0, 0): 1.5..10 m ahead, ±45° wide, ordered row by row like an image.
std::vector<Eigen::Vector3d> StereoFrame(double x0, std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> points;
  points.reserve(n);
  const int rows = 480;
  const auto cols = static_cast<int>(n / rows);
  for (int r = 0; r < rows; ++r) {
    const double range = 1.5 + 8.5 * std::pow(static_cast<double>(r) / rows, 2.0);
    for (int c = 0; c < cols; ++c) {
      const double bearing = (static_cast<double>(c) / cols - 0.5) * M_PI / 2;
      const double x = x0 + range * std::cos(bearing);
      const double y = range * std::sin(bearing);
      points.emplace_back(x, y, Terrain(x, y) + noise(rng));
    }
  }
  return points;
}

long PeakRssKiB() {  // VmHWM
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  }
  return 0;
}

long RssKiB() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

// Fusion of one 300k-point frame per iteration into a map that already holds the terrain.
// model 0: every point independent, no normals (the fusion before frame_points_correlated and
// slope_aware_variance); model 1: the defaults, with normals.
void BM_DemFusion(benchmark::State& state) {
  const bool with_covariances = state.range(0) != 0;
  const bool defaults = state.range(1) != 0;
  const auto points = StereoFrame(0.0, 300000, 1);
  std::vector<Eigen::Matrix3d> covariances;
  if (with_covariances) covariances.assign(points.size(), Eigen::Matrix3d::Identity() * 1e-4);
  const std::vector<Eigen::Vector3d> normals(points.size(), Eigen::Vector3d(0.1, 0.0, 0.995));
  dem::ElevationMapOptions options;
  options.frame_points_correlated = defaults;
  dem::ElevationMap map(options);
  dem::FrameContext ctx;
  ctx.sensor_origin_world = {0.0, 0.0, 1.5};
  if (defaults) ctx.normals = &normals;
  if (with_covariances) {
    ctx.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
  }
  dem::FusionStats last;
  for (auto _ : state) {
    last = map.FuseFrame(points, covariances, ctx);
    ++ctx.frame;
    benchmark::DoNotOptimize(last.fused);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points.size()));
  state.counters["cells"] = static_cast<double>(map.CellCount());
  state.counters["fused_ratio"] =
      static_cast<double>(last.fused + last.swapped) / static_cast<double>(last.points);
}
BENCHMARK(BM_DemFusion)
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->ArgNames({"covariances", "model"})
    ->Unit(benchmark::kMillisecond);

// One frame of ~300k points into a tree that has seen the previous frames (the rover moves
// 0.3 m per frame), inner nodes on the touched paths included (dem::BatchOcTree).
void BM_OctoMapInsert(benchmark::State& state) {
  dem::OctoMapOptions options;
  options.resolution_m = static_cast<double>(state.range(0)) / 1000.0;
  dem::OctoMapFusion fusion(options);
  std::vector<std::vector<Eigen::Vector3d>> frames;
  for (int k = 0; k < 4; ++k) frames.push_back(StereoFrame(0.3 * k, 300000, 10 + k));
  int k = 0;
  for (auto _ : state) {
    const auto& frame = frames[static_cast<std::size_t>(k % 4)];
    const auto stats = fusion.InsertFrame(frame, {0.3 * (k % 4), 0.0, 1.5});
    benchmark::DoNotOptimize(stats.inserted);
    ++k;
  }
  state.SetItemsProcessed(state.iterations() * 300000);
  state.counters["leaves"] = static_cast<double>(fusion.tree()->getNumLeafNodes());
}
BENCHMARK(BM_OctoMapInsert)
    ->Arg(100)
    ->Arg(50)
    ->ArgName("resolution_mm")
    ->Unit(benchmark::kMillisecond);

// A cloud-sized frame (20k points) into an empty tree (Arg grown 0) or one grown by 600 frames
// along a 180 m road, the frame revisiting the road's start: Arg impl 0 is
// octomap's insertPointCloud (lazy, discretized) with updateInnerOccupancy every 50 frames, as
// dem::OctoMapFusion did before, 1 is dem::BatchOcTree (the fusion now). Same trees.
void BM_OctoMapInsertGrown(benchmark::State& state) {
  const int grown = static_cast<int>(state.range(0));
  const bool batch = state.range(1) == 1;
  dem::BatchOcTree tree(0.1);
  std::vector<octomap::point3d> cloud;
  int frames = 0;
  const auto insert = [&](const std::vector<Eigen::Vector3d>& points, double x0) {
    cloud.clear();
    for (const Eigen::Vector3d& p : points)
      cloud.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                         static_cast<float>(p.z()));
    const octomap::point3d origin(static_cast<float>(x0), 0.0f, 1.5f);
    if (batch) {
      tree.InsertDiscretized(cloud, origin, 20.0);
      return;
    }
    octomap::Pointcloud scan;
    for (const octomap::point3d& p : cloud) scan.push_back(p);
    tree.insertPointCloud(scan, origin, 20.0, /*lazy_eval=*/true, /*discretize=*/true);
    if (++frames % 50 == 0) tree.updateInnerOccupancy();
  };
  for (int k = 0; k < grown; ++k)
    insert(StereoFrame(0.3 * k, 20000, 100 + static_cast<unsigned>(k)), 0.3 * k);
  std::vector<std::vector<Eigen::Vector3d>> frames_in_hand;
  for (int k = 0; k < 4; ++k) frames_in_hand.push_back(StereoFrame(0.3 * k, 20000, 10 + k));
  int k = 0;
  for (auto _ : state) {
    insert(frames_in_hand[static_cast<std::size_t>(k % 4)], 0.3 * (k % 4));
    ++k;
  }
  state.counters["leaves"] = static_cast<double>(tree.getNumLeafNodes());
}
BENCHMARK(BM_OctoMapInsertGrown)
    ->ArgsProduct({{0, 600}, {0, 1}})
    ->ArgNames({"grown", "impl"})
    ->Unit(benchmark::kMillisecond);

// A tree of 12 frames of ~300k points at 0.1 m, serialised: Arg 0 OctoMap's own writers
// through an ostringstream (.ot: write, .bt: writeBinaryConst), Arg 1 dem/OcTreeBytes (the
// same bytes). The snapshot writes the .ot, every publication map.bt.
void BM_OcTreeBytes(benchmark::State& state) {
  dem::OctoMapFusion fusion;
  for (int k = 0; k < 12; ++k)
    fusion.InsertFrame(StereoFrame(0.3 * k, 300000, 10 + k), {0.3 * k, 0.0, 1.5});
  const octomap::OcTree& tree = *fusion.tree();
  const bool ours = state.range(0) == 1;
  const bool binary = state.range(1) == 1;
  std::size_t bytes = 0;
  for (auto _ : state) {
    if (ours) {
      bytes = (binary ? dem::BinaryOcTreeBytes(tree) : dem::FullOcTreeBytes(tree)).size();
    } else {
      std::ostringstream s;
      const dem::QuietStderr quiet;  // writeBinaryConst prints " done."
      if (binary)
        tree.writeBinaryConst(s);
      else
        tree.write(s);
      bytes = s.str().size();
    }
    benchmark::DoNotOptimize(bytes);
  }
  state.counters["nodes"] = static_cast<double>(tree.size());
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
}
BENCHMARK(BM_OcTreeBytes)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->ArgNames({"ours", "bt"})
    ->Unit(benchmark::kMillisecond);

// The same 12-frame tree moved onto a pose graph's poses, as serve publishes it
// (dem::BatchOcTree::MovedCopy): each frame's voxels turned 0.1° × k and shifted 3.7 cm × k.
// Arg 0: the voxels read and moved (MoveVoxels, on the OctoMap's thread); Arg 1: the tree built
// from them (Build, on the publication's writer; the copy of the voxels it takes is not timed).
void BM_OcTreeMove(benchmark::State& state) {
  dem::OctoMapFusion fusion;
  for (int k = 0; k < 12; ++k)
    fusion.InsertFrame(StereoFrame(0.3 * k, 300000, 10 + k), {0.3 * k, 0.0, 1.5},
                       static_cast<std::uint32_t>(k));
  std::vector<Eigen::Isometry3d> corrections;
  for (int k = 0; k < 12; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(0.1 * M_PI / 180.0 * k, Eigen::Vector3d::UnitZ()).matrix();
    T.translation() = Eigen::Vector3d(0.037 * k, -0.021 * k, 0.005 * k);
    corrections.push_back(T);
  }
  const dem::BatchOcTree::FrameCorrection correction =
      [&corrections](std::uint32_t frame) -> const Eigen::Isometry3d* {
    return frame < corrections.size() ? &corrections[frame] : nullptr;
  };
  const dem::BatchOcTree& tree = *fusion.tree();
  const dem::MovedVoxels moved = tree.MoveVoxels(correction);
  std::size_t leaves = 0;
  for (auto _ : state) {
    if (state.range(0) == 0) {
      leaves = tree.MoveVoxels(correction).leaves.size();
    } else {
      state.PauseTiming();
      dem::MovedVoxels copy = moved;
      state.ResumeTiming();
      leaves = dem::BatchOcTree::Build(std::move(copy))->getNumLeafNodes();
    }
    benchmark::DoNotOptimize(leaves);
  }
  state.counters["voxels"] = static_cast<double>(moved.leaves.size());
}
BENCHMARK(BM_OcTreeMove)->Arg(0)->Arg(1)->ArgName("build")->Unit(benchmark::kMillisecond);

// The publication test of every cell of a 2000×2000-cell map (dem.tif, dem.png and the counts
// each make this pass): min_support and 4 agreeing neighbours of 8.
void BM_PublishedCells(benchmark::State& state) {
  dem::ElevationMap map{dem::ElevationMapOptions{}};
  for (int i = 0; i < 2000; ++i)
    for (int j = 0; j < 2000; ++j) {
      const Eigen::Vector2d c = map.CellCenterWorld({i, j});
      map.SetCell({i, j}, Terrain(c.x(), c.y()), 1e-4, 5);
    }
  std::size_t published = 0;
  for (auto _ : state) benchmark::DoNotOptimize(published = map.PublishedCellCount());
  state.counters["cells"] = static_cast<double>(published);
}
BENCHMARK(BM_PublishedCells)->Unit(benchmark::kMillisecond);

// dem.tif of a full 2000×2000-cell map (100 m × 100 m at 5 cm): COG, DEFLATE, overviews.
void BM_GeoTiffWrite(benchmark::State& state) {
  const io::Georeference georef({47.3, 17.8, 400.0});
  dem::ElevationMapOptions options;
  options.grid_rotation_rad = georef.convergence_rad();
  dem::ElevationMap map(options);
  for (int i = 0; i < 2000; ++i)
    for (int j = 0; j < 2000; ++j) {
      const Eigen::Vector2d c = map.CellCenterWorld({i, j});
      map.SetCell({i, j}, Terrain(c.x(), c.y()), 1e-4, 5);
    }
  const auto dir = std::filesystem::temp_directory_path() / "rovermap_bench_maps";
  std::filesystem::create_directories(dir);
  io::GeoTiffOptions tiff;
  tiff.deflate_level = static_cast<int>(state.range(0));
  tiff.threads = static_cast<int>(state.range(1));
  io::GeoTiffInfo info;
  for (auto _ : state) info = io::WriteDemGeoTiff(dir / "dem.tif", map, georef, tiff);
  state.counters["pixels"] = static_cast<double>(info.width) * info.height;
  state.counters["file_MB"] =
      static_cast<double>(std::filesystem::file_size(dir / "dem.tif")) / 1e6;
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_GeoTiffWrite)
    ->Args({1, 0})  // the defaults
    ->Args({1, 1})
    ->Args({6, 1})
    ->ArgNames({"deflate_level", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3)
    ->UseRealTime();

// A 1 km traverse, a 300k-point frame every 0.5 m (2000 frames): map memory, process RSS, and
// per-frame fusion time at the start and the end (flat = no growth with map size).
void BM_LongTraverse(benchmark::State& state) {
  for (auto _ : state) {
    const long rss_before = RssKiB();
    dem::ElevationMap map;
    dem::FrameContext ctx;
    const auto frame = StereoFrame(0.0, 300000, 3);
    std::vector<Eigen::Vector3d> moved(frame.size());
    std::vector<Eigen::Matrix3d> none;
    const int frames = static_cast<int>(state.range(0));
    double first_ms = 0.0, last_ms = 0.0;
    for (int k = 0; k < frames; ++k) {
      const double dx = 0.5 * k;
      for (std::size_t i = 0; i < frame.size(); ++i) {
        moved[i] = {frame[i].x() + dx, frame[i].y(), Terrain(frame[i].x() + dx, frame[i].y())};
      }
      ctx.frame = static_cast<std::uint32_t>(k);
      const auto t0 = std::chrono::steady_clock::now();
      map.FuseFrame(moved, none, ctx);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (k < frames / 10) first_ms += ms / (frames / 10);
      if (k >= frames - frames / 10) last_ms += ms / (frames / 10);
    }
    state.counters["length_m"] = 0.5 * frames;
    state.counters["tiles"] = static_cast<double>(map.TileCount());
    state.counters["map_MB"] = static_cast<double>(map.MemoryBytes()) / 1e6;
    state.counters["rss_growth_MB"] = static_cast<double>(RssKiB() - rss_before) / 1024.0;
    state.counters["points_M"] = frames * 0.3;
    state.counters["first10pct_ms_per_frame"] = first_ms;
    state.counters["last10pct_ms_per_frame"] = last_ms;
  }
}
BENCHMARK(BM_LongTraverse)->Arg(2000)->ArgName("frames")->Unit(benchmark::kSecond)->Iterations(1);

// A DEM of `side` × `side` 5 cm cells on the synthetic terrain, 2 cm σ, 5 % of cells empty.
struct TerrainGrid {
  int side = 0;
  std::vector<float> z, sigma;
  explicit TerrainGrid(int n) : side(n) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        z.push_back(u(rng) < 0.05 ? NAN : static_cast<float>(Terrain(0.05 * c, -0.05 * r)));
        sigma.push_back(0.02f);
      }
    }
  }
  terrain::GridView View() const { return {side, side, 0.05, 0.05, z.data(), sigma.data()}; }
};

// The layers with the defaults (0.6 m footprint: 13 × 13 cells) and a 1.05 m one (21 × 21), on
// a 2000 × 2000 DEM (4 megacells, a 100 m square of 5 cm cells), all cores.
void BM_TerrainLayers(benchmark::State& state) {
  const TerrainGrid grid(2000);
  terrain::TerrainOptions options;
  options.footprint_m = 0.05 * static_cast<double>(state.range(0));
  for (auto _ : state)
    benchmark::DoNotOptimize(terrain::ComputeTerrain(grid.View(), options).known);
  state.counters["megacells_per_s"] =
      benchmark::Counter(4.0, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_TerrainLayers)
    ->Arg(13)
    ->Arg(21)
    ->ArgName("footprint_cells")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// serve's publication of the same DEM through a TerrainCache: between two publications a patch
// of `range(0)` × `range(0)` cells changed (200: the 10 m square a stereo frame reaches, on 5 cm
// cells), somewhere new each time; only the tiles whose footprints it touches are computed.
void BM_TerrainPublication(benchmark::State& state) {
  TerrainGrid grid(2000);
  const int patch = static_cast<int>(state.range(0));
  terrain::TerrainOptions options;
  terrain::TerrainCache cache;
  cache.Update(grid.View(), options);
  std::size_t computed = 0, publications = 0;
  int at = 0;
  for (auto _ : state) {
    state.PauseTiming();
    at = (at + 613) % (grid.side - patch);  // a new place each time
    for (int r = at; r < at + patch; ++r)
      for (int c = at; c < at + patch; ++c)
        grid.z[static_cast<std::size_t>(r) * grid.side + c] += 0.001f;
    state.ResumeTiming();
    benchmark::DoNotOptimize(cache.Update(grid.View(), options).known);
    computed += cache.tiles_computed();
    ++publications;
  }
  state.counters["tiles"] = static_cast<double>(cache.tiles());
  state.counters["tiles_computed"] =
      static_cast<double>(computed) / static_cast<double>(std::max<std::size_t>(1, publications));
}
BENCHMARK(BM_TerrainPublication)
    ->Arg(200)
    ->ArgName("patch_cells")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The terrain layers of the largest mosaic the issue names (7500 × 5000 cells of 5 cm, 375 m ×
// 250 m, heights and σ), a row of tiles at a time from the file (rovermap terrain, the mosaic's
// NAME_terrain.tif): time, and the process's peak memory against what the layers would take in
// memory at once (6 bands + the DEM's 2, 1.2 GB).
void BM_TerrainLargestMosaic(benchmark::State& state) {
  constexpr int kWidth = 7500, kHeight = 5000;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "rovermap_bench_mosaic";
  std::filesystem::create_directories(dir);
  const std::filesystem::path dem = dir / "mosaic.tif";
  {
    io::RegisterGdal();
    io::BoundGdalCache();
    OGRSpatialReference srs;
    srs.importFromEPSG(32633);
    io::GdalDatasetPtr ds =
        io::CreateStaging(dem, dem, kWidth, kHeight, {500000.0, 0.05, 0.0, 4000000.0, 0.0, -0.05},
                          srs, {{"elevation", "m"}, {"elevation_stddev", "m"}});
    std::vector<float> z(kWidth * 256), sigma(kWidth * 256, 0.02f);
    for (int row0 = 0; row0 < kHeight; row0 += 256) {
      const int rows = std::min(256, kHeight - row0);
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < kWidth; ++c)
          z[static_cast<std::size_t>(r) * kWidth + c] =
              static_cast<float>(Terrain(0.05 * c, -0.05 * (row0 + r)));
      io::WriteWindow(ds.get(), dem, 1, 0, row0, kWidth, rows, z.data());
      io::WriteWindow(ds.get(), dem, 2, 0, row0, kWidth, rows, sigma.data());
    }
    io::CloseStaging(std::move(ds), dem);
  }
  const long before_kib = PeakRssKiB();
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        io::WriteTerrainTiled(dem, dir / "terrain.tif", dir / "terrain.png", {}).counts.known);
  }
  state.counters["megacells"] = kWidth * kHeight / 1e6;
  state.counters["peak_rss_mib"] = static_cast<double>(PeakRssKiB()) / 1024.0;
  state.counters["peak_rss_before_mib"] = static_cast<double>(before_kib) / 1024.0;
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_TerrainLargestMosaic)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same plane fit and step written the obvious way (grid_map's filters loop so): every
// cell gathers its footprint and solves its 3 × 3 normal equations; one core, 500 × 500 cells.
void BM_TerrainPlainLoops(benchmark::State& state) {
  const TerrainGrid grid(500);
  const int h = static_cast<int>(state.range(0)) / 2, n = grid.side;
  std::vector<float> slope(grid.z.size()), step(grid.z.size());
  for (auto _ : state) {
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        float lo = INFINITY, hi = -INFINITY;
        for (int i = std::max(0, r - h); i <= std::min(n - 1, r + h); ++i) {
          for (int j = std::max(0, c - h); j <= std::min(n - 1, c + h); ++j) {
            const float zz = grid.z[static_cast<std::size_t>(i) * n + j];
            if (std::isnan(zz)) continue;
            const double s = grid.sigma[static_cast<std::size_t>(i) * n + j];
            const Eigen::Vector3d a(1.0, 0.05 * (j - c), 0.05 * (i - r));
            normal += a * a.transpose() / (s * s);
            rhs += a * zz / (s * s);
            lo = std::min(lo, zz);
            hi = std::max(hi, zz);
          }
        }
        const Eigen::Vector3d beta = normal.ldlt().solve(rhs);
        slope[static_cast<std::size_t>(r) * n + c] = static_cast<float>(beta.tail<2>().norm());
        step[static_cast<std::size_t>(r) * n + c] = hi - lo;
      }
    }
    benchmark::DoNotOptimize(slope.data());
    benchmark::DoNotOptimize(step.data());
  }
  state.counters["megacells_per_s"] =
      benchmark::Counter(0.25, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_TerrainPlainLoops)
    ->Arg(13)
    ->Arg(21)
    ->ArgName("footprint_cells")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
