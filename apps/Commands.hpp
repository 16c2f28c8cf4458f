#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config/Config.hpp"
#include "io/FrameSource.hpp"
#include "io/RegistrationPreview.hpp"
#include "mapper/GraphRun.hpp"
#include "mapper/Mapper.hpp"
#include "terrain/TerrainOptions.hpp"

namespace rovermap::apps {

/// Exit statuses (docs/design.md §5).
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  ///< bad input data, failed registration, I/O
constexpr int kExitUsage = 2;    ///< usage or config error

/// `--config FILE` and repeated `--set key=value`, taken by every subcommand.
struct ConfigArgs {
  std::string config_file;
  std::vector<std::string> overrides;
};
void AddConfigOptions(CLI::App* cmd, ConfigArgs* args);
/// config::LoadConfig of `--config` (when given) and the `--set` overrides.
/// @throw config::ConfigError as LoadConfig.
config::Config LoadConfigArgs(const ConfigArgs& args);

struct RegisterArgs {
  ConfigArgs config;
  std::string source;
  std::string target;
  std::string init;     ///< "rx ry rz tx ty tz" (rad, m)
  std::string preview;  ///< PNG of the alignment before and after (optional)
};
CLI::App* AddRegisterCommand(CLI::App* app, RegisterArgs* args);
/// Writes the --preview PNG (io::WriteRegistrationPreview in rovermap-full; the launcher, which
/// loads no image codecs, hands --preview to rovermap-full and passes none).
using PreviewWriter =
    std::function<void(const std::filesystem::path& png, const registration::PointCloud& source,
                       const registration::PointCloud& target, const Eigen::Isometry3d& T_init,
                       const Eigen::Isometry3d& T_estimate, const io::PreviewOptions& options)>;
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunRegister(const RegisterArgs& args, const PreviewWriter& write_preview);

struct EvalArgs {
  ConfigArgs config;
  std::vector<std::string> estimates;  ///< trajectory files (TUM or KITTI)
  std::string groundtruth;
  std::string format = "auto";  ///< auto|tum|kitti, for every trajectory file
  std::string dem;              ///< DEM GeoTIFF to judge
  std::string reference;        ///< reference terrain GeoTIFF
  std::string plot_dir;         ///< PNGs go here (optional)
};
CLI::App* AddEvalCommand(CLI::App* app, EvalArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunEval(const EvalArgs& args);

struct SimulateArgs {
  ConfigArgs config;
  std::string out;     ///< sequence directory to write
  bool force = false;  ///< write into a non-empty directory
};
CLI::App* AddSimulateCommand(CLI::App* app, SimulateArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunSimulate(const SimulateArgs& args);

struct ReplayArgs {
  ConfigArgs config;
  std::string sequence;       ///< sequence directory (docs/design.md §4) or ROS 1 bag
  std::string out;            ///< output directory
  bool force = false;         ///< write into a non-empty directory
  std::string reference_dem;  ///< a reference DEM to match the rover's DEM against ("" = none)
};
CLI::App* AddReplayCommand(CLI::App* app, ReplayArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunReplay(const ReplayArgs& args);

struct ImportArgs {
  ConfigArgs config;
  std::string recording;  ///< a ROS 1 bag (or a sequence directory)
  std::string out;        ///< sequence directory to write
  bool force = false;     ///< replace a non-empty directory
};
CLI::App* AddImportCommand(CLI::App* app, ImportArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunImport(const ImportArgs& args);

struct MosaicArgs {
  ConfigArgs config;
  std::vector<std::string> inputs;  ///< dem.tif files (or mosaics)
  std::string out;                  ///< output COG; mosaic.json goes beside it
  bool force = false;               ///< replace an existing output
};
CLI::App* AddMosaicCommand(CLI::App* app, MosaicArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunMosaic(const MosaicArgs& args);

struct TerrainArgs {
  ConfigArgs config;
  std::string dem;     ///< any north-up DEM GeoTIFF in metres (dem.tif, a mosaic, another tool's)
  std::string out;     ///< folder for terrain.tif and terrain.png
  bool force = false;  ///< replace them
};
CLI::App* AddTerrainCommand(CLI::App* app, TerrainArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunTerrain(const TerrainArgs& args);
/// The terrain layers of a mosaic NAME.tif, beside it: NAME_terrain.tif and NAME_terrain.png
/// (io::WriteTerrainTiled, bounded memory), unless `options.enabled` is false. A mosaic
/// smaller than the footprint gets none, and says why. @return what summary.json says of
/// them: `written`, the counts, or `reason`.
/// @throw io::IoError naming the file if an output cannot be written.
nlohmann::json WriteMosaicTerrain(const std::filesystem::path& mosaic,
                                  const terrain::TerrainOptions& options);

struct CampaignArgs {
  ConfigArgs config;
  std::vector<std::string> inputs;  ///< recordings (sequence directories or bags)
  std::string list;                 ///< a file naming more, one per line
  std::string out;                  ///< the campaign folder
  bool local = false;               ///< run the tasks here (the default)
  bool slurm = false;               ///< submit them with sbatch
  bool wait = false;                ///< with slurm: until the campaign has ended
  int jobs = 0;                     ///< local tasks at once; 0 = from the cores
};
CLI::App* AddCampaignCommand(CLI::App* app, CampaignArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError; returns the exit status.
int RunCampaign(const CampaignArgs& args);

/// `rovermap campaign-task STEP DIR INDEX`: one task of a campaign (internal; what the Slurm
/// scripts and --local run).
struct CampaignTaskArgs {
  std::string step;
  std::string dir;
  int index = 0;
};
CLI::App* AddCampaignTaskCommand(CLI::App* app, CampaignTaskArgs* args);
/// Never throws for the step's own errors: they go to its status file and log.
int RunCampaignTask(const CampaignTaskArgs& args);

/// Runs `command`, turning the typed errors into a message on stderr and the exit status of
/// docs/design.md §5, as main does; the message (without "rovermap: ") also goes to `message`.
int RunReportingErrors(const std::function<int()>& command, std::string* message = nullptr);

/// Opens a recording (io::OpenFrameSource with the `bag.` options) and tells stderr, as
/// `command`, what it skipped. @throw io::IoError naming the recording.
std::unique_ptr<io::FrameSource> OpenRecording(const std::string& path, const config::Config& cfg,
                                               const std::string& command);

struct ServeArgs {
  ConfigArgs config;
  std::string inbox;          ///< inbox directory (docs/design.md §7)
  std::string out;            ///< output directory (holds the checkpoint and the lock)
  std::string reference_dem;  ///< reference DEM for the pose graph (empty: none)
};
CLI::App* AddServeCommand(CLI::App* app, ServeArgs* args);
/// Throws config::ConfigError / io::IoError / UsageError / mapper::DaemonBusyError; returns the
/// exit status.
int RunServe(const ServeArgs& args);

/// `--out DIR` before any work: DIR must be a directory or creatable (its nearest existing
/// ancestor a directory we may write into) and, unless `force`, empty. @return true if DIR
/// holds files (then `force` was given). @throw UsageError if DIR is not a directory, or is not
/// empty without --force (`force_hint`: what --force does); io::IoError if DIR cannot be created.
bool CheckOutputDirectory(const std::filesystem::path& out, bool force,
                          const std::string& force_hint);

/// The pipeline's options (mapper, registration, stereo, dem, octomap) out of a configuration:
/// replay and serve run the same pipeline.
mapper::PipelineOptions PipelineFrom(const config::Config& cfg);
/// The options of the pose graph's sources (replay and serve).
mapper::GraphSetup GraphSetupFrom(const config::Config& cfg);

/// A command-line value that parses but makes no sense (exit 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace rovermap::apps
