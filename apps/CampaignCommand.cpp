// `rovermap campaign RECORDING... --out DIR`: every traverse replayed, then one co-registered
// mosaic of their DEMs, as Slurm job arrays (--slurm) or as processes on this machine (--local).
// Both run the same steps (`rovermap campaign-task STEP DIR INDEX`), so they give the same files.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "apps/Commands.hpp"
#include "campaign/Campaign.hpp"
#include "config/Config.hpp"
#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "mosaic/Mosaic.hpp"

extern char** environ;

namespace rovermap::apps {
namespace {

namespace fs = std::filesystem;
using campaign::CampaignLayout;
using campaign::CampaignPlan;
using campaign::Step;

constexpr Step kSteps[] = {Step::kReplay, Step::kMosaicPlan, Step::kMosaicPart, Step::kFinish};

// The inputs: the positional ones, then --list's lines (blank lines and # comments skipped).
std::vector<fs::path> Inputs(const CampaignArgs& args) {
  std::vector<fs::path> inputs(args.inputs.begin(), args.inputs.end());
  if (!args.list.empty()) {
    std::ifstream in(args.list);
    if (!in) throw io::IoError(args.list + ": cannot read the list of traverses");
    std::string line;
    while (std::getline(in, line)) {
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      const auto last = line.find_last_not_of(" \t\r");
      inputs.emplace_back(line.substr(first, last - first + 1));
    }
  }
  if (inputs.empty()) throw UsageError("campaign: no traverse (give recordings or --list FILE)");
  for (const fs::path& input : inputs) {
    std::error_code error;
    if (!fs::exists(input, error)) throw io::IoError(input.string() + ": no such recording");
  }
  return inputs;
}

// Values that go into #SBATCH lines must be one word.
void CheckSbatchWord(const std::string& key, const std::string& value) {
  for (const char c : value) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\'' || c == '"' || c == '\\') {
      throw config::ConfigError(key + ": '" + value + "' must be one word (no blanks or quotes)");
    }
  }
}

fs::path ThisExecutable() {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  if (error) throw io::IoError("/proc/self/exe: cannot find the rovermap executable");
  return self;
}

// Starts `argv` (PATH searched), its stdout on `stdout_fd` when >= 0. @return its pid.
// @throw io::IoError if it cannot be started.
pid_t Spawn(const std::vector<std::string>& argv, int stdout_fd = -1) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdout_fd >= 0) posix_spawn_file_actions_adddup2(&actions, stdout_fd, 1);
  pid_t pid = 0;
  const int spawned =
      ::posix_spawnp(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw io::IoError(argv[0] + ": cannot run it (" + std::strerror(spawned) + ")");
  return pid;
}

// Runs `argv` (PATH searched) and returns its stdout in `out`. @return the exit status, 128 +
// signal if it was killed. @throw io::IoError if it cannot be started.
int RunProcess(const std::vector<std::string>& argv, std::string* out) {
  int pipe_fds[2] = {-1, -1};
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) throw io::IoError(argv[0] + ": cannot make a pipe");
  pid_t pid = 0;
  try {
    pid = Spawn(argv, pipe_fds[1]);
  } catch (...) {
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    throw;
  }
  ::close(pipe_fds[1]);
  char buffer[4096];
  ssize_t n = 0;
  while ((n = ::read(pipe_fds[0], buffer, sizeof buffer)) > 0 || (n < 0 && errno == EINTR)) {
    if (n > 0) out->append(buffer, static_cast<std::size_t>(n));
  }
  ::close(pipe_fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// After the last step: summary.json on stdout, what failed on stderr; the finish task's status.
int Finished(const CampaignLayout& layout) {
  const campaign::ReadStatus finish = campaign::ReadTaskStatus(layout.Status(Step::kFinish, 0));
  std::error_code error;
  if (!finish.found || !fs::exists(layout.Summary(), error)) {
    std::cerr << "rovermap: campaign: the finish task left no summary (see "
              << layout.Log(Step::kFinish, 0).string() << ")\n";
    return kExitFailure;
  }
  const std::string text = io::ReadWholeFile(layout.Summary());
  std::cout << text;
  const nlohmann::json summary = nlohmann::json::parse(text, nullptr, false);
  if (summary.is_object()) {
    for (const nlohmann::json& t : summary.value("traverse", nlohmann::json::array())) {
      if (t.value("status", "") != "ok") {
        std::cerr << "rovermap: campaign: " << t.value("name", "?")
                  << " failed, left out: " << t.value("error", "") << "\n";
      }
    }
    const nlohmann::json mosaic = summary.value("mosaic", nlohmann::json::object());
    if (mosaic.value("status", "") == "ok") {
      std::cerr << "rovermap: campaign: " << summary.value("succeeded", 0) << " of "
                << summary.value("traverses", 0) << " traverses in " << (layout.Mosaic()).string()
                << " (" << mosaic.value("width", 0) << " x " << mosaic.value("height", 0)
                << " cells)\n";
    } else {
      std::cerr << "rovermap: campaign: no mosaic: " << mosaic.value("error", "") << "\n";
    }
  }
  const bool all_ok =
      summary.is_object() && summary.value("failed", nlohmann::json::array()).empty();
  return finish.status.exit_status == kExitOk && all_ok ? kExitOk : kExitFailure;
}

// --local: the tasks of each step as child processes, `jobs` at a time, the steps in order.
int RunLocally(const CampaignLayout& layout, const CampaignPlan& plan, int replay_jobs,
               int mosaic_jobs) {
  const std::string self = ThisExecutable().string();
  for (const Step step : kSteps) {
    const int tasks = campaign::TaskCount(step, plan);
    const int jobs = std::max(1, step == Step::kReplay ? replay_jobs : mosaic_jobs);
    const auto started = std::chrono::steady_clock::now();
    std::map<pid_t, int> running;
    int next = 0;
    int done = 0;
    int failed = 0;
    auto report = [&] {
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      std::cerr << "rovermap: campaign: " << campaign::ToString(step) << " " << done << "/" << tasks
                << (failed > 0 ? " (" + std::to_string(failed) + " failed)" : "") << ", "
                << std::fixed << std::setprecision(1) << seconds << " s\n";
    };
    while (done < tasks) {
      while (next < tasks && static_cast<int>(running.size()) < jobs) {
        const pid_t pid = Spawn({self, "campaign-task", campaign::ToString(step),
                                 layout.dir().string(), std::to_string(next)});
        running[pid] = next++;
      }
      int status = 0;
      const pid_t pid = ::waitpid(-1, &status, 0);
      if (pid < 0) {
        if (errno == EINTR) continue;
        throw io::IoError(std::string("campaign: waiting for a task failed (") +
                          std::strerror(errno) + ")");
      }
      if (running.erase(pid) == 0) continue;
      ++done;
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) ++failed;
      report();
    }
  }
  return Finished(layout);
}

// --slurm: the four batch scripts written and submitted, each step after the one before ends
// (afterany: a failed traverse is left out of the mosaic, not a reason to skip it; every step
// checks what the one before left and the summary says what failed).
int SubmitToSlurm(const CampaignLayout& layout, const CampaignPlan& plan,
                  const campaign::CampaignOptions& options, bool wait) {
  const std::vector<campaign::BatchScript> scripts =
      campaign::SlurmScripts(layout, plan, options, ThisExecutable());
  std::string previous;
  for (const campaign::BatchScript& script : scripts) {
    const fs::path file = layout.SlurmDir() / script.file_name;
    io::WriteFileAtomically(file, script.text);
    std::vector<std::string> argv = {"sbatch", "--parsable"};
    if (!previous.empty()) argv.push_back("--dependency=afterany:" + previous);
    const bool last = script.step == Step::kFinish;
    if (last && wait) argv.push_back("--wait");
    argv.push_back(file.string());
    std::string out;
    int status = 0;
    try {
      status = RunProcess(argv, &out);
    } catch (const io::IoError& e) {
      throw io::IoError(std::string(e.what()) + "; is Slurm installed? The scripts are in " +
                        layout.SlurmDir().string());
    }
    const std::string id = out.substr(0, out.find_first_of(";\n"));
    if (id.empty() || (status != 0 && !(last && wait))) {
      throw io::IoError(file.string() + ": sbatch failed (exit status " + std::to_string(status) +
                        "); is Slurm reachable (SLURM_CONF)? The scripts are in " +
                        layout.SlurmDir().string());
    }
    std::cerr << "rovermap: campaign: " << campaign::ToString(script.step) << ": job " << id << " ("
              << campaign::TaskCount(script.step, plan) << " task"
              << (campaign::TaskCount(script.step, plan) > 1 ? "s" : "") << ")\n";
    previous = id;
  }
  return wait ? Finished(layout) : kExitOk;
}

// A task's output goes to its log file, whoever runs it.
void RedirectOutput(const fs::path& log) {
  fs::create_directories(log.parent_path());
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw io::IoError(log.string() + ": cannot write the task's log");
  std::cout.flush();
  std::cerr.flush();
  ::dup2(fd, 1);
  ::dup2(fd, 2);
  ::close(fd);
}

// The traverses whose replay ended well, as the mosaic's inputs (relative to the campaign).
std::vector<fs::path> ReplayedDems(const CampaignLayout& layout, const CampaignPlan& plan) {
  std::vector<fs::path> dems;
  for (std::size_t i = 0; i < plan.traverses.size(); ++i) {
    const campaign::ReadStatus s =
        campaign::ReadTaskStatus(layout.Status(Step::kReplay, static_cast<int>(i)));
    const fs::path dem = fs::path("traverses") / plan.traverses[i].name / "dem.tif";
    std::error_code error;
    if (s.found && s.status.exit_status == 0 && fs::exists(dem, error)) dems.push_back(dem);
  }
  return dems;
}

int RunStep(Step step, const CampaignLayout& layout, const CampaignPlan& plan, int index,
            const config::Config& cfg) {
  switch (step) {
    case Step::kReplay: {
      if (index < 0 || index >= static_cast<int>(plan.traverses.size())) {
        throw UsageError("campaign-task replay: no traverse " + std::to_string(index));
      }
      const campaign::Traverse& t = plan.traverses[static_cast<std::size_t>(index)];
      ReplayArgs replay;
      replay.config.config_file = layout.Config().string();
      replay.sequence = t.input.string();
      replay.out = layout.TraverseDir(t).string();
      replay.force = true;  // a task run again (requeued) replaces what it left
      return RunReplay(replay);
    }
    case Step::kMosaicPlan: {
      const std::vector<fs::path> dems = ReplayedDems(layout, plan);
      if (dems.empty()) throw io::IoError("campaign: no traverse was replayed; no mosaic");
      const mosaic::MosaicPlan mosaic_plan = mosaic::PlanMosaic(dems, cfg.mosaic, cfg.registration);
      io::WriteFileAtomically(layout.MosaicPlan(), mosaic::MosaicPlanJson(mosaic_plan));
      return kExitOk;
    }
    case Step::kMosaicPart: {
      const mosaic::MosaicPlan mosaic_plan =
          mosaic::ParseMosaicPlan(io::ReadWholeFile(layout.MosaicPlan()), layout.MosaicPlan());
      mosaic::FuseMosaicPart(mosaic_plan, index, plan.mosaic_tasks, layout.MosaicPart(index),
                             cfg.mosaic);
      return kExitOk;
    }
    case Step::kFinish: {
      std::string mosaic_error;
      nlohmann::json terrain;
      try {
        const mosaic::MosaicPlan mosaic_plan =
            mosaic::ParseMosaicPlan(io::ReadWholeFile(layout.MosaicPlan()), layout.MosaicPlan());
        mosaic::AssembleMosaic(
            mosaic_plan, plan.mosaic_tasks, [&](int part) { return layout.MosaicPart(part); },
            layout.Mosaic(), layout.MosaicReport(), cfg.mosaic);
        for (int part = 0; part < plan.mosaic_tasks; ++part) {
          std::error_code ignored;
          fs::remove(layout.MosaicPart(part), ignored);
        }
        terrain = WriteMosaicTerrain(layout.Mosaic(), cfg.terrain);
      } catch (const std::exception& e) {
        const campaign::ReadStatus planned =
            campaign::ReadTaskStatus(layout.Status(Step::kMosaicPlan, 0));
        mosaic_error = planned.found && planned.status.exit_status != 0
                           ? "mosaic-plan: " + planned.status.error
                           : e.what();
        std::cerr << "rovermap: campaign: no mosaic: " << mosaic_error << "\n";
      }
      const std::string summary =
          campaign::CampaignSummaryJson(layout, plan, mosaic_error, terrain);
      io::WriteFileAtomically(layout.Summary(), summary);
      return mosaic_error.empty() ? kExitOk : kExitFailure;
    }
  }
  return kExitUsage;
}

}  // namespace

CLI::App* AddCampaignCommand(CLI::App* app, CampaignArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "campaign",
      "Replay many traverses and mosaic their DEMs: as Slurm job arrays (--slurm) or on this "
      "machine (--local, the default)");
  cmd->add_option("recordings", args->inputs,
                  "Sequence directories or ROS bags, one traverse each");
  cmd->add_option("--list", args->list, "A file naming one recording per line (# comments)");
  cmd->add_option("--out", args->out, "Campaign folder to create (must not exist or be empty)")
      ->required();
  cmd->add_flag("--local", args->local, "Run the tasks here, in parallel (the default)");
  cmd->add_flag("--slurm", args->slurm, "Submit the tasks as Slurm job arrays (sbatch)");
  cmd->add_flag("--wait", args->wait, "With --slurm: wait until the campaign has ended");
  cmd->add_option("--jobs", args->jobs,
                  "With --local: tasks at once (0 = cores / campaign.cpus_per_task for replays, "
                  "cores for the mosaic)")
      ->check(CLI::NonNegativeNumber);
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Writes DIR/campaign.json, config.yaml, traverses/NNN-NAME/ (one replay output each),\n"
      "mosaic.tif + mosaic.json, summary.json, logs/ and slurm/. Steps: replay (array),\n"
      "mosaic-plan, mosaic-part (array of campaign.mosaic_tasks), finish; each after the one\n"
      "before has ended. Config keys: campaign.* (and every replay and mosaic key).\n"
      "Exit status: 0 every traverse and the mosaic done (with --slurm and no --wait: submitted),\n"
      "1 a traverse or the mosaic failed (summary.json says which and why) or Slurm refused,\n"
      "2 usage or config error.\n");
  return cmd;
}

CLI::App* AddCampaignTaskCommand(CLI::App* app, CampaignTaskArgs* args) {
  CLI::App* cmd = app->add_subcommand("campaign-task", "One task of a campaign (run by campaign)");
  cmd->group("");  // internal: not listed in the help
  cmd->add_option("step", args->step, "replay | mosaic-plan | mosaic-part | finish")->required();
  cmd->add_option("dir", args->dir, "The campaign folder")->required();
  cmd->add_option("index", args->index, "The task's index in its step's array")->required();
  return cmd;
}

int RunCampaign(const CampaignArgs& args) {
  const config::Config cfg = LoadConfigArgs(args.config);
  CheckSbatchWord("campaign.partition", cfg.campaign.partition);
  CheckSbatchWord("campaign.account", cfg.campaign.account);
  if (args.local && args.slurm)
    throw UsageError("campaign: --local and --slurm exclude each other");
  if (args.wait && !args.slurm) throw UsageError("campaign: --wait goes with --slurm");
  const std::vector<fs::path> inputs = Inputs(args);
  CheckOutputDirectory(args.out, false, "");
  CampaignPlan plan;
  try {
    plan = campaign::MakeCampaignPlan(inputs, cfg.campaign);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const CampaignLayout layout(fs::absolute(args.out).lexically_normal());
  for (const fs::path& dir : {layout.dir() / "traverses", layout.dir() / "work",
                              layout.dir() / "logs", layout.SlurmDir()}) {
    fs::create_directories(dir);
  }
  io::WriteFileAtomically(layout.Config(), config::DumpYaml(cfg));
  io::WriteFileAtomically(layout.Plan(), campaign::CampaignPlanJson(plan));
  if (args.slurm) return SubmitToSlurm(layout, plan, cfg.campaign, args.wait);
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int replay_jobs =
      args.jobs > 0 ? args.jobs : std::max(1, cores / cfg.campaign.cpus_per_task);
  const int mosaic_jobs = args.jobs > 0 ? args.jobs : cores;
  return RunLocally(layout, plan, replay_jobs, mosaic_jobs);
}

int RunCampaignTask(const CampaignTaskArgs& args) {
  const Step step = [&] {
    try {
      return campaign::StepFromString(args.step);
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
  }();
  const CampaignLayout absolute(fs::absolute(args.dir).lexically_normal());
  const CampaignPlan plan = [&] {
    try {
      return campaign::ParseCampaignPlan(io::ReadWholeFile(absolute.Plan()), absolute.Plan());
    } catch (const std::runtime_error& e) {
      throw io::IoError(e.what());
    }
  }();
  // Relative paths from here on: the campaign folder can move, and two campaigns of the same
  // recordings write the same files (mosaic.json names its inputs).
  if (::chdir(absolute.dir().c_str()) != 0) {
    throw io::IoError(absolute.dir().string() + ": cannot enter the campaign folder");
  }
  const CampaignLayout layout(".");
  RedirectOutput(layout.Log(step, args.index));
  std::string error;
  const int status = RunReportingErrors(
      [&] {
        const config::Config cfg = config::LoadConfig(layout.Config(), {});
        return RunStep(step, layout, plan, args.index, cfg);
      },
      &error);
  io::WriteFileAtomically(layout.Status(step, args.index),
                          campaign::TaskStatusJson({status, error}));
  return status;
}

}  // namespace rovermap::apps
