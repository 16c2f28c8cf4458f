// What every subcommand shares: its --config/--set options, and typed errors turned into
// messages and exit statuses (docs/design.md §5). Linked into both programs (apps/Launcher.cpp).
#include <iostream>

#include "apps/Commands.hpp"
#include "config/ConfigError.hpp"
#include "io/IoError.hpp"

void rovermap::apps::AddConfigOptions(CLI::App* cmd, ConfigArgs* args) {
  cmd->add_option("--config", args->config_file, "YAML config file (see config/default.yaml)");
  cmd->add_option("--set", args->overrides, "Override one config key: --set key=value (repeatable)")
      ->take_all();
}

rovermap::config::Config rovermap::apps::LoadConfigArgs(const ConfigArgs& args) {
  if (args.config_file.empty()) return rovermap::config::LoadConfig(std::nullopt, args.overrides);
  return rovermap::config::LoadConfig(std::filesystem::path(args.config_file), args.overrides);
}

int rovermap::apps::RunReportingErrors(const std::function<int()>& command, std::string* message) {
  std::string text;
  int status = kExitOk;
  try {
    return command();
  } catch (const rovermap::config::ConfigError& e) {
    text = std::string("config error: ") + e.what();
    status = kExitUsage;
  } catch (const UsageError& e) {
    text = e.what();
    status = kExitUsage;
  } catch (const rovermap::io::IoError& e) {
    text = e.what();
    status = kExitFailure;
  } catch (const std::exception& e) {
    text = std::string("error: ") + e.what();
    status = kExitFailure;
  }
  std::cerr << "rovermap: " << text << "\n";
  if (message != nullptr) *message = text;
  return status;
}
