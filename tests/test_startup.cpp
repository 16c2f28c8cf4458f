// How the `rovermap` command starts (apps/Launcher.cpp, apps/main.cpp): a plain `register` runs
// in the launcher, which loads neither GDAL nor OpenCV's image codecs (a start-up longer than
// the registration's own work); everything else runs in rovermap-full, which the launcher
// becomes. The commands that run many frames and `register` get OMP_WAIT_POLICY=PASSIVE (libgomp
// reads it only when it loads; docs/benchmarks.md, "One-shot registration").
//
// What the process runs with is read from /proc/PID/environ while it waits, blocked, to open its
// configuration file (--config, read before anything else): a FIFO, which it cannot open before
// the test opens the other end. Once the test can
// open the FIFO for writing without blocking, the process has it open for reading, so it has
// re-executed itself by then if it was going to.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/ScratchDir.hpp"

namespace fs = std::filesystem;

namespace {

struct Started {
  bool blocked_on_input = false;  ///< the process opened the FIFO
  std::string environment;        ///< its /proc/PID/environ then, NUL-separated
  std::string program;            ///< the file name of the program it runs (/proc/PID/exe)
  std::string maps;               ///< its /proc/PID/maps: the shared libraries it loaded
};

// Starts `rovermap ARGS` without OMP_WAIT_POLICY in its environment, waits until it opens
// `fifo`, reads its environment, then lets it go (the FIFO closes empty) and reaps it.
Started StartBlockedOn(const fs::path& fifo, const std::vector<std::string>& args) {
  Started out;
  std::vector<std::string> argv_strings = {ROVERMAP_EXECUTABLE};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::unsetenv("OMP_WAIT_POLICY");
    const int null_fd = ::open("/dev/null", O_WRONLY);
    ::dup2(null_fd, 1);
    ::dup2(null_fd, 2);
    std::vector<char*> argv;
    for (auto& s : argv_strings) argv.push_back(s.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int writer = -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline) {
    writer = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
    if (writer >= 0 || errno != ENXIO) break;  // ENXIO: no reader yet
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (writer >= 0) {
    out.blocked_on_input = true;
    std::ifstream environ("/proc/" + std::to_string(pid) + "/environ", std::ios::binary);
    out.environment.assign(std::istreambuf_iterator<char>(environ), {});
    std::error_code error;
    out.program = fs::read_symlink("/proc/" + std::to_string(pid) + "/exe", error).filename();
    std::ifstream maps("/proc/" + std::to_string(pid) + "/maps");
    out.maps.assign(std::istreambuf_iterator<char>(maps), {});
    ::close(writer);  // the reader sees an empty input and fails on it
  } else {
    ::kill(pid, SIGKILL);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return out;
}

bool HasPassiveWaitPolicy(const std::string& environment) {
  return environment.find(std::string("OMP_WAIT_POLICY=PASSIVE") + '\0') != std::string::npos;
}

}  // namespace

TEST(Startup, OneShotRegisterRunsInTheLauncherWithPassiveOpenMp) {
  const fs::path dir = rovermap::testing::ScratchDir();
  const fs::path fifo = dir / "config.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Started started =
      StartBlockedOn(fifo, {"register", (dir / "source.ply").string(),
                            (dir / "target.ply").string(), "--config", fifo.string()});
  ASSERT_TRUE(started.blocked_on_input);
  EXPECT_TRUE(HasPassiveWaitPolicy(started.environment));
  EXPECT_EQ(started.program, "rovermap");
  EXPECT_EQ(started.maps.find("libgdal"), std::string::npos);
  EXPECT_EQ(started.maps.find("libopencv_imgcodecs"), std::string::npos);
}

TEST(Startup, RegisterWithAPreviewRunsInTheFullProgram) {
  const fs::path dir = rovermap::testing::ScratchDir();
  const fs::path fifo = dir / "config.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Started started = StartBlockedOn(
      fifo, {"register", (dir / "source.ply").string(), (dir / "target.ply").string(), "--preview",
             (dir / "preview.png").string(), "--config", fifo.string()});
  ASSERT_TRUE(started.blocked_on_input);
  EXPECT_EQ(started.program, "rovermap-full");
  EXPECT_TRUE(HasPassiveWaitPolicy(started.environment));
}

TEST(Startup, ReplayRunsAgainWithPassiveOpenMp) {
  const fs::path dir = rovermap::testing::ScratchDir();
  const fs::path fifo = dir / "config.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Started started = StartBlockedOn(
      fifo, {"replay", dir.string(), "--out", (dir / "out").string(), "--config", fifo.string()});
  ASSERT_TRUE(started.blocked_on_input);
  EXPECT_TRUE(HasPassiveWaitPolicy(started.environment));
  EXPECT_EQ(started.program, "rovermap-full");
}
