// `rovermap serve` end to end (DESIGN §7): frames dropped into an inbox give the outputs of
// `replay`; kill -9 at every kind of point (mid-frame, mid-journal, mid-checkpoint,
// mid-publish) and a restart give them too, with no frame registered twice; SIGTERM exits 0
// with outputs; bad frames go to rejected/; a gap times out; a second daemon is refused.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "io/GeoTiff.hpp"
#include "tests/support/CommandFixture.hpp"

namespace fs = std::filesystem;
using rovermap::testing::DataLines;
using rovermap::testing::Slurp;

namespace {

const fs::path kTinyCloud = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_cloud";    // 5 frames
const fs::path kTinyStereo = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_stereo";  // 3 frames

// Lines of `text` that start with `prefix` and hold one of `words` (std::regex would do, but
// GCC 12 warns inside <regex> in the sanitizer build).
int CountLines(const std::string& text, const std::string& prefix,
               const std::vector<std::string>& words = {""}) {
  int n = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) != 0) continue;
    for (const std::string& w : words) {
      if (line.find(w, prefix.size()) != std::string::npos) {
        ++n;
        break;
      }
    }
  }
  return n;
}

class Serve : public rovermap::testing::CommandFixture {
 protected:
  void TearDown() override {
    for (pid_t pid : running_) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
    CommandFixture::TearDown();
  }

  // A file put into the inbox the way a producer must: written under a dot-name, renamed in.
  static void Drop(const fs::path& to, const std::string& contents) {
    const fs::path temp = to.parent_path() / ("." + to.filename().string());
    std::ofstream(temp, std::ios::binary) << contents;
    fs::rename(temp, to);
  }

  // Frame k of `sequence` into the inbox: its data files, its ground-truth line, its odometry.
  static void DropFrame(const fs::path& sequence, const fs::path& inbox, std::size_t k) {
    char stem[16];
    std::snprintf(stem, sizeof(stem), "%06zu", k);
    fs::create_directories(inbox / "frames");
    for (const char* ext : {".left.png", ".right.png", ".ply"}) {
      const fs::path from = sequence / "frames" / (std::string(stem) + ext);
      if (fs::exists(from)) Drop(inbox / "frames" / from.filename(), Slurp(from));
    }
    Drop(inbox / "frames" / (std::string(stem) + ".gt"),
         DataLines(sequence / "groundtruth.tum").at(k) + "\n");
    Drop(inbox / "frames" / (std::string(stem) + ".odom"),
         DataLines(sequence / "odometry.tum").at(k) + "\n");
  }

  fs::path MakeInbox(const fs::path& sequence, std::size_t frames, const std::string& name) {
    const fs::path inbox = dir_ / name;
    fs::create_directories(inbox);
    Drop(inbox / "sequence.yaml", Slurp(sequence / "sequence.yaml"));
    for (std::size_t k = 0; k < frames; ++k) DropFrame(sequence, inbox, k);
    return inbox;
  }

  // `rovermap serve` in the background, stderr appended to `log`; `fault` sets the kill hook.
  pid_t Start(const fs::path& inbox, const fs::path& out, const std::string& log,
              const std::vector<std::string>& extra = {}, const std::string& fault = "") {
    std::vector<std::string> args = {ROVERMAP_EXECUTABLE,
                                     "serve",
                                     "--inbox",
                                     inbox.string(),
                                     "--out",
                                     out.string(),
                                     "--set",
                                     "serve.poll_interval_s=0.05"};
    args.insert(args.end(), extra.begin(), extra.end());
    const pid_t pid = ::fork();
    if (pid == 0) {
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      if (!fault.empty()) ::setenv("ROVERMAP_FAULT_KILL", fault.c_str(), 1);
      std::FILE* err = std::fopen((dir_ / log).c_str(), "a");
      if (err != nullptr) ::dup2(fileno(err), 2);
      std::FILE* out_null = std::fopen("/dev/null", "w");
      if (out_null != nullptr) ::dup2(fileno(out_null), 1);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    running_.push_back(pid);
    return pid;
  }

  // Exit status (128 + signal when killed); -1 if still running after `timeout_s`.
  int WaitExit(pid_t pid, double timeout_s = 60.0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < until) {
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        running_.erase(std::remove(running_.begin(), running_.end(), pid), running_.end());
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }

  // status.json once its next_frame reached `next` (null json on timeout).
  nlohmann::json WaitForNext(const fs::path& out, std::size_t next, double timeout_s = 60.0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < until) {
      if (fs::exists(out / "status.json")) {
        const nlohmann::json s = nlohmann::json::parse(Slurp(out / "status.json"), nullptr, false);
        if (!s.is_discarded() && s.value("next_frame", std::size_t{0}) >= next) return s;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return nullptr;
  }

  // SIGTERM: the daemon finishes, publishes, checkpoints and exits 0.
  void Stop(pid_t pid) {
    ::kill(pid, SIGTERM);
    EXPECT_EQ(WaitExit(pid), 0);
  }

  fs::path Replay(const fs::path& sequence, const std::vector<std::string>& sets = {}) {
    const fs::path out = dir_ / "replay";
    std::string args = "replay " + sequence.string() + " --out " + out.string();
    for (const std::string& s : sets) args += " --set " + s;
    EXPECT_EQ(Rovermap(args).status, 0);
    return out;
  }

  // The outputs that must not depend on how the frames came: the trajectory to the byte, the
  // OctoMap to the byte, the DEM cell for cell.
  static void ExpectSameOutputs(const fs::path& replay, const fs::path& serve) {
    EXPECT_EQ(Slurp(serve / "trajectory.tum"), Slurp(replay / "trajectory.tum"));
    EXPECT_EQ(Slurp(serve / "odometry.tum"), Slurp(replay / "odometry.tum"));
    EXPECT_EQ(Slurp(serve / "map.bt"), Slurp(replay / "map.bt"));
    // The DEM: every band, cell for cell (NaN where NaN).
    const auto a = rovermap::io::ReadDemGeoTiff(replay / "dem.tif");
    const auto b = rovermap::io::ReadDemGeoTiff(serve / "dem.tif");
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.geotransform, b.geotransform);
    EXPECT_TRUE(SameFloats(a.elevation_m, b.elevation_m));
    EXPECT_TRUE(SameFloats(a.stddev_m, b.stddev_m));
    EXPECT_TRUE(SameFloats(a.count, b.count));
    std::size_t cells = 0;
    for (float z : a.elevation_m) cells += std::isfinite(z) ? 1 : 0;
    EXPECT_GT(cells, 100u);
    // drift.csv row for row, but for time_ms (column 21).
    const auto rows_a = DataLines(replay / "drift.csv");
    const auto rows_b = DataLines(serve / "drift.csv");
    ASSERT_EQ(rows_a.size(), rows_b.size());
    for (std::size_t i = 0; i < rows_a.size(); ++i) {
      EXPECT_EQ(WithoutField(rows_a[i], 21), WithoutField(rows_b[i], 21)) << "row " << i;
    }
  }

  static bool SameFloats(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (std::isnan(a[i]) != std::isnan(b[i]) || (!std::isnan(a[i]) && a[i] != b[i])) return false;
    }
    return true;
  }

  static std::string WithoutField(const std::string& line, std::size_t field) {
    std::size_t start = 0;
    for (std::size_t k = 0; k < field && start != std::string::npos; ++k) {
      start = line.find(',', start);
      if (start != std::string::npos) ++start;
    }
    if (start == std::string::npos) return line;
    const std::size_t end = line.find(',', start);
    return line.substr(0, start) + (end == std::string::npos ? "" : line.substr(end + 1));
  }

  std::vector<pid_t> running_;
};

TEST_F(Serve, FramesDroppedOneByOneGiveReplaysOutputs) {
  const fs::path replay = Replay(kTinyCloud);
  const fs::path inbox = MakeInbox(kTinyCloud, 0, "inbox");
  const fs::path out = dir_ / "out";
  const pid_t pid = Start(inbox, out, "log", {"--set", "serve.publish_every=2"});
  // A producer on another thread, one frame at a time.
  std::thread producer([&] {
    for (std::size_t k = 0; k < 5; ++k) {
      DropFrame(kTinyCloud, inbox, k);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  producer.join();
  const nlohmann::json status = WaitForNext(out, 5);
  ASSERT_FALSE(status.is_null()) << Slurp(dir_ / "log");
  EXPECT_EQ(status["frames_done"], 5);
  EXPECT_EQ(status["rejected"], 0);
  EXPECT_EQ(status["state"], "running");
  EXPECT_GT(status["frames_per_second"].get<double>(), 0.0);
  Stop(pid);
  ExpectSameOutputs(replay, out);
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(summary["frames"], 5);
  EXPECT_TRUE(summary.contains("metrics"));
  EXPECT_EQ(nlohmann::json::parse(Slurp(out / "status.json"))["state"], "stopped");
  EXPECT_EQ(CountLines(Slurp(dir_ / "log"), "serve: frame "), 5);
}

// kill -9 at each kind of point, then a restart on the same OUT: the result is the
// uninterrupted run's, and every frame is logged as done exactly once over the two runs.
TEST_F(Serve, KillNineAtAnyPointThenRestartLosesNothing) {
  const fs::path replay = Replay(kTinyCloud);
  const std::vector<std::string> every = {"--set", "serve.publish_every=2", "--set",
                                          "serve.checkpoint_every=2"};
  int run = 0;
  for (const std::string fault :
       {"frame:processed:4", "journal:partial:3", "checkpoint:written:1", "checkpoint:renamed:2",
        "publish:dem.tif:1", "publish:summary.json:2"}) {
    SCOPED_TRACE(fault);
    const std::string tag = std::to_string(++run);
    const fs::path inbox = MakeInbox(kTinyCloud, 5, "inbox-" + tag);
    const fs::path out = dir_ / ("out-" + tag);
    const std::string log = "log-" + tag;
    EXPECT_EQ(WaitExit(Start(inbox, out, log, every, fault)), 128 + SIGKILL) << Slurp(dir_ / log);
    const pid_t pid = Start(inbox, out, log, every);
    ASSERT_FALSE(WaitForNext(out, 5).is_null()) << Slurp(dir_ / log);
    Stop(pid);
    ExpectSameOutputs(replay, out);
    const std::string text = Slurp(dir_ / log);
    EXPECT_EQ(CountLines(text, "serve: frame ", {" first", " registered", " partial", " fallback"}),
              5)
        << text;
    EXPECT_EQ(CountLines(text, "serve: resumed at frame"), 1) << text;
  }
}

// Stereo: a restart reloads the registration reference from the inbox (it is not in the
// snapshot); the result must still be the replay's.
TEST_F(Serve, StereoRestartFromSnapshotReloadsTheReference) {
  const fs::path replay = Replay(kTinyStereo);
  const fs::path inbox = MakeInbox(kTinyStereo, 3, "inbox");
  const fs::path out = dir_ / "out";
  const std::vector<std::string> every = {"--set", "serve.checkpoint_every=1"};
  EXPECT_EQ(WaitExit(Start(inbox, out, "log", every, "checkpoint:renamed:2")), 128 + SIGKILL);
  const pid_t pid = Start(inbox, out, "log", every);
  ASSERT_FALSE(WaitForNext(out, 3).is_null()) << Slurp(dir_ / "log");
  Stop(pid);
  ExpectSameOutputs(replay, out);
  EXPECT_NE(Slurp(dir_ / "log").find("resumed at frame 2"), std::string::npos)
      << Slurp(dir_ / "log");
}

TEST_F(Serve, BadFrameIsRejectedWithItsReasonAndTheDaemonGoesOn) {
  const fs::path inbox = MakeInbox(kTinyCloud, 0, "inbox");
  for (std::size_t k = 0; k < 5; ++k) DropFrame(kTinyCloud, inbox, k);
  // Frame 2's PLY cut in half.
  const fs::path ply = inbox / "frames" / "000002.ply";
  const std::string bytes = Slurp(ply);
  Drop(ply, bytes.substr(0, bytes.size() / 2));
  const fs::path out = dir_ / "out";
  // Polling instead of inotify (network file systems), here too.
  const pid_t pid = Start(inbox, out, "log", {"--set", "serve.use_inotify=false"});
  const nlohmann::json status = WaitForNext(out, 5);
  ASSERT_FALSE(status.is_null()) << Slurp(dir_ / "log");
  EXPECT_EQ(status["rejected"], 1);
  Stop(pid);
  EXPECT_TRUE(fs::exists(inbox / "rejected" / "000002.ply"));
  EXPECT_FALSE(fs::exists(inbox / "frames" / "000002.ply"));
  EXPECT_NE(Slurp(inbox / "rejected" / "000002.reason").find("000002.ply"), std::string::npos);
  const auto rows = DataLines(out / "drift.csv");
  ASSERT_EQ(rows.size(), 6u);  // header + 5 frames: the bad one keeps its dead-reckoning pose
  EXPECT_NE(rows[3].find("bad_frame"), std::string::npos);
  EXPECT_EQ(DataLines(out / "trajectory.tum").size(), 5u);
}

TEST_F(Serve, GapTimesOutAndIsRecordedThenALateFrameIsRejected) {
  const fs::path inbox = MakeInbox(kTinyCloud, 0, "inbox");
  for (std::size_t k : {0, 1, 4}) DropFrame(kTinyCloud, inbox, k);
  const fs::path out = dir_ / "out";
  const pid_t pid = Start(inbox, out, "log", {"--set", "serve.gap_timeout_s=0.5"});
  nlohmann::json status = WaitForNext(out, 5);
  ASSERT_FALSE(status.is_null()) << Slurp(dir_ / "log");
  // Frames 2 and 3 never came: one timeout declares both.
  EXPECT_EQ(status["missing"], nlohmann::json::array({2, 3}));
  EXPECT_EQ(status["frames_done"], 3);
  EXPECT_EQ(CountLines(Slurp(dir_ / "log"), "serve: frame 2 holds the queue"), 1);
  EXPECT_EQ(CountLines(Slurp(dir_ / "log"), "serve: frame 3 holds the queue"), 0);
  // Frame 2 arrives after all: too late.
  DropFrame(kTinyCloud, inbox, 2);
  for (int i = 0; i < 200 && !fs::exists(inbox / "rejected" / "000002.reason"); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_NE(Slurp(inbox / "rejected" / "000002.reason").find("declared missing"),
            std::string::npos);
  Stop(pid);
  EXPECT_EQ(DataLines(out / "trajectory.tum").size(), 3u);
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(summary["serve"]["missing_frames"], nlohmann::json::array({2, 3}));
}

// A missing frame whose odometry line came keeps its place in the trajectory, flagged.
TEST_F(Serve, GapWithOdometryKeepsTheDeadReckoningPose) {
  const fs::path inbox = MakeInbox(kTinyCloud, 0, "inbox");
  for (std::size_t k : {0, 1, 3}) DropFrame(kTinyCloud, inbox, k);
  Drop(inbox / "frames" / "000002.odom", DataLines(kTinyCloud / "odometry.tum").at(2) + "\n");
  const fs::path out = dir_ / "out";
  const pid_t pid = Start(inbox, out, "log", {"--set", "serve.gap_timeout_s=0.3"});
  ASSERT_FALSE(WaitForNext(out, 4).is_null()) << Slurp(dir_ / "log");
  Stop(pid);
  const auto rows = DataLines(out / "drift.csv");
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_NE(rows[3].find("bad_frame,missing"), std::string::npos) << rows[3];
  EXPECT_TRUE(fs::exists(inbox / "rejected" / "000002.odom"));
}

TEST_F(Serve, SecondDaemonOnTheSameOutIsRefusedNamingThePid) {
  const fs::path inbox = MakeInbox(kTinyCloud, 1, "inbox");
  const fs::path out = dir_ / "out";
  const pid_t pid = Start(inbox, out, "log");
  ASSERT_FALSE(WaitForNext(out, 1).is_null()) << Slurp(dir_ / "log");
  const auto second = Rovermap("serve --inbox " + inbox.string() + " --out " + out.string());
  EXPECT_EQ(second.status, 1);
  EXPECT_NE(second.err.find("pid " + std::to_string(pid)), std::string::npos) << second.err;
  Stop(pid);
}

TEST_F(Serve, BadSequenceYamlIsAClearErrorAtStart) {
  const fs::path inbox = dir_ / "inbox";
  fs::create_directories(inbox);
  Drop(inbox / "sequence.yaml", "sensor:\n  type: lidar\n");
  const auto r = Rovermap("serve --inbox " + inbox.string() + " --out " + (dir_ / "o").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("sequence.yaml"), std::string::npos) << r.err;
}

TEST_F(Serve, RestartWithAnotherConfigurationIsRefused) {
  const fs::path inbox = MakeInbox(kTinyCloud, 2, "inbox");
  const fs::path out = dir_ / "out";
  const pid_t pid = Start(inbox, out, "log");
  ASSERT_FALSE(WaitForNext(out, 2).is_null()) << Slurp(dir_ / "log");
  Stop(pid);
  const auto r = Rovermap("serve --inbox " + inbox.string() + " --out " + out.string() +
                          " --set registration.max_iterations=7");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("another configuration"), std::string::npos) << r.err;
}

// A second SIGTERM leaves at once (status 1), mid-frame; the checkpoint is still consistent:
// a restart ends where an uninterrupted run does.
TEST_F(Serve, SecondSignalExitsAtOnceAndTheRestartStillEqualsReplay) {
  const fs::path replay = Replay(kTinyStereo);
  const fs::path inbox = MakeInbox(kTinyStereo, 3, "inbox");
  const fs::path out = dir_ / "out";
  const pid_t pid = Start(inbox, out, "log", {"--set", "serve.checkpoint_every=1"});
  ASSERT_FALSE(WaitForNext(out, 1).is_null()) << Slurp(dir_ / "log");
  ::kill(pid, SIGTERM);
  // Apart, or the kernel merges the two pending signals into one.
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  ::kill(pid, SIGTERM);
  EXPECT_EQ(WaitExit(pid), 1);
  const pid_t again = Start(inbox, out, "log", {"--set", "serve.checkpoint_every=1"});
  ASSERT_FALSE(WaitForNext(out, 3).is_null()) << Slurp(dir_ / "log");
  Stop(again);
  ExpectSameOutputs(replay, out);
}

// A publication that cannot be written (here dem.tif's place is taken by a directory) stops
// the daemon with status 1 and a message naming the file; no temporary is left beside it. The
// journal holds every frame done, so a restart loses nothing.
TEST_F(Serve, FailedPublicationStopsTheDaemonNamingTheFile) {
  const fs::path inbox = MakeInbox(kTinyCloud, 5, "inbox");
  const fs::path out = dir_ / "out";
  fs::create_directories(out / "dem.tif");
  const pid_t pid = Start(inbox, out, "log", {"--set", "serve.publish_every=2"});
  EXPECT_EQ(WaitExit(pid), 1) << Slurp(dir_ / "log");
  const std::string log = Slurp(dir_ / "log");
  EXPECT_NE(log.find("dem.tif"), std::string::npos) << log;
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
  }
}

TEST_F(Serve, SigtermWhileWaitingForTheSequenceExitsZero) {
  const pid_t pid = Start(dir_ / "empty-inbox", dir_ / "out", "log");
  // Signalled once it says it waits: after a fixed 300 ms its handler was sometimes not in
  // place yet on a loaded machine (load average 8; it died of the SIGTERM, status 143).
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (Slurp(dir_ / "log").find("waiting for") == std::string::npos &&
         std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  Stop(pid);
  EXPECT_NE(Slurp(dir_ / "log").find("waiting for"), std::string::npos);
}

}  // namespace
