// `rovermap simulate --out DIR`: a synthetic sequence (docs/design.md §4) with ground truth.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "apps/Commands.hpp"
#include "config/Config.hpp"
#include "core/Stopwatch.hpp"
#include "sim/Simulator.hpp"
#include "sim/TerrainGeoTiff.hpp"

namespace rovermap::apps {

CLI::App* AddSimulateCommand(CLI::App* app, SimulateArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "simulate",
      "Write a synthetic sequence (terrain, rover, stereo or cloud frames, odometry with "
      "errors, ground truth); options under sim. in the config");
  cmd->add_option("--out", args->out, "Output sequence directory (created)")->required();
  cmd->add_flag("--force", args->force,
                "Write into a non-empty DIR (its frames/ directory is replaced)");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Prints a JSON summary on stdout; progress on stderr.\n"
      "Exit status: 0 written, 1 cannot write, 2 usage or config error.\n");
  return cmd;
}

int RunSimulate(const SimulateArgs& args) {
  const config::Config cfg =
      config::LoadConfig(args.config.config_file.empty()
                             ? std::nullopt
                             : std::optional<std::filesystem::path>(args.config.config_file),
                         args.config.overrides);
  namespace fs = std::filesystem;
  const fs::path out(args.out);
  if (CheckOutputDirectory(out, args.force, "replace its sequence")) {
    std::error_code error;
    fs::remove_all(out / "frames", error);
  }

  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<sim::Simulator> simulator;
  try {
    simulator = std::make_unique<sim::Simulator>(cfg.sim);
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(e.what());
  }
  const bool tty = isatty(2);
  const sim::SimulateResult r =
      simulator->WriteSequence(out, [&](std::size_t done, std::size_t total) {
        if (tty || done == total) {
          std::cerr << "\rsimulate: frame " << done << "/" << total << std::flush;
          if (done == total) std::cerr << "\n";
        }
      });
  // The true terrain, on the DEM's grid (dem.cell_size_m) and with dem.tif's conventions.
  const io::GeoTiffInfo tif = sim::WriteTerrainGeoTiff(out / "terrain.tif", *simulator, cfg.dem);
  // An orbital product's stand-in, for replay --reference-dem (docs/graph.md).
  std::optional<io::GeoTiffInfo> reference;
  if (cfg.sim.reference_post_m > 0.0) {
    reference = sim::WriteReferenceDem(out / "reference_dem.tif", *simulator);
  }
  const double total_ms = core::MsSince(start);
  nlohmann::json summary = {
      {"out", args.out},
      {"frames", r.frames},
      {"sensor", cfg.sim.sensor == sim::SensorKind::kCloud ? "cloud" : "stereo"},
      {"seed", cfg.sim.seed},
      {"path_length_m", r.path_length_m},
      {"final_odometry_error_m", r.final_odometry_error_m},
      {"final_heading_error_deg", r.final_heading_error_deg},
      {"points", r.points},
      {"outliers", r.outliers},
      {"render_ms", r.render_ms},
      {"frames_per_second", r.render_ms > 0 ? 1000.0 * r.frames / r.render_ms : 0.0},
      {"time_ms", total_ms},
      {"terrain_tif", (out / "terrain.tif").string()},
      {"terrain_tif_cells", tif.valid_cells}};
  if (reference) {
    summary["reference_dem_tif"] = (out / "reference_dem.tif").string();
    summary["reference_dem_cells"] = reference->valid_cells;
  }
  std::cout << summary.dump(2) << "\n";
  return kExitOk;
}

}  // namespace rovermap::apps
