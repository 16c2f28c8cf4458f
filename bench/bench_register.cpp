// bench_register: rovermap's matcher against PCL and Open3D ICP on the same pairs, from the
// same initial estimate, with the same correspondence gate. Prints one table.
//
//   bench_register [--runs N] [--pairs bunny|terrain|all] [--data DIR] [--threads N]
//
// Timing is wall clock from clouds in memory (each library's own cloud type, converted
// beforehand) to the result: k-d trees, normals, the iterations. See bench/README.md.

#include <fcntl.h>
#include <omp.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "config/Config.hpp"
#include "io/PointCloudIo.hpp"
#include "registration/Icp.hpp"
#include "registration/Options.hpp"
#include "tests/support/StanfordPairs.hpp"
#include "tests/support/SyntheticScenes.hpp"

#ifdef ROVERMAP_BENCH_PEERS
#include "bench/Peers.hpp"
#endif

#ifndef ROVERMAP_DATASETS_DIR
#define ROVERMAP_DATASETS_DIR "datasets"
#endif

namespace {

using rovermap::bench::LoadAverage;
using rovermap::bench::Median;

namespace reg = rovermap::registration;
using Clock = std::chrono::steady_clock;

struct Args {
  int runs = 7;
  std::string pairs = "all";
  std::string data_dir = ROVERMAP_DATASETS_DIR;
  int threads = 0;           // 0 = OpenMP default
  int max_iterations = 100;  // every method
  double gate_factor = 0.0;  // peers' gate = gate_factor * D; 0 = rovermap's initial factor (20)
  int pause_ms = 100;        // idle time before each run [ms] (see Worker::Run)
  // Internal: a worker process runs one method of one pair (see StartWorker).
  int worker_pair = -1, worker_method = -1;
  double worker_gate = 0.0;  // [m]
};

void Usage(std::ostream& os) {
  os << "usage: bench_register [--runs N] [--pairs bunny|terrain|all] [--data DIR] "
        "[--threads N] [--gate-factor F]\n"
        "                     [--max-iterations N] [--pause-ms MS]\n"
        "  --runs N      timed runs per method (default 7); the table shows the median\n"
        "  --pairs P     which pairs: bunny (2 Stanford bunny scans), terrain (synthetic), all\n"
        "  --data DIR    datasets directory (default " ROVERMAP_DATASETS_DIR
        ")\n"
        "  --threads N   OpenMP threads for rovermap and Open3D (default: OpenMP's default)\n"
        "  --gate-factor F  peers' max correspondence distance = F x rovermap's D (default: 20,\n"
        "                rovermap's initial Dmax factor)\n"
        "  --max-iterations N  iteration limit of every method (default 100)\n"
        "  --pause-ms MS idle time before each run, so that the previous method's OpenMP\n"
        "                threads have stopped spinning (default 100)\n";
}

Args ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&] { return rovermap::bench::OptionValue(argc, argv, &i); };
    if (arg == "--runs") {
      a.runs = rovermap::bench::ParseRuns(value());
    } else if (arg == "--pairs") {
      a.pairs = value();
      if (a.pairs != "bunny" && a.pairs != "terrain" && a.pairs != "all")
        throw std::invalid_argument("--pairs must be bunny, terrain or all, not '" + a.pairs + "'");
    } else if (arg == "--data") {
      a.data_dir = value();
    } else if (arg == "--threads") {
      a.threads = std::stoi(value());
      if (a.threads < 1) throw std::invalid_argument("--threads must be at least 1");
    } else if (arg == "--pause-ms") {
      a.pause_ms = std::stoi(value());
      if (a.pause_ms < 0) throw std::invalid_argument("--pause-ms must not be negative");
    } else if (arg == "--max-iterations") {
      a.max_iterations = std::stoi(value());
      if (a.max_iterations < 1) throw std::invalid_argument("--max-iterations must be at least 1");
    } else if (arg == "--gate-factor") {
      a.gate_factor = std::stod(value());
      if (!(a.gate_factor > 0.0)) throw std::invalid_argument("--gate-factor must be positive");
    } else if (arg == "--worker-pair") {
      a.worker_pair = std::stoi(value());
    } else if (arg == "--worker-method") {
      a.worker_method = std::stoi(value());
    } else if (arg == "--worker-gate") {
      a.worker_gate = std::stod(value());
    } else if (arg == "-h" || arg == "--help") {
      Usage(std::cout);
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown argument '" + arg + "'");
    }
  }
  return a;
}

struct BenchPair {
  std::string name;
  reg::PointCloud source, target;
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_init = Eigen::Isometry3d::Identity();
  std::string perturbation;
};

BenchPair BunnyPair(const std::string& data_dir, const std::string& source,
                    const std::string& target) {
  const std::string dir = data_dir + "/stanford_bunny/";
  BenchPair p;
  p.name = source.substr(0, source.find('.')) + "->" + target.substr(0, target.find('.'));
  p.source = rovermap::io::ReadPointCloud(dir + source);
  p.target = rovermap::io::ReadPointCloud(dir + target);
  p.T_true = rovermap::testing::ReadGroundTruth(dir + "gt_pairs.txt", source, target);
  p.T_init = rovermap::testing::Perturb(p.T_true, 10.0, 0.005);
  p.perturbation = "truth perturbed by 10 deg and 5 mm";
  return p;
}

BenchPair TerrainPair() {
  const rovermap::testing::ScenePair scene = rovermap::testing::MakeTerrainPair(
      rovermap::testing::SceneOptions{}, rovermap::testing::RoverMotion());
  BenchPair p;
  p.name = "terrain";
  p.source = scene.source;
  p.target = scene.target;
  p.T_true = scene.T_target_source;
  p.T_init = rovermap::testing::Perturb(p.T_true, 2.0, 0.1);
  p.perturbation = "rover motion perturbed by 2 deg and 0.1 m";
  return p;
}

// One registration: estimate, time, iterations and a short status.
struct RunResult {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  double time_ms = 0.0;
  int iterations = -1;
  std::string status;
  double reference_distance_m = 0.0;  // rovermap only
};

struct Method {
  std::string name;
  std::function<RunResult()> run;
  std::function<int()> count_iterations;  // for peers that do not report iterations
};

RunResult RunRovermap(const BenchPair& pair, const reg::RegistrationOptions& options) {
  // Copies outside the timer (the peers also get their clouds ready-made), moved in.
  reg::PointCloud source = pair.source, target = pair.target;
  const auto t0 = Clock::now();
  const reg::IndexedCloud s(std::move(source), options);
  const reg::IndexedCloud t(std::move(target), options);
  const reg::RegistrationResult r = reg::Register(s, t, pair.T_init, options);
  const auto t1 = Clock::now();
  RunResult out;
  out.time_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  out.T = r.T_target_source;
  out.iterations = r.iterations;
  out.status = reg::ToString(r.status);
  out.reference_distance_m = r.reference_distance_m;
  return out;
}

struct Row {
  std::string pair, method;
  double median_ms = 0, min_ms = 0, max_ms = 0;
  double rot_deg = 0, trans_mm = 0;
  double rot_spread_deg = 0, trans_spread_mm = 0;  // max - min over runs
  int iterations = -1;
  std::string status;
  double ratio_default = 0, ratio_p2p = 0;
};

std::string Fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string Pad(const std::string& s, std::size_t width, bool right) {
  // Width in characters; the strings here are ASCII.
  if (s.size() >= width) return s;
  return right ? std::string(width - s.size(), ' ') + s : s + std::string(width - s.size(), ' ');
}

void PrintTable(const std::vector<Row>& rows) {
  const std::vector<std::string> head = {"pair",        "method",       "median ms", "min-max ms",
                                         "rot err deg", "trans err mm", "iters",     "status",
                                         "t / t(rm)",   "t / t(rm p2p)"};
  const std::vector<bool> right = {false, false, true, true, true, true, true, false, true, true};
  std::vector<std::vector<std::string>> cells;
  for (const Row& r : rows) {
    std::string rot = Fmt("%.4f", r.rot_deg), trans = Fmt("%.3f", r.trans_mm);
    if (r.rot_spread_deg > 1e-4 || r.trans_spread_mm > 1e-3) {  // not the same every run
      rot += "*";
      trans += "*";
    }
    cells.push_back({r.pair, r.method, Fmt("%.1f", r.median_ms),
                     Fmt("%.1f", r.min_ms) + "-" + Fmt("%.1f", r.max_ms), rot, trans,
                     r.iterations >= 0 ? std::to_string(r.iterations) : "?", r.status,
                     Fmt("%.2f", r.ratio_default), Fmt("%.2f", r.ratio_p2p)});
  }
  std::vector<std::size_t> width(head.size());
  for (std::size_t c = 0; c < head.size(); ++c) {
    width[c] = head[c].size();
    for (const auto& row : cells) width[c] = std::max(width[c], row[c].size());
  }
  auto line = [&](const std::vector<std::string>& v) {
    std::string s = "|";
    for (std::size_t c = 0; c < v.size(); ++c) s += " " + Pad(v[c], width[c], right[c]) + " |";
    std::cout << s << "\n";
  };
  line(head);
  std::string sep = "|";
  for (std::size_t c = 0; c < head.size(); ++c)
    sep +=
        (right[c] ? std::string(width[c] + 1, '-') + ":" : ":" + std::string(width[c] + 1, '-')) +
        "|";
  std::cout << sep << "\n";
  for (const auto& row : cells) line(row);
}

// The three rovermap configurations of the table.
struct MethodOptions {
  reg::RegistrationOptions plane, fast, p2p;
};

MethodOptions MakeMethodOptions(const Args& args) {
  MethodOptions o;
  o.plane.max_iterations = args.max_iterations;  // defaults: point-to-plane, orientation test
  o.p2p = o.plane;
  o.p2p.residual = reg::Residual::kPointToPoint;
  o.fast =
      rovermap::config::LoadConfig(std::filesystem::path(ROVERMAP_FAST_PRESET), {}).registration;
  o.fast.max_iterations = args.max_iterations;
  return o;
}

// The table's methods, in row order: rovermap's three, then the peers'.
#ifdef ROVERMAP_BENCH_PEERS
constexpr int kMethodCount = 6;
#else
constexpr int kMethodCount = 3;
#endif

// Method `index` of the table on one pair, and only that one: a worker converts no cloud for
// another library. `gate` is the peers' fixed correspondence distance [m].
Method MakeMethod(const BenchPair& pair, const MethodOptions& o, double gate, int index) {
  if (index == 0)
    return {"rovermap point-to-plane (default)", [&pair, &o] { return RunRovermap(pair, o.plane); },
            nullptr};
  if (index == 1)
    return {"rovermap fast preset", [&pair, &o] { return RunRovermap(pair, o.fast); }, nullptr};
  if (index == 2)
    return {"rovermap point-to-point (paper)", [&pair, &o] { return RunRovermap(pair, o.p2p); },
            nullptr};
#ifdef ROVERMAP_BENCH_PEERS
  namespace rb = rovermap::bench;
  const rb::PeerParams params{gate, o.plane.max_iterations};
  const std::shared_ptr<rb::PeerMethod> m =
      index == 3   ? rb::MakePclIcp(pair.source.points, pair.target.points)
      : index == 4 ? rb::MakeOpen3dPointToPoint(pair.source.points, pair.target.points)
                   : rb::MakeOpen3dPointToPlane(pair.source.points, pair.target.points);
  return {m->Name(),
          [m, &pair, params] {
            RunResult out;
            out.T = pair.T_init;
            try {
              const rb::PeerResult r = m->Run(pair.T_init, params);
              out.T = r.T_target_source;
              out.time_ms = r.time_ms;
              out.iterations = r.iterations;
              out.status = r.status;
            } catch (const std::exception& e) {  // Open3D throws on bad input
              std::cerr << m->Name() << ": " << e.what() << "\n";
              out.iterations = 0;
              out.status = "error";
            }
            return out;
          },
          [m, &pair, params] {
            try {
              return m->CountIterations(pair.T_init, params);
            } catch (const std::exception&) {
              return 0;
            }
          }};
#else
  (void)gate;
  return {};
#endif
}

// One run's result as one line: time, iterations, D, the 3×4 pose, then the status.
std::string EncodeResult(const RunResult& r) {
  std::ostringstream os;
  os.precision(17);
  os << r.time_ms << ' ' << r.iterations << ' ' << r.reference_distance_m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) os << ' ' << r.T.matrix()(i, j);
  os << ' ' << (r.status.empty() ? "-" : r.status) << '\n';
  return os.str();
}

RunResult DecodeResult(const std::string& line) {
  std::istringstream is(line);
  RunResult r;
  is >> r.time_ms >> r.iterations >> r.reference_distance_m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) is >> r.T.matrix()(i, j);
  is >> r.status;
  if (!is) throw std::runtime_error("bench_register: bad worker reply '" + line + "'");
  if (r.status == "-") r.status.clear();
  return r;
}

// Marks a worker's answers on its standard output; other lines there (a library's own log
// messages) are passed on to standard error.
constexpr const char* kReplyMark = "@reply ";

// Worker side: "name" -> the method's name, "run" -> one result line, "count" -> the
// iteration count, end of input -> exit.
int ServeMethod(const Method& method) {
  std::string command;
  while (std::getline(std::cin, command)) {
    if (command == "name") {
      std::cout << kReplyMark << method.name << '\n' << std::flush;
    } else if (command == "run") {
      std::cout << kReplyMark << EncodeResult(method.run()) << std::flush;
    } else if (command == "count") {
      const int count = method.count_iterations ? method.count_iterations() : -1;
      std::cout << kReplyMark << count << '\n' << std::flush;
    } else {
      return 2;
    }
  }
  return 0;
}

// Parent side: a worker process, this program re-executed on one method of one pair.
class Worker {
 public:
  Worker(pid_t pid, int to_child, int from_child, int pause_ms)
      : pid_(pid), to_(to_child), from_(::fdopen(from_child, "r")), pause_ms_(pause_ms) {}
  Worker(Worker&& other) noexcept
      : pid_(other.pid_), to_(other.to_), from_(other.from_), pause_ms_(other.pause_ms_) {
    other.pid_ = -1;
    other.to_ = -1;
    other.from_ = nullptr;
  }
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;
  Worker& operator=(Worker&&) = delete;
  ~Worker() { Stop(); }

  // One run after an idle pause. libgomp's idle threads spin-wait (300 000 rounds, some
  // milliseconds) before they sleep: without the pause the previous method's threads still
  // held the cores when the next run began, which slowed rovermap's short runs, not the
  // peers' long ones (bench/README.md, "How the methods are kept apart").
  RunResult Run() {
    if (pause_ms_ > 0) ::usleep(static_cast<useconds_t>(pause_ms_) * 1000);
    return DecodeResult(Ask("run"));
  }
  int CountIterations() { return std::stoi(Ask("count")); }
  std::string Name() { return Ask("name"); }

  void Stop() {
    if (to_ >= 0) ::close(to_);
    if (from_ != nullptr) std::fclose(from_);
    if (pid_ > 0) ::waitpid(pid_, nullptr, 0);
    to_ = -1;
    from_ = nullptr;
    pid_ = -1;
  }

 private:
  std::string Ask(const std::string& command) {
    const std::string line = command + "\n";
    if (::write(to_, line.data(), line.size()) != static_cast<ssize_t>(line.size()))
      throw std::runtime_error("bench_register: worker " + std::to_string(pid_) + " is gone");
    const std::string mark = kReplyMark;
    for (;;) {
      std::string reply;
      int c = std::fgetc(from_);
      for (; c != EOF && c != '\n'; c = std::fgetc(from_)) reply.push_back(static_cast<char>(c));
      if (reply.compare(0, mark.size(), mark) == 0) return reply.substr(mark.size());
      if (!reply.empty()) std::cerr << reply << "\n";
      if (c == EOF)
        throw std::runtime_error("bench_register: worker " + std::to_string(pid_) +
                                 " ended without an answer to '" + command + "'");
    }
  }

  pid_t pid_ = -1;
  int to_ = -1;
  std::FILE* from_ = nullptr;
  int pause_ms_ = 0;
};

Worker StartWorker(int argc, char** argv, std::size_t pair_index, int method, double gate,
                   int pause_ms) {
  // Close-on-exec, so that a later worker does not inherit this one's pipe ends: an inherited
  // write end would keep this worker's stdin open after Stop() and its waitpid would hang.
  int down[2], up[2];  // parent -> child, child -> parent
  if (::pipe2(down, O_CLOEXEC) != 0 || ::pipe2(up, O_CLOEXEC) != 0)
    throw std::runtime_error("bench_register: cannot create a pipe");
  std::vector<std::string> args(argv, argv + argc);
  args.insert(args.end(), {"--worker-pair", std::to_string(pair_index), "--worker-method",
                           std::to_string(method), "--worker-gate", Fmt("%.17g", gate)});
  std::vector<char*> child_argv;
  for (std::string& a : args) child_argv.push_back(a.data());
  child_argv.push_back(nullptr);
  std::cout << std::flush;
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("bench_register: cannot fork");
  if (pid == 0) {
    ::dup2(down[0], STDIN_FILENO);
    ::dup2(up[1], STDOUT_FILENO);
    ::close(down[0]);
    ::close(down[1]);
    ::close(up[0]);
    ::close(up[1]);
    ::execv("/proc/self/exe", child_argv.data());
    ::_exit(127);
  }
  ::close(down[0]);
  ::close(up[1]);
  return Worker(pid, down[1], up[0], pause_ms);
}
}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = ParseArgs(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "bench_register: " << e.what() << "\n";
    Usage(std::cerr);
    return 2;
  }
  if (args.threads > 0) omp_set_num_threads(args.threads);

  // The selected pairs, loaded on demand: a worker loads only its own.
  std::vector<std::function<BenchPair()>> loaders;
  if (args.pairs == "bunny" || args.pairs == "all") {
    loaders.push_back([&] { return BunnyPair(args.data_dir, "bun045.ply", "bun000.ply"); });
    loaders.push_back([&] { return BunnyPair(args.data_dir, "bun315.ply", "bun000.ply"); });
  }
  if (args.pairs == "terrain" || args.pairs == "all") loaders.push_back(TerrainPair);

  const MethodOptions method_options = MakeMethodOptions(args);
  if (args.worker_pair >= 0) {  // a worker process: one method on one pair, driven over stdin
    if (static_cast<std::size_t>(args.worker_pair) >= loaders.size() || args.worker_method < 0 ||
        args.worker_method >= kMethodCount)
      return 2;
    try {
      const BenchPair pair = loaders[static_cast<std::size_t>(args.worker_pair)]();
      return ServeMethod(MakeMethod(pair, method_options, args.worker_gate, args.worker_method));
    } catch (const std::exception& e) {
      std::cerr << "bench_register: " << e.what() << "\n";
      return 1;
    }
  }

  std::vector<BenchPair> pairs;
  try {
    for (const auto& load : loaders) pairs.push_back(load());
  } catch (const std::exception& e) {
    std::cerr << "bench_register: " << e.what() << "\n";
    return 1;
  }

  std::cout << "bench_register: " << args.runs << " timed runs per method (+1 warm-up), each "
            << "method in its own process, " << args.pause_ms << " ms idle before each run, "
            << "OpenMP threads " << omp_get_max_threads()
            << " (rovermap, Open3D; PCL ICP is single-threaded)";
#ifdef ROVERMAP_BENCH_PEERS
  std::cout << "; PCL " << rovermap::bench::PclVersion() << ", Open3D "
            << rovermap::bench::Open3dVersion();
#else
  std::cout << "; peers not built (cmake -DROVERMAP_BENCH_PEERS=ON)";
#endif
  std::cout << "; load average " << LoadAverage() << "\n\n";

  const reg::RegistrationOptions& plane_options = method_options.plane;

  std::vector<Row> rows;
  std::signal(SIGPIPE, SIG_IGN);  // a worker that died shows as a failed write, not a kill
  try {
    for (std::size_t pair_index = 0; pair_index < pairs.size(); ++pair_index) {
      const BenchPair& pair = pairs[pair_index];
      // Each method runs in its own process (this program re-executed), so that no library's
      // allocations change another's: in one process, after Open3D had run, each default bun045
      // registration was slower, glibc having handed the freed memory back so that every run
      // faulted it in again (bench/README.md, "How the methods are kept apart"). Worker 0 is
      // rovermap's default; its warm-up run gives D (median spacing of the target), and D
      // everyone else's gate.
      std::vector<Worker> workers;
      workers.push_back(StartWorker(argc, argv, pair_index, 0, 0.0, args.pause_ms));
      const RunResult warm = workers[0].Run();
      const double d_ref = warm.reference_distance_m;
      const double gate_factor =
          args.gate_factor > 0.0 ? args.gate_factor : plane_options.dmax_initial_factor;
      const double gate = gate_factor * d_ref;
      if (!(gate > 0.0)) {
        std::cerr << "bench_register: pair " << pair.name
                  << ": rovermap derived no reference distance (" << warm.status
                  << "), skipping the pair\n";
        continue;
      }
      const auto [init_rot, init_trans] = rovermap::testing::PoseError(pair.T_true, pair.T_init);
      std::printf(
          "pair %-14s source %zu pts, target %zu pts; initial error %.3f deg, %.2f mm (%s); "
          "D = %.3f mm, gate = %.0f x D = %.2f mm\n",
          pair.name.c_str(), pair.source.size(), pair.target.size(), init_rot, init_trans * 1e3,
          pair.perturbation.c_str(), d_ref * 1e3, gate_factor, gate * 1e3);
      std::fflush(stdout);

      for (int k = 1; k < kMethodCount; ++k) {
        workers.push_back(StartWorker(argc, argv, pair_index, k, gate, args.pause_ms));
        workers.back().Run();  // warm-up (untimed)
      }
      std::vector<std::string> names;
      for (Worker& w : workers) names.push_back(w.Name());

      // `runs` rounds, methods interleaved in each round so that machine noise spreads over all.
      std::vector<std::vector<RunResult>> results(workers.size());
      for (int r = 0; r < args.runs; ++r)
        for (std::size_t k = 0; k < workers.size(); ++k) results[k].push_back(workers[k].Run());
      std::vector<int> counted(workers.size(), -1);
      for (std::size_t k = 0; k < workers.size(); ++k)
        if (results[k].front().iterations < 0) counted[k] = workers[k].CountIterations();
      for (Worker& w : workers) w.Stop();
      const std::size_t first_row = rows.size();
      for (std::size_t k = 0; k < workers.size(); ++k) {
        Row row;
        row.pair = pair.name;
        row.method = names[k];
        std::vector<double> times, rots, transs;
        for (const RunResult& rr : results[k]) {
          times.push_back(rr.time_ms);
          const auto [rot, trans] = rovermap::testing::PoseError(pair.T_true, rr.T);
          rots.push_back(rot);
          transs.push_back(trans * 1e3);
        }
        row.median_ms = Median(times);
        row.min_ms = *std::min_element(times.begin(), times.end());
        row.max_ms = *std::max_element(times.begin(), times.end());
        row.rot_deg = Median(rots);
        row.trans_mm = Median(transs);
        row.rot_spread_deg = *std::max_element(rots.begin(), rots.end()) -
                             *std::min_element(rots.begin(), rots.end());
        row.trans_spread_mm = *std::max_element(transs.begin(), transs.end()) -
                              *std::min_element(transs.begin(), transs.end());
        row.iterations = results[k].front().iterations;
        row.status = results[k].front().status;
        if (row.iterations < 0 && counted[k] >= 0) {
          row.iterations = counted[k];
          if (row.status.empty())
            row.status =
                row.iterations < plane_options.max_iterations ? "converged" : "max_iterations";
        }
        rows.push_back(row);
      }
      const double t_default = rows[first_row].median_ms;
      const double t_p2p =
          rows[first_row + 2].median_ms;  // methods: default, fast preset, p2p, ...
      for (std::size_t k = first_row; k < rows.size(); ++k) {
        rows[k].ratio_default = rows[k].median_ms / t_default;
        rows[k].ratio_p2p = rows[k].median_ms / t_p2p;
      }
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }

  const double shown_factor =
      args.gate_factor > 0.0 ? args.gate_factor : plane_options.dmax_initial_factor;
  std::cout
      << "\nAll methods start from the same initial estimate. Correspondence gate: the peers "
         "use a fixed max distance of "
      << shown_factor
      << " x rovermap's D (D = median point spacing of the target); rovermap starts at Dmax = "
      << plane_options.dmax_initial_factor
      << " x D and adapts it (Zhang 1994).\nTimes: wall clock, clouds in memory to result "
         "(trees, normals, iterations), median of "
      << args.runs
      << " runs. Errors vs ground truth (median over runs; * = varied between runs).\n"
         "t / t(rm): median time / rovermap default's; t / t(rm p2p): / rovermap "
         "point-to-point's (> 1: rovermap faster).\n\n";
  PrintTable(rows);
  std::cout << "\nload average at the end: " << LoadAverage() << "\n";
  return 0;
}
