#include "campaign/Campaign.hpp"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::campaign {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kPlanFormat = "rovermap campaign 1";

// A JSON file, or null when it is missing, unreadable or not JSON.
json ReadJson(const fs::path& file) {
  try {
    return json::parse(io::ReadWholeFile(file), nullptr, /*allow_exceptions=*/false);
  } catch (const io::IoError&) {
    return nullptr;
  }
}

// A name that is safe in a path and a shell word: letters, digits, '-', '_' and '.'.
std::string SafeName(const std::string& name) {
  std::string out;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.';
    out += ok ? c : '_';
  }
  return out.empty() || out == "." || out == ".." ? "traverse" : out;
}

std::string Numbered(int index, const std::string& what) {
  char number[16];
  std::snprintf(number, sizeof number, "%03d", index);
  return std::string(number) + (what.empty() ? "" : "-" + what);
}

// A word for bash, single-quoted.
std::string ShellQuote(const std::string& word) {
  std::string out = "'";
  for (const char c : word) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

json Pick(const json& from, const std::initializer_list<const char*> keys) {
  json out = json::object();
  if (!from.is_object()) return out;
  for (const char* key : keys) {
    if (from.contains(key)) out[key] = from[key];
  }
  return out;
}

json MetricOf(const json& replay, const char* trajectory) {
  const json* m = &replay;
  for (const char* key : {"metrics", trajectory, "ate_rmse_origin_m"}) {
    if (!m->is_object() || !m->contains(key)) return nullptr;
    m = &(*m)[key];
  }
  return *m;
}

}  // namespace

const char* ToString(Step step) {
  switch (step) {
    case Step::kReplay:
      return "replay";
    case Step::kMosaicPlan:
      return "mosaic-plan";
    case Step::kMosaicPart:
      return "mosaic-part";
    case Step::kFinish:
      return "finish";
  }
  return "?";
}

Step StepFromString(const std::string& name) {
  for (const Step step : {Step::kReplay, Step::kMosaicPlan, Step::kMosaicPart, Step::kFinish}) {
    if (name == ToString(step)) return step;
  }
  throw std::invalid_argument("campaign step '" + name +
                              "': not one of replay, mosaic-plan, mosaic-part, finish");
}

CampaignPlan MakeCampaignPlan(const std::vector<fs::path>& inputs, const CampaignOptions& options) {
  if (inputs.empty()) throw std::invalid_argument("campaign: no traverse to replay");
  CampaignPlan plan;
  plan.mosaic_tasks = std::max(1, options.mosaic_tasks);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const fs::path input = fs::absolute(inputs[i]).lexically_normal();
    std::string stem = input.filename().empty() ? input.parent_path().filename().string()
                                                : input.filename().string();
    // A bag file's traverse is named without its extension (ROS 1 .bag, ROS 2 .mcap or .db3).
    const fs::path extension = input.extension();
    if (extension == ".bag" || extension == ".mcap" || extension == ".db3") {
      stem = input.stem().string();
    }
    plan.traverses.push_back({Numbered(static_cast<int>(i), SafeName(stem)), input});
  }
  return plan;
}

std::string CampaignPlanJson(const CampaignPlan& plan) {
  json traverses = json::array();
  for (const Traverse& t : plan.traverses) {
    traverses.push_back({{"name", t.name}, {"input", t.input.string()}});
  }
  const json out = {
      {"format", kPlanFormat}, {"mosaic_tasks", plan.mosaic_tasks}, {"traverses", traverses}};
  return out.dump(2) + "\n";
}

CampaignPlan ParseCampaignPlan(const std::string& text, const fs::path& file) {
  CampaignPlan plan;
  try {
    const json j = json::parse(text);
    if (j.at("format").get<std::string>() != kPlanFormat) {
      throw std::runtime_error(file.string() + ": not a " + kPlanFormat + " plan");
    }
    plan.mosaic_tasks = j.at("mosaic_tasks").get<int>();
    for (const json& t : j.at("traverses")) {
      plan.traverses.push_back({t.at("name").get<std::string>(), t.at("input").get<std::string>()});
    }
  } catch (const json::exception& e) {
    throw std::runtime_error(file.string() + ": not a campaign plan (" + e.what() + ")");
  }
  if (plan.traverses.empty() || plan.mosaic_tasks < 1) {
    throw std::runtime_error(file.string() + ": not a campaign plan (no traverse or no task)");
  }
  return plan;
}

fs::path CampaignLayout::Status(Step step, int index) const {
  return dir_ / "work" / (std::string(ToString(step)) + "-" + Numbered(index, "") + ".status.json");
}

fs::path CampaignLayout::Log(Step step, int index) const {
  return dir_ / "logs" / (std::string(ToString(step)) + "-" + Numbered(index, "") + ".log");
}

fs::path CampaignLayout::MosaicPart(int part) const {
  return dir_ / "work" / ("mosaic-part-" + Numbered(part, "") + ".tif");
}

std::string TaskStatusJson(const TaskStatus& status) {
  return json({{"exit_status", status.exit_status}, {"error", status.error}}).dump() + "\n";
}

ReadStatus ReadTaskStatus(const fs::path& file) {
  ReadStatus out;
  const json j = ReadJson(file);
  if (!j.is_object() || !j.contains("exit_status")) return out;
  out.found = true;
  out.status.exit_status = j.value("exit_status", 1);
  out.status.error = j.value("error", std::string());
  return out;
}

int TaskCount(Step step, const CampaignPlan& plan) {
  switch (step) {
    case Step::kReplay:
      return static_cast<int>(plan.traverses.size());
    case Step::kMosaicPart:
      return plan.mosaic_tasks;
    default:
      return 1;
  }
}

std::string CampaignSummaryJson(const CampaignLayout& layout, const CampaignPlan& plan,
                                const std::string& mosaic_error, const nlohmann::json& terrain) {
  const json mosaic_report = ReadJson(layout.MosaicReport());
  json traverses = json::array();
  int succeeded = 0;
  long frames = 0;
  long fallbacks = 0;
  std::vector<std::string> failed;
  for (std::size_t i = 0; i < plan.traverses.size(); ++i) {
    const Traverse& t = plan.traverses[i];
    const ReadStatus status = ReadTaskStatus(layout.Status(Step::kReplay, static_cast<int>(i)));
    const fs::path dir = layout.TraverseDir(t);
    const json replay = ReadJson(dir / "summary.json");
    json entry = {
        {"name", t.name}, {"input", t.input.string()}, {"output", fs::path("traverses") / t.name}};
    const bool ok = status.found && status.status.exit_status == 0 && replay.is_object();
    if (!ok) {
      entry["status"] = "failed";
      entry["exit_status"] = status.found ? json(status.status.exit_status) : json(nullptr);
      entry["error"] =
          status.found
              ? status.status.error
              : "no status: the task was killed or never ran (see " +
                    fs::relative(layout.Log(Step::kReplay, static_cast<int>(i)), layout.dir())
                        .string() +
                    " and the scheduler's log)";
      failed.push_back(t.name);
      traverses.push_back(entry);
      continue;
    }
    ++succeeded;
    entry["status"] = "ok";
    entry.update(Pick(replay, {"frames", "registered", "partial", "fallbacks", "bad_frames",
                               "distance_m", "final_correction", "odometry_bias"}));
    frames += replay.value("frames", 0L);
    fallbacks += replay.value("fallbacks", 0L);
    entry["ate_rmse_origin_m"] = {{"registered", MetricOf(replay, "registered")},
                                  {"odometry", MetricOf(replay, "odometry")}};
    json placed = nullptr;
    if (mosaic_report.is_object() && mosaic_report.contains("inputs")) {
      const std::string dem = (fs::path("traverses") / t.name / "dem.tif").string();
      for (const json& input : mosaic_report["inputs"]) {
        if (input.value("file", std::string()) == dem) {
          placed = Pick(input, {"status", "reason", "applied", "translation_m", "rotation_deg",
                                "overlap_cells", "inlier_ratio", "disagreement_before",
                                "disagreement_after", "rms_before_m", "rms_after_m"});
        }
      }
    }
    entry["mosaic"] = placed;
    traverses.push_back(entry);
  }
  json mosaic = {{"status", mosaic_error.empty() ? "ok" : "failed"}};
  if (!mosaic_error.empty()) mosaic["error"] = mosaic_error;
  if (mosaic_error.empty() && mosaic_report.is_object()) {
    mosaic["file"] = "mosaic.tif";
    mosaic["report"] = "mosaic.json";
    mosaic.update(Pick(mosaic_report, {"width", "height", "cell_size_m", "valid_cells", "tiles"}));
    mosaic["traverses"] = mosaic_report.contains("inputs") ? mosaic_report["inputs"].size() : 0;
    if (!terrain.is_null()) mosaic["terrain"] = terrain;
  }
  const json out = {{"traverses", plan.traverses.size()},
                    {"succeeded", succeeded},
                    {"failed", failed},
                    {"frames", frames},
                    {"fallbacks", fallbacks},
                    {"mosaic", mosaic},
                    {"traverse", traverses}};
  return out.dump(2) + "\n";
}

std::vector<BatchScript> SlurmScripts(const CampaignLayout& layout, const CampaignPlan& plan,
                                      const CampaignOptions& options, const fs::path& rovermap) {
  std::vector<BatchScript> scripts;
  for (const Step step : {Step::kReplay, Step::kMosaicPlan, Step::kMosaicPart, Step::kFinish}) {
    const bool replay = step == Step::kReplay;
    const int tasks = TaskCount(step, plan);
    const bool array = step == Step::kReplay || step == Step::kMosaicPart;
    std::ostringstream s;
    s << "#!/bin/bash\n";
    s << "#SBATCH --job-name=rovermap-" << ToString(step) << "\n";
    if (array) s << "#SBATCH --array=0-" << tasks - 1 << "\n";
    s << "#SBATCH --ntasks=1\n";
    s << "#SBATCH --cpus-per-task=" << (replay ? std::max(1, options.cpus_per_task) : 1) << "\n";
    s << "#SBATCH --mem=" << (replay ? options.memory_mb : options.mosaic_memory_mb) << "M\n";
    if (options.time_limit_min > 0) s << "#SBATCH --time=" << options.time_limit_min << "\n";
    if (!options.partition.empty()) s << "#SBATCH --partition=" << options.partition << "\n";
    if (!options.account.empty()) s << "#SBATCH --account=" << options.account << "\n";
    // The scheduler's own messages (a task killed for memory or time); the task's output goes to
    // logs/ as it does without Slurm.
    s << "#SBATCH --output=" << (layout.SlurmDir() / ToString(step)).string()
      << (array ? "-%a" : "") << ".out\n";
    s << "exec " << ShellQuote(rovermap.string()) << " campaign-task " << ToString(step) << " "
      << ShellQuote(layout.dir().string()) << " " << (array ? "\"$SLURM_ARRAY_TASK_ID\"" : "0")
      << "\n";
    scripts.push_back({step, std::string(ToString(step)) + ".sbatch", s.str()});
  }
  return scripts;
}

}  // namespace rovermap::campaign
