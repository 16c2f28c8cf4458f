// bench_kdtree: rovermap's k-d tree (registration/KdTree) against nanoflann 1.4 (the tree it
// replaced) on the matcher's workloads: build, bounded closest point near convergence, and
// 10 nearest neighbours (normals). Checks that both return identical distances for every
// query and prints one markdown table of median times.
//
//   bench_kdtree [--runs N] [--data DIR]
//
// See bench/README.md, section "bench_kdtree".

#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "io/PointCloudIo.hpp"
#include "registration/CloudGeometry.hpp"
#include "registration/KdTree.hpp"
#include "tests/support/SyntheticScenes.hpp"

#ifndef ROVERMAP_DATASETS_DIR
#define ROVERMAP_DATASETS_DIR "datasets"
#endif

namespace {

using rovermap::bench::LoadAverage;
using rovermap::bench::Median;

using Clock = std::chrono::steady_clock;
using Points = std::vector<Eigen::Vector3d>;
using rovermap::registration::KdTree;
using rovermap::registration::Neighbor;

constexpr int kLeafSize = 10;           // both trees: our default, nanoflann's default
constexpr std::size_t kNeighbors = 10;  // normal estimation's k
constexpr double kBoundFactor = 4.0;    // bound = 4 x median spacing
constexpr std::size_t kNoHint = std::numeric_limits<std::size_t>::max();

// nanoflann dataset adaptor over the same std::vector our tree indexes (no copy).
struct PointsAdaptor {
  const Points& points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const {
    return points[i][static_cast<int>(dim)];
  }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;  // let nanoflann compute it, as the old matcher did
  }
};

using NanoTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointsAdaptor>,
                                        PointsAdaptor, 3, std::size_t>;

// 1-NN result set whose initial worst distance is the bound squared: nanoflann prunes every
// branch farther than worstDist(), so the bound prunes from the root (as the old matcher did).
class BoundedNearestResultSet {
 public:
  explicit BoundedNearestResultSet(double bound_sq) : best_sq_(bound_sq) {}
  bool addPoint(double dist_sq, std::size_t index) {
    if (dist_sq < best_sq_) {
      best_sq_ = dist_sq;
      index_ = index;
      found_ = true;
    }
    return true;  // keep searching
  }
  double worstDist() const { return best_sq_; }
  bool full() const { return found_; }
  std::size_t size() const { return found_ ? 1 : 0; }

  bool found() const { return found_; }
  double best_sq() const { return best_sq_; }
  std::size_t index() const { return index_; }

 private:
  bool found_ = false;
  double best_sq_;
  std::size_t index_ = 0;
};

struct Args {
  int runs = 7;
  std::string data_dir = ROVERMAP_DATASETS_DIR;
};

void Usage(std::ostream& os) {
  os << "usage: bench_kdtree [--runs N] [--data DIR]\n"
        "  --runs N    timed runs (default 7); the table shows the median\n"
        "  --data DIR  datasets directory (default: " ROVERMAP_DATASETS_DIR ")\n"
        "  OMP_NUM_THREADS sets the default thread count of the threaded build row.\n";
}

Args ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&] { return rovermap::bench::OptionValue(argc, argv, &i); };
    if (arg == "--runs") {
      a.runs = rovermap::bench::ParseRuns(value());
    } else if (arg == "--data") {
      a.data_dir = value();
    } else if (arg == "-h" || arg == "--help") {
      Usage(std::cout);
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown argument '" + arg + "'");
    }
  }
  return a;
}


double TimeMs(const std::function<void()>& work) {
  const auto t0 = Clock::now();
  work();
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// A stereo frame's worth (640 x 480) of points scattered uniformly over the test terrain
// (8 m x 6 m, 5 mm noise): denser than the grid-sampled terrain pair. In generation order
// the points are shuffled in memory; `raster` sorts them into 1 cm rows along y, x within a
// row, like a stereo frame's image order (memory order alone changes both trees' speed).
Points MakeRandomSurface(std::size_t n, unsigned seed, bool raster) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0.0, 8.0), uy(0.0, 6.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  Points points;
  points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = ux(rng), y = uy(rng);
    points.emplace_back(x + noise(rng), y + noise(rng),
                        rovermap::testing::TerrainHeight(x, y) + noise(rng));
  }
  if (raster) {
    auto row = [](const Eigen::Vector3d& p) { return static_cast<long>(std::floor(p.y() / 0.01)); };
    std::sort(points.begin(), points.end(),
              [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
                return row(a) != row(b) ? row(a) < row(b) : a.x() < b.x();
              });
  }
  return points;
}


// The state near convergence: every point turned 0.2 deg about the centroid and shifted by
// half a spacing, so most queries have a match within the bound at about half a spacing.
Points MoveSlightly(const Points& points, double spacing) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.2 * M_PI / 180.0, Eigen::Vector3d(1, 2, 3).normalized())
          .toRotationMatrix();
  const Eigen::Vector3d shift = 0.5 * spacing * Eigen::Vector3d(2, -1, 1).normalized();
  Points queries;
  queries.reserve(points.size());
  for (const auto& p : points) queries.push_back(rotation * (p - centroid) + centroid + shift);
  return queries;
}

// Aborts on the first query whose distances differ: a speed-up only counts if the answers
// are the same. Not found is stored as -1.
void CheckSame(const std::string& what, const std::vector<double>& nano,
               const std::vector<double>& ours, std::size_t per_query) {
  for (std::size_t i = 0; i < nano.size(); ++i) {
    if (nano[i] != ours[i]) {
      std::fprintf(stderr,
                   "bench_kdtree: %s: query %zu (entry %zu) differs: nanoflann %.17g, ours %.17g "
                   "(squared distance; -1 = none within the bound)\n",
                   what.c_str(), i / per_query, i % per_query, nano[i], ours[i]);
      std::exit(1);
    }
  }
}

struct Row {
  std::string operation;
  int threads = 1;
  std::vector<double> nano_ms, ours_ms;
};

struct Cloud {
  std::string name;
  Points points;
};

// Runs every operation on one cloud: one untimed warm-up round, then `runs` rounds; within a
// round each operation times nanoflann and ours back to back, alternating which goes first.
std::vector<Row> BenchCloud(const Cloud& cloud, int runs, int default_threads) {
  const Points& points = cloud.points;
  const std::size_t n = points.size();
  const PointsAdaptor adaptor{points};
  const nanoflann::KDTreeSingleIndexAdaptorParams nano_params(kLeafSize);
  const nanoflann::SearchParams search_params;  // exact search (eps = 0)

  // Query trees, built once (the build rows time their own trees).
  omp_set_num_threads(default_threads);
  const NanoTree nano_tree(3, adaptor, nano_params);  // nanoflann 1.4 builds in the constructor
  const KdTree our_tree(points, kLeafSize);

  const double spacing = rovermap::registration::MedianNeighborSpacing(points, our_tree);
  const double bound_sq = (kBoundFactor * spacing) * (kBoundFactor * spacing);
  const Points queries = MoveSlightly(points, spacing);

  std::vector<double> nano_d(n), ours_d(n);    // closest: squared distance
  std::vector<std::size_t> hints(n, kNoHint);  // previous answers
  std::vector<double> nano_knn(n * kNeighbors), ours_knn(n * kNeighbors);

  auto nano_closest = [&](bool use_hints) {
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d& q = queries[i];
      BoundedNearestResultSet set(bound_sq);
      // Warm start exactly as our tree does (and the old nanoflann-based matcher did).
      if (use_hints && hints[i] != kNoHint)
        set.addPoint((points[hints[i]] - q).squaredNorm(), hints[i]);
      nano_tree.findNeighbors(set, q.data(), search_params);
      nano_d[i] = set.found() ? set.best_sq() : -1.0;
    }
  };
  auto our_closest = [&](bool use_hints) {
    const double bound = kBoundFactor * spacing;
    for (std::size_t i = 0; i < n; ++i) {
      const Neighbor nb = use_hints ? our_tree.FindClosest(queries[i], bound, hints[i])
                                    : our_tree.FindClosest(queries[i], bound);
      ours_d[i] = nb.found ? nb.squared_distance : -1.0;
    }
  };
  auto nano_knn_all = [&] {
    std::size_t idx[kNeighbors];
    for (std::size_t i = 0; i < n; ++i) {
      nanoflann::KNNResultSet<double, std::size_t, std::size_t> set(kNeighbors);
      set.init(idx, &nano_knn[i * kNeighbors]);
      nano_tree.findNeighbors(set, points[i].data(), search_params);
    }
  };
  auto our_knn_all = [&] {
    std::size_t idx[kNeighbors];
    for (std::size_t i = 0; i < n; ++i)
      our_tree.FindKNearest(points[i], kNeighbors, idx, &ours_knn[i * kNeighbors]);
  };

  // The previous answers for the warm-started rows: the unhinted result (matches no longer
  // change near convergence).
  std::size_t matched = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Neighbor nb = our_tree.FindClosest(queries[i], kBoundFactor * spacing);
    if (nb.found) {
      hints[i] = nb.index;
      ++matched;
    }
  }

  std::printf(
      "cloud %s: %zu points, median spacing D = %.3f mm, bound = %.0f D = %.3f mm, "
      "queries moved 0.2 deg + 0.5 D: %.1f %% matched within the bound\n",
      cloud.name.c_str(), n, spacing * 1e3, kBoundFactor, kBoundFactor * spacing * 1e3,
      100.0 * static_cast<double>(matched) / static_cast<double>(n));
  std::fflush(stdout);

  std::vector<Row> rows = {{"build", 1, {}, {}},
                           {"build", default_threads, {}, {}},
                           {"closest within 4 D", 1, {}, {}},
                           {"closest within 4 D, hint", 1, {}, {}},
                           {"10 nearest", 1, {}, {}}};

  for (int run = -1; run < runs; ++run) {  // run -1: warm-up, untimed
    const bool nano_first = run % 2 == 0;
    auto time_pair = [&](Row& row, const std::function<void()>& nano,
                         const std::function<void()>& ours) {
      double t_nano, t_ours;
      if (nano_first) {
        t_nano = TimeMs(nano);
        t_ours = TimeMs(ours);
      } else {
        t_ours = TimeMs(ours);
        t_nano = TimeMs(nano);
      }
      if (run >= 0) {
        row.nano_ms.push_back(t_nano);
        row.ours_ms.push_back(t_ours);
      }
    };

    // Builds: the tree's destruction stays outside the timer.
    for (int b = 0; b < 2; ++b) {
      Row& row = rows[static_cast<std::size_t>(b)];
      omp_set_num_threads(row.threads);
      std::unique_ptr<NanoTree> nano;
      std::unique_ptr<KdTree> ours;
      time_pair(
          row, [&] { nano = std::make_unique<NanoTree>(3, adaptor, nano_params); },
          [&] { ours = std::make_unique<KdTree>(points, kLeafSize); });
      if (nano->size(*nano) != n || ours->size() != n) {
        std::fprintf(stderr, "bench_kdtree: %s: a tree lost points\n", cloud.name.c_str());
        std::exit(1);
      }
    }
    omp_set_num_threads(default_threads);

    time_pair(
        rows[2], [&] { nano_closest(false); }, [&] { our_closest(false); });
    CheckSame(cloud.name + " closest", nano_d, ours_d, 1);
    time_pair(
        rows[3], [&] { nano_closest(true); }, [&] { our_closest(true); });
    CheckSame(cloud.name + " closest with hint", nano_d, ours_d, 1);
    time_pair(rows[4], nano_knn_all, our_knn_all);
    CheckSame(cloud.name + " 10 nearest", nano_knn, ours_knn, kNeighbors);
  }
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = ParseArgs(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "bench_kdtree: " << e.what() << "\n";
    Usage(std::cerr);
    return 2;
  }
  const int default_threads = omp_get_max_threads();

  std::vector<Cloud> clouds;
  try {
    clouds.push_back(
        {"bunny bun000",
         rovermap::io::ReadPointCloud(args.data_dir + "/stanford_bunny/bun000.ply").points});
  } catch (const std::exception& e) {
    std::cerr << "bench_kdtree: cannot read the bunny (" << e.what() << "); use --data DIR\n";
    return 1;
  }
  clouds.push_back({"terrain", rovermap::testing::MakeTerrainPair(rovermap::testing::SceneOptions{},
                                                                  rovermap::testing::RoverMotion())
                                   .target.points});
  clouds.push_back({"random surface, shuffled", MakeRandomSurface(640 * 480, 1, false)});
  clouds.push_back({"random surface, rows", MakeRandomSurface(640 * 480, 1, true)});

  std::printf(
      "bench_kdtree: rovermap KdTree vs nanoflann (NANOFLANN_VERSION 0x%x), leaf size %d, "
      "median of %d runs (+1 warm-up), implementations interleaved\n",
      NANOFLANN_VERSION, kLeafSize, args.runs);
  std::printf(
      "threads: build rows with 1 and with %d (OpenMP default; nanoflann builds "
      "serially); query rows single-threaded\n",
      default_threads);
  std::printf("load average at start: %s\n", LoadAverage().c_str());
  std::fflush(stdout);

  std::vector<std::pair<const Cloud*, std::vector<Row>>> results;
  for (const Cloud& cloud : clouds)
    results.emplace_back(&cloud, BenchCloud(cloud, args.runs, default_threads));

  std::printf(
      "\n| cloud | points | operation | threads | nanoflann ms | ours ms | nanoflann / ours "
      "| ratio of minima |\n");
  std::printf("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: |\n");
  for (const auto& [cloud, rows] : results) {
    for (const Row& row : rows) {
      const double nano = Median(row.nano_ms), ours = Median(row.ours_ms);
      const double nano_min = *std::min_element(row.nano_ms.begin(), row.nano_ms.end());
      const double ours_min = *std::min_element(row.ours_ms.begin(), row.ours_ms.end());
      std::printf("| %s | %zu | %s | %d | %.2f | %.2f | %.2f | %.2f |\n", cloud->name.c_str(),
                  cloud->points.size(), row.operation.c_str(), row.threads, nano, ours, nano / ours,
                  nano_min / ours_min);
    }
  }
  std::printf("\nall distances identical (nanoflann vs ours) for every query of every run\n");
  std::printf("load average at end: %s\n", LoadAverage().c_str());
  return 0;
}
