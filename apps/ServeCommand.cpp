// `rovermap serve --inbox DIR --out DIR`: the daemon (docs/design.md §7).
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <string_view>

#include "apps/Commands.hpp"
#include "config/Config.hpp"
#include "io/IoError.hpp"
#include "service/Checkpoint.hpp"
#include "service/Daemon.hpp"

namespace rovermap::apps {
namespace {

std::atomic<int> g_stop{0};

// The first SIGTERM/SIGINT asks the daemon to finish its frame, publish and checkpoint; a
// second one leaves at once (every file the daemon writes is atomic or journalled, so the
// checkpoint stays consistent).
extern "C" void OnStopSignal(int) {
  if (g_stop.fetch_add(1) >= 1) ::_exit(kExitFailure);
}

void InstallSignalHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a waiting poll() wakes up
  ::sigaction(SIGTERM, &action, nullptr);
  ::sigaction(SIGINT, &action, nullptr);
}

// Test hook: ROVERMAP_FAULT_KILL="POINT[:N]" kills the process (SIGKILL, as a power loss would
// stop it) the N-th time (default 1st) it passes POINT: "frame:processed", "journal:partial",
// "checkpoint:written", "checkpoint:renamed", "publish:dem.tif", ... (service/Daemon.hpp).
mapper::FaultHook FaultFromEnvironment() {
  const char* spec = std::getenv("ROVERMAP_FAULT_KILL");
  if (spec == nullptr || *spec == '\0') return {};
  std::string point = spec;
  int count = 1;
  const auto colon = point.rfind(':');
  if (colon != std::string::npos && colon + 1 < point.size() &&
      point.find_first_not_of("0123456789", colon + 1) == std::string::npos) {
    count = std::stoi(point.substr(colon + 1));
    point.resize(colon);
  }
  auto seen = std::make_shared<int>(0);
  return [point, count, seen](std::string_view at) {
    if (at == point && ++*seen >= count) ::raise(SIGKILL);
  };
}

}  // namespace

CLI::App* AddServeCommand(CLI::App* app, ServeArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "serve", "Run the mapping pipeline as a daemon on frames dropped into an inbox");
  cmd->add_option("--inbox", args->inbox, "Inbox directory (docs/design.md section 7)")->required();
  cmd->add_option("--out", args->out, "Output directory (created; holds the checkpoint)")
      ->required();
  cmd->add_option("--reference-dem", args->reference_dem,
                  "Reference DEM (any GeoTIFF GDAL reads, any CRS; band 2 its sigma) the rover's "
                  "recent ground is matched against for the pose graph (docs/graph.md)");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Takes frames/NNNNNN.* with NNNNNN.odom from the inbox in index order once complete,\n"
      "publishes the replay outputs and status.json into OUT (serve.publish_every), journals\n"
      "every frame and snapshots the state in OUT/checkpoint, so a restart resumes where it\n"
      "stopped. SIGTERM/SIGINT: finish the frame, checkpoint, publish what is not out yet,\n"
      "exit 0; a second signal exits at once (1). Exit status: 0 stopped by a signal,\n"
      "1 failure (OUT served by another daemon, cannot write, unusable checkpoint files),\n"
      "2 usage or config error, bad sequence.yaml, or a checkpoint made with another\n"
      "configuration.\n");
  return cmd;
}

int RunServe(const ServeArgs& args) {
  const config::Config cfg =
      config::LoadConfig(args.config.config_file.empty()
                             ? std::nullopt
                             : std::optional<std::filesystem::path>(args.config.config_file),
                         args.config.overrides);
  // The inbox may not exist yet (it is created), but a file in its place would be waited on
  // for ever.
  std::error_code error;
  if (std::filesystem::exists(args.inbox, error) &&
      !std::filesystem::is_directory(args.inbox, error)) {
    throw UsageError("--inbox " + args.inbox + ": not a directory");
  }
  InstallSignalHandlers();
  mapper::DaemonSetup setup;
  setup.inbox = args.inbox;
  setup.out = args.out;
  setup.pipeline = PipelineFrom(cfg);
  setup.serve = cfg.serve;
  setup.eval = cfg.eval;
  setup.graph = GraphSetupFrom(cfg);
  setup.reference_dem = args.reference_dem;
  setup.config_text = config::DumpYaml(cfg);
  setup.log = [](const std::string& line) { std::cerr << line << "\n"; };
  setup.fault = FaultFromEnvironment();
  mapper::Daemon daemon(std::move(setup));
  try {
    if (!daemon.WaitForSequence(g_stop)) return kExitOk;
  } catch (const mapper::ReferenceRequiredError& e) {
    throw io::IoError(e.what());  // exit 1, as replay's
  } catch (const io::IoError& e) {
    throw UsageError(e.what());  // a bad sequence.yaml: exit 2 (docs/design.md §5, §7)
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(e.what());
  }
  try {
    daemon.Resume();
  } catch (const mapper::CheckpointError& e) {
    const std::string what = e.what();
    if (what.find("another configuration") != std::string::npos) throw UsageError(what);
    throw;
  }
  daemon.Run(g_stop);
  return kExitOk;
}

}  // namespace rovermap::apps
