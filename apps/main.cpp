// rovermap-full, the program behind the `rovermap` command (apps/Launcher.cpp runs it for every
// subcommand but a plain `register`): parses the command line, runs one subcommand, and turns
// typed errors into messages and exit statuses (docs/design.md §5).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <string>

#include "apps/Commands.hpp"
#include "apps/Startup.hpp"
#include "config/ConfigError.hpp"
#include "core/Heap.hpp"
#include "io/IoError.hpp"
#include "io/RegistrationPreview.hpp"

using namespace rovermap::apps;
using namespace rovermap;

int main(int argc, char** argv) {
  // Past a file-size limit (ulimit -f) write() fails with EFBIG, reported like a full disk,
  // instead of the signal killing the process in the middle of a write.
  std::signal(SIGXFSZ, SIG_IGN);
  // OpenMP threads that finish a parallel loop first spin for the others by default; on a shared
  // 2-core machine (a rover's computer runs more than the mapper) the spinning thread takes the
  // core its partner needs (docs/replay.md, "Threads"). libgomp reads OMP_WAIT_POLICY when it is
  // loaded, before main, so the default is set by running this program again with it (once; a
  // user's setting is kept; the launcher sets it before it becomes this program, so the run
  // again is for a direct start). Only for the commands that run many frames: loading the
  // program's libraries again (GDAL's among them) would cost a one-shot command more than
  // spinning does.
  const bool many_frames = RunsManyFrames(argc, argv);
  if (many_frames) RunAgainWithPassiveOpenMp(argv);
  if (many_frames) rovermap::core::KeepFreedMemoryInHeap();
  CLI::App app{"rovermap: incremental DEM mapping from correlation-stereo frames"};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for every subcommand");

  RegisterArgs register_args;
  CLI::App* register_cmd = AddRegisterCommand(&app, &register_args);
  SimulateArgs simulate_args;
  CLI::App* simulate_cmd = AddSimulateCommand(&app, &simulate_args);
  EvalArgs eval_args;
  CLI::App* eval_cmd = AddEvalCommand(&app, &eval_args);
  ReplayArgs replay_args;
  CLI::App* replay_cmd = AddReplayCommand(&app, &replay_args);
  ImportArgs import_args;
  CLI::App* import_cmd = AddImportCommand(&app, &import_args);
  ServeArgs serve_args;
  CLI::App* serve_cmd = AddServeCommand(&app, &serve_args);
  MosaicArgs mosaic_args;
  CLI::App* mosaic_cmd = AddMosaicCommand(&app, &mosaic_args);
  TerrainArgs terrain_args;
  CLI::App* terrain_cmd = AddTerrainCommand(&app, &terrain_args);
  CampaignArgs campaign_args;
  CLI::App* campaign_cmd = AddCampaignCommand(&app, &campaign_args);
  CampaignTaskArgs campaign_task_args;
  CLI::App* campaign_task_cmd = AddCampaignTaskCommand(&app, &campaign_task_args);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help (code 0) or the parse error
    return code == 0 ? kExitOk : kExitUsage;
  }

  return RunReportingErrors([&] {
    if (register_cmd->parsed()) return RunRegister(register_args, io::WriteRegistrationPreview);
    if (simulate_cmd->parsed()) return RunSimulate(simulate_args);
    if (eval_cmd->parsed()) return RunEval(eval_args);
    if (replay_cmd->parsed()) return RunReplay(replay_args);
    if (serve_cmd->parsed()) return RunServe(serve_args);
    if (import_cmd->parsed()) return RunImport(import_args);
    if (mosaic_cmd->parsed()) return RunMosaic(mosaic_args);
    if (terrain_cmd->parsed()) return RunTerrain(terrain_args);
    if (campaign_cmd->parsed()) return RunCampaign(campaign_args);
    if (campaign_task_cmd->parsed()) return RunCampaignTask(campaign_task_args);
    return kExitUsage;
  });
}
