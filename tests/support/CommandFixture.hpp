#pragma once
// Runs the `rovermap` executable in end-to-end tests: exit status, stdout and stderr, with a
// scratch directory per test for inputs and outputs.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/ScratchDir.hpp"

namespace rovermap::testing {

struct CommandResult {
  int status = -1;  ///< exit status, or 128 + signal
  std::string out;
  std::string err;
};

inline std::string Slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The lines of a text file that are neither empty nor `#` comments (TUM files, drift.csv).
inline std::vector<std::string> DataLines(const std::filesystem::path& p) {
  std::vector<std::string> lines;
  std::istringstream in(Slurp(p));
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  return lines;
}

/// Runs the shell command `cmd` with stdout and stderr into `dir`.
inline CommandResult RunCapturing(const std::string& cmd, const std::filesystem::path& dir) {
  const int rc = std::system(
      (cmd + " >" + (dir / "stdout").string() + " 2>" + (dir / "stderr").string()).c_str());
  CommandResult r;
  r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
  r.out = Slurp(dir / "stdout");
  r.err = Slurp(dir / "stderr");
  return r;
}

/// `rovermap ARGS` with stdout and stderr into `dir` (suites that share one scratch directory).
inline CommandResult RunRovermapIn(const std::filesystem::path& dir, const std::string& args) {
  return RunCapturing(std::string(ROVERMAP_EXECUTABLE) + " " + args, dir);
}

class CommandFixture : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = ScratchDir(); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  /// `rovermap ARGS` (ARGS as a shell would split them), under run_as_ if set.
  CommandResult Rovermap(const std::string& args) {
    std::string cmd;
    for (const std::string& word : run_as_) cmd += word + " ";
    cmd += std::string(ROVERMAP_EXECUTABLE) + " " + args;
    return RunCapturing(cmd, dir_);
  }

  /// Writes `text` to `name` in the scratch directory; returns its path.
  std::string Write(const std::string& name, const std::string& text) {
    const std::filesystem::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }

  std::filesystem::path dir_;
  /// A command the commands run under (e.g. setpriv to drop root); its first word an
  /// absolute path.
  std::vector<std::string> run_as_;
};

}  // namespace rovermap::testing
