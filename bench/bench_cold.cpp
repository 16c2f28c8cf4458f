// bench_cold: one registration per process, as a user runs it, against Open3D's point-to-plane ICP
// run the same way (the aim: a cold process as fast as a warm one). Each run starts a fresh process
// and is timed from fork to exit: loading the program and its libraries, reading the two PLY files,
// the registration and printing the result.
//
//   bench_cold [--runs N] [--data DIR] [--rovermap PATH] [--open3d PATH] [--pause-ms MS]
//
// rovermap: `rovermap register SOURCE TARGET --init "rx ry rz tx ty tz"` (defaults). Open3D:
// `open3d_register` (built with -DROVERMAP_BENCH_PEERS=ON, linked against Open3D alone): Open3D's
// PLY reader, target normals from 10 neighbours, RegistrationICP point-to-plane with the gate
// 20 × D that rovermap starts from (D from rovermap's own output). Both from the truth turned by
// 10° and moved by 5 mm, as bench_register. One untimed run of each first (the files in the page
// cache), then N rounds with the methods in turn, each run after an idle pause.
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "tests/support/StanfordPairs.hpp"
#include "tests/support/SyntheticScenes.hpp"

#ifndef ROVERMAP_DATASETS_DIR
#define ROVERMAP_DATASETS_DIR "datasets"
#endif
#ifndef ROVERMAP_CLI
#define ROVERMAP_CLI "rovermap"
#endif
#ifndef ROVERMAP_OPEN3D_REGISTER
#define ROVERMAP_OPEN3D_REGISTER ""
#endif

namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  int runs = 20;
  std::string data_dir = ROVERMAP_DATASETS_DIR;
  std::string rovermap = ROVERMAP_CLI;
  std::string open3d = ROVERMAP_OPEN3D_REGISTER;
  int pause_ms = 100;
};

void Usage(std::ostream& os) {
  os << "usage: bench_cold [--runs N] [--data DIR] [--rovermap PATH] [--open3d PATH] "
        "[--pause-ms MS]\n"
        "  --runs N       timed runs per method (default 20)\n"
        "  --data DIR     datasets directory (default " ROVERMAP_DATASETS_DIR
        ")\n"
        "  --rovermap P   the rovermap command (default: this build's)\n"
        "  --open3d P     open3d_register (default: this build's, if built with the peers; an\n"
        "                 empty path leaves Open3D out)\n"
        "  --pause-ms MS  idle time before each run (default 100)\n";
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
    } else if (arg == "--rovermap") {
      a.rovermap = value();
    } else if (arg == "--open3d") {
      a.open3d = value();
    } else if (arg == "--pause-ms") {
      a.pause_ms = std::stoi(value());
      if (a.pause_ms < 0) throw std::invalid_argument("--pause-ms must not be negative");
    } else if (arg == "-h" || arg == "--help") {
      Usage(std::cout);
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown argument '" + arg + "'");
    }
  }
  return a;
}

struct Process {
  double wall_ms = 0.0;
  std::string out;  // its standard output
};

// Runs `argv` to its end; its standard output is captured, its standard error discarded.
Process Run(const std::vector<std::string>& argv) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("bench_cold: pipe failed");
  const auto start = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("bench_cold: fork failed");
  if (pid == 0) {
    ::dup2(fds[1], STDOUT_FILENO);
    ::close(fds[0]);
    ::close(fds[1]);
    if (std::FILE* null = std::freopen("/dev/null", "w", stderr); null == nullptr) ::_exit(126);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  Process p;
  char buffer[65536];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;)
    p.out.append(buffer, static_cast<std::size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  p.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("bench_cold: '" + argv[0] + "' failed (status " +
                             std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  return p;
}

std::string InitText(const Eigen::Isometry3d& T) {
  const Eigen::AngleAxisd aa(T.linear());
  const Eigen::Vector3d r = aa.angle() * aa.axis();
  char text[256];
  std::snprintf(text, sizeof text, "%.17g %.17g %.17g %.17g %.17g %.17g", r.x(), r.y(), r.z(),
                T.translation().x(), T.translation().y(), T.translation().z());
  return text;
}

struct RovermapOutput {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  double reference_distance_m = 0.0;
};

RovermapOutput ParseRovermap(const std::string& out) {
  const nlohmann::json j = nlohmann::json::parse(out);
  RovermapOutput r;
  Eigen::Matrix4d m;
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) m(row, col) = j.at("matrix").at(row).at(col).get<double>();
  r.T.matrix() = m;
  r.reference_distance_m = j.at("reference_distance").get<double>();
  return r;
}

Eigen::Isometry3d ParseOpen3d(const std::string& out) {
  std::istringstream in(out);
  Eigen::Matrix4d m;
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col)
      if (!(in >> m(row, col))) throw std::runtime_error("bench_cold: bad open3d_register output");
  Eigen::Isometry3d T;
  T.matrix() = m;
  return T;
}

struct Row {
  std::string pair, method;
  std::vector<double> times;
  double rot_deg = 0.0, trans_mm = 0.0;
};

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = ParseArgs(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "bench_cold: " << e.what() << "\n";
    Usage(std::cerr);
    return 2;
  }
  const bool with_open3d = !args.open3d.empty();
  std::cout << "bench_cold: " << args.runs << " runs per method (+1 untimed), one process each, "
            << args.pause_ms << " ms idle before each; load average "
            << rovermap::bench::LoadAverage() << "\n\n";
  std::vector<Row> rows;
  try {
    for (const char* source_name : {"bun045", "bun315"}) {
      const std::string dir = args.data_dir + "/stanford_bunny/";
      const std::string source = dir + source_name + ".ply", target = dir + "bun000.ply";
      const Eigen::Isometry3d T_true = rovermap::testing::ReadGroundTruth(
          dir + "gt_pairs.txt", std::string(source_name) + ".ply", "bun000.ply");
      const Eigen::Isometry3d T_init = rovermap::testing::Perturb(T_true, 10.0, 0.005);
      const std::vector<std::string> rovermap_cmd = {args.rovermap, "register", source,
                                                     target,        "--init",   InitText(T_init)};
      const RovermapOutput warm = ParseRovermap(Run(rovermap_cmd).out);
      const double gate = 20.0 * warm.reference_distance_m;
      std::vector<std::vector<std::string>> commands = {rovermap_cmd};
      if (with_open3d) {
        commands.push_back({args.open3d, source, target, "--init", InitText(T_init), "--gate",
                            std::to_string(gate)});
        Run(commands.back());  // untimed
      }
      const std::string pair = std::string(source_name) + "->bun000";
      std::vector<Row> pair_rows(commands.size());
      pair_rows[0].method = "rovermap register (defaults)";
      if (with_open3d) pair_rows[1].method = "Open3D 0.16 ICP point-to-plane";
      std::vector<std::vector<Eigen::Isometry3d>> estimates(commands.size());
      for (int r = 0; r < args.runs; ++r) {
        for (std::size_t k = 0; k < commands.size(); ++k) {
          std::this_thread::sleep_for(std::chrono::milliseconds(args.pause_ms));
          const Process p = Run(commands[k]);
          pair_rows[k].times.push_back(p.wall_ms);
          estimates[k].push_back(k == 0 ? ParseRovermap(p.out).T : ParseOpen3d(p.out));
        }
      }
      for (std::size_t k = 0; k < commands.size(); ++k) {
        std::vector<double> rot, trans;
        for (const Eigen::Isometry3d& T : estimates[k]) {
          const auto [r, t] = rovermap::testing::PoseError(T_true, T);
          rot.push_back(r);
          trans.push_back(t * 1e3);
        }
        pair_rows[k].pair = pair;
        pair_rows[k].rot_deg = rovermap::bench::Median(rot);
        pair_rows[k].trans_mm = rovermap::bench::Median(trans);
        rows.push_back(pair_rows[k]);
      }
      std::fprintf(stderr, "bench_cold: %s done\n", pair.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  std::printf(
      "| pair | method | median ms | min-max ms | max / median | rot err deg | trans err mm | "
      "t / t(rovermap) |\n|---|---|---:|---:|---:|---:|---:|---:|\n");
  double rovermap_median = 0.0;
  for (const Row& r : rows) {
    const double median = rovermap::bench::Median(r.times);
    if (r.method.rfind("rovermap", 0) == 0) rovermap_median = median;
    const auto [lo, hi] = std::minmax_element(r.times.begin(), r.times.end());
    std::printf("| %s | %s | %.1f | %.1f-%.1f | %.2f | %.4f | %.3f | %.2f |\n", r.pair.c_str(),
                r.method.c_str(), median, *lo, *hi, *hi / median, r.rot_deg, r.trans_mm,
                median / rovermap_median);
  }
  std::printf("\nload average at the end: %s\n", rovermap::bench::LoadAverage().c_str());
  return 0;
}
