#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace rovermap::apps {

/// Exit statuses (DESIGN.md §5).
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  ///< bad input data, failed registration, I/O
constexpr int kExitUsage = 2;    ///< usage or config error

/// `--config FILE` and repeated `--set key=value`, taken by every subcommand.
struct ConfigArgs {
  std::string config_file;
  std::vector<std::string> overrides;
};
void AddConfigOptions(CLI::App* cmd, ConfigArgs* args);

struct RegisterArgs {
  ConfigArgs config;
  std::string source;
  std::string target;
  std::string init;     ///< "rx ry rz tx ty tz" (rad, m)
  std::string preview;  ///< PNG of the alignment before and after (optional)
};
CLI::App* AddRegisterCommand(CLI::App* app, RegisterArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunRegister(const RegisterArgs& args);

/// A command-line value that parses but makes no sense (exit 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace rovermap::apps
