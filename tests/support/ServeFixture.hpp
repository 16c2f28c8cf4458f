#pragma once
// Runs `rovermap serve` in end-to-end tests: an inbox filled the way a producer must fill it,
// the daemon in the background with its stderr in a log, and waits with timeouts (a daemon
// that hangs fails the test instead of blocking it).

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/CommandFixture.hpp"

namespace rovermap::testing {

class ServeFixture : public CommandFixture {
 protected:
  void TearDown() override {
    for (pid_t pid : running_) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
    CommandFixture::TearDown();
  }

  // A file put into the inbox the way a producer must: written under a dot-name, renamed in.
  static void Drop(const std::filesystem::path& to, const std::string& contents) {
    const std::filesystem::path temp = to.parent_path() / ("." + to.filename().string());
    std::ofstream(temp, std::ios::binary) << contents;
    std::filesystem::rename(temp, to);
  }

  // Frame k of `sequence` into the inbox: its data files, its ground-truth line, its odometry.
  static void DropFrame(const std::filesystem::path& sequence, const std::filesystem::path& inbox,
                        std::size_t k) {
    char stem[16];
    std::snprintf(stem, sizeof(stem), "%06zu", k);
    std::filesystem::create_directories(inbox / "frames");
    for (const char* ext : {".left.png", ".right.png", ".ply"}) {
      const std::filesystem::path from = sequence / "frames" / (std::string(stem) + ext);
      if (std::filesystem::exists(from)) Drop(inbox / "frames" / from.filename(), Slurp(from));
    }
    Drop(inbox / "frames" / (std::string(stem) + ".gt"),
         DataLines(sequence / "groundtruth.tum").at(k) + "\n");
    Drop(inbox / "frames" / (std::string(stem) + ".odom"),
         DataLines(sequence / "odometry.tum").at(k) + "\n");
  }

  std::filesystem::path MakeInbox(const std::filesystem::path& sequence, std::size_t frames,
                                  const std::string& name) {
    const std::filesystem::path inbox = dir_ / name;
    std::filesystem::create_directories(inbox);
    Drop(inbox / "sequence.yaml", Slurp(sequence / "sequence.yaml"));
    for (std::size_t k = 0; k < frames; ++k) DropFrame(sequence, inbox, k);
    return inbox;
  }

  // `rovermap serve` in the background (under run_as_), stderr appended to `log`; `fault` sets
  // the kill hook.
  pid_t Start(const std::filesystem::path& inbox, const std::filesystem::path& out,
              const std::string& log, const std::vector<std::string>& extra = {},
              const std::string& fault = "") {
    std::vector<std::string> args = {ROVERMAP_EXECUTABLE,
                                     "serve",
                                     "--inbox",
                                     inbox.string(),
                                     "--out",
                                     out.string(),
                                     "--set",
                                     "serve.poll_interval_s=0.05"};
    args.insert(args.end(), extra.begin(), extra.end());
    args.insert(args.begin(), run_as_.begin(), run_as_.end());
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

  // status.json once its next_frame reached `next`, written by a daemon still running (not one
  // reaped before: a killed run's status can be ahead of its journal, since the publications
  // run beside the frames); null json on timeout.
  nlohmann::json WaitForNext(const std::filesystem::path& out, std::size_t next,
                             double timeout_s = 60.0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < until) {
      if (std::filesystem::exists(out / "status.json")) {
        const nlohmann::json s = nlohmann::json::parse(Slurp(out / "status.json"), nullptr, false);
        const bool ours = !s.is_discarded() &&
                          std::find(running_.begin(), running_.end(), s.value("pid", pid_t{-1})) !=
                              running_.end();
        if (ours && s.value("next_frame", std::size_t{0}) >= next) return s;
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

  std::vector<pid_t> running_;
};

}  // namespace rovermap::testing
