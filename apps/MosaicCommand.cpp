// `rovermap mosaic DEM.tif ... --out MOSAIC.tif`: dem.tif files fused into one COG on a common
// grid, with its report MOSAIC.json beside it; a thin layer over mosaic/.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <system_error>

#include "apps/Commands.hpp"
#include "config/Config.hpp"
#include "io/IoError.hpp"
#include "mosaic/Mosaic.hpp"

namespace rovermap::apps {
namespace {

namespace fs = std::filesystem;

// --out's folder must exist and be writable (checked before any work); the file (and its
// report beside it) may exist only with --force.
void CheckOutputFile(const fs::path& out, const fs::path& report, bool force) {
  std::error_code error;
  if (fs::is_directory(out, error)) throw UsageError("--out " + out.string() + ": a directory");
  if (report == out) {
    throw UsageError("--out " + out.string() +
                     ": the report takes the output's name with .json; name the output .tif");
  }
  const fs::path parent = out.parent_path().empty() ? fs::path(".") : out.parent_path();
  if (!fs::is_directory(parent, error)) {
    throw UsageError("--out " + out.string() + ": no folder " + parent.string());
  }
  if (::access(parent.c_str(), W_OK | X_OK) != 0) {
    throw io::IoError("--out " + out.string() + ": cannot write in " + parent.string() + " (" +
                      std::strerror(errno) + ")");
  }
  for (const fs::path& file : {out, report}) {
    if (fs::exists(file, error) && !force) {
      throw UsageError("--out " + out.string() + ": " + file.string() +
                       " exists (use --force to replace it)");
    }
  }
}

}  // namespace

CLI::App* AddMosaicCommand(CLI::App* app, MosaicArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "mosaic",
      "Fuse dem.tif files (each with its own origin, rotation or UTM zone) into one "
      "co-registered COG mosaic on a common grid");
  cmd->add_option("dems", args->inputs, "Input DEM GeoTIFFs (dem.tif of replay, or mosaics)")
      ->required();
  cmd->add_option("--out", args->out,
                  "Output COG NAME.tif (its report NAME.json is written beside it)")
      ->required();
  cmd->add_flag("--force", args->force, "Replace an existing output and its report");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Bands: 1 elevation (m), 2 sigma (m), 3 summed point count, 4 inputs disagreeing beyond\n"
      "mosaic.disagreement_sigma; nodata NaN. Config keys: mosaic.crs, mosaic.cell_size_m,\n"
      "mosaic.disagreement_sigma, mosaic.tile_cells, mosaic.coregister,\n"
      "mosaic.min_overlap_cells, mosaic.min_information, mosaic.min_improvement,\n"
      "mosaic.max_correction_m, mosaic.max_correction_deg (and registration.* for "
      "co-registration).\n"
      "Prints the report (NAME.json beside NAME.tif) on stdout.\n"
      "Exit status: 0 written, 1 bad or missing input file or cannot write, 2 usage or config\n"
      "error.\n");
  return cmd;
}

int RunMosaic(const MosaicArgs& args) {
  const config::Config cfg = LoadConfigArgs(args.config);
  const fs::path out(args.out);
  const fs::path report = mosaic::MosaicReportPath(out);
  CheckOutputFile(out, report, args.force);
  std::vector<fs::path> inputs(args.inputs.begin(), args.inputs.end());
  mosaic::MosaicResult result;
  try {
    result = mosaic::BuildMosaic(inputs, out, report, cfg.mosaic, cfg.registration);
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(e.what());
  }
  std::cout << mosaic::MosaicReportJson(result, cfg.mosaic);
  const nlohmann::json terrain = WriteMosaicTerrain(out, cfg.terrain);
  if (terrain.value("written", false)) {
    std::cerr << "rovermap: mosaic: terrain layers in " << terrain["file"].get<std::string>()
              << " and " << terrain["preview"].get<std::string>() << ": " << terrain["hazard_cells"]
              << " hazard, " << terrain["uncertain_cells"] << " uncertain, "
              << terrain["benign_cells"] << " benign of " << terrain["known_cells"] << " cells\n";
  } else if (terrain.contains("reason")) {
    std::cerr << "rovermap: mosaic: no terrain layers: " << terrain["reason"].get<std::string>()
              << "\n";
  }
  for (const mosaic::InputReport& input : result.inputs) {
    if (!input.reference && !input.applied && cfg.mosaic.coregister) {
      const bool why = input.status == "refused" || input.status == "no_overlap";
      std::cerr << "rovermap: mosaic: " << input.file << ": placed as it is (" << input.status
                << (why ? ": " + input.reason : "") << ")\n";
    }
  }
  return kExitOk;
}

}  // namespace rovermap::apps
