#pragma once
// A campaign: many traverses replayed independently, then one co-registered mosaic of their
// DEMs, as steps that run as Slurm job arrays or as processes on this machine (apps/). This
// module knows the campaign folder, the plan, the task statuses, the summary and the batch
// scripts; it runs nothing itself.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "campaign/CampaignOptions.hpp"

namespace rovermap::campaign {

/// The steps, in order; each waits for the one before to end (Slurm afterany).
enum class Step {
  kReplay,      ///< array: one traverse each
  kMosaicPlan,  ///< one task: the grid and the co-registration (sequential by nature)
  kMosaicPart,  ///< array: campaign.mosaic_tasks bands of tile rows
  kFinish,      ///< one task: the parts into mosaic.tif, and summary.json
};
const char* ToString(Step step);  ///< "replay", "mosaic-plan", "mosaic-part", "finish"
/// @throw std::invalid_argument for an unknown name.
Step StepFromString(const std::string& name);

/// One traverse: its recording and the folder its replay writes (relative to the campaign).
struct Traverse {
  std::string name;             ///< "003-<input's name>"
  std::filesystem::path input;  ///< absolute
};

/// What `rovermap campaign` decided before any task ran (campaign.json).
struct CampaignPlan {
  std::vector<Traverse> traverses;
  int mosaic_tasks = 1;
};

/// Names the traverses after their inputs (made absolute), numbered in order.
/// @throw std::invalid_argument if there is no input.
CampaignPlan MakeCampaignPlan(const std::vector<std::filesystem::path>& inputs,
                              const CampaignOptions& options);
std::string CampaignPlanJson(const CampaignPlan& plan);
/// @throw std::runtime_error naming `file` if the text is not a campaign plan.
CampaignPlan ParseCampaignPlan(const std::string& text, const std::filesystem::path& file);

/// The campaign folder's layout (a contract: docs/design.md §13).
class CampaignLayout {
 public:
  explicit CampaignLayout(std::filesystem::path dir) : dir_(std::move(dir)) {}
  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path Plan() const { return dir_ / "campaign.json"; }
  std::filesystem::path Config() const { return dir_ / "config.yaml"; }
  std::filesystem::path TraverseDir(const Traverse& t) const { return dir_ / "traverses" / t.name; }
  /// A task's status (exit status and error), written when it ends.
  std::filesystem::path Status(Step step, int index) const;
  /// A task's stdout and stderr.
  std::filesystem::path Log(Step step, int index) const;
  std::filesystem::path MosaicPlan() const { return dir_ / "work" / "mosaic-plan.json"; }
  std::filesystem::path MosaicPart(int part) const;
  std::filesystem::path Mosaic() const { return dir_ / "mosaic.tif"; }
  /// Named after the mosaic, as `rovermap mosaic` names it (mosaic::MosaicReportPath).
  std::filesystem::path MosaicReport() const { return dir_ / "mosaic.json"; }
  std::filesystem::path Summary() const { return dir_ / "summary.json"; }
  std::filesystem::path SlurmDir() const { return dir_ / "slurm"; }

 private:
  std::filesystem::path dir_;
};

/// How a task ended.
struct TaskStatus {
  int exit_status = 0;
  std::string error;  ///< the message, when it failed
};
std::string TaskStatusJson(const TaskStatus& status);
/// A task's status file; `found` is false when the task left none (killed, or never ran).
struct ReadStatus {
  bool found = false;
  TaskStatus status;
};
ReadStatus ReadTaskStatus(const std::filesystem::path& file);

/// summary.json: per traverse its status (and why it failed), frames, fallbacks, drift and its
/// mosaic correction; the mosaic's size and which traverses it holds. No timings and no absolute
/// campaign paths, so that a campaign run anywhere, by Slurm or locally, gives the same text.
/// `mosaic_error`: why the mosaic could not be built ("" when it was); `terrain`: what was
/// written of its terrain layers (apps::WriteMosaicTerrain), put under `mosaic` when not null.
std::string CampaignSummaryJson(const CampaignLayout& layout, const CampaignPlan& plan,
                                const std::string& mosaic_error,
                                const nlohmann::json& terrain = nullptr);

/// The batch scripts of the four steps (sbatch files; the arrays by SLURM_ARRAY_TASK_ID), each
/// running `rovermap campaign-task STEP DIR INDEX`.
struct BatchScript {
  Step step;
  std::string file_name;  ///< in CampaignLayout::SlurmDir()
  std::string text;
};
std::vector<BatchScript> SlurmScripts(const CampaignLayout& layout, const CampaignPlan& plan,
                                      const CampaignOptions& options,
                                      const std::filesystem::path& rovermap);

/// Tasks of a step (the array size).
int TaskCount(Step step, const CampaignPlan& plan);

}  // namespace rovermap::campaign
