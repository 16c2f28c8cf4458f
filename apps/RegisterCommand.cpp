// `rovermap register SOURCE TARGET [--init "rx ry rz tx ty tz"]`: one JSON object on stdout.
#include <chrono>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/Commands.hpp"
#include "config/Config.hpp"
#include "core/Stopwatch.hpp"
#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "io/RegistrationPreview.hpp"
#include "registration/Icp.hpp"

namespace rovermap::apps {
namespace {

using Clock = std::chrono::steady_clock;
using core::MsSince;

Eigen::Isometry3d ParseInit(const std::string& text) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (text.empty()) return T;
  std::istringstream in(text);
  double v[6];
  for (double& x : v)
    if (!(in >> x) || !std::isfinite(x))
      throw UsageError("--init: expected 6 numbers \"rx ry rz tx ty tz\" (rad, m), got \"" + text +
                       "\"");
  std::string extra;
  if (in >> extra) throw UsageError("--init: more than 6 values in \"" + text + "\"");
  const Eigen::Vector3d r(v[0], v[1], v[2]);
  if (r.norm() > 0.0) T.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[3], v[4], v[5]);
  return T;
}

registration::PointCloud LoadCloud(const std::string& path) {
  registration::PointCloud cloud = io::ReadPointCloud(path);
  if (cloud.size() < 3)
    throw io::IoError(path + ": need at least 3 points, found " + std::to_string(cloud.size()));
  return cloud;
}

nlohmann::json MatrixToJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json ToJson(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

CLI::App* AddRegisterCommand(CLI::App* app, RegisterArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "register", "Register SOURCE onto TARGET (Zhang's iterative point matching); prints JSON");
  cmd->add_option("SOURCE", args->source, "Source points (.xyz or .ply)")->required();
  cmd->add_option("TARGET", args->target, "Target points (.xyz or .ply)")->required();
  cmd->add_option("--init", args->init,
                  "Initial T_target_source as \"rx ry rz tx ty tz\" (rotation vector rad, m)");
  cmd->add_option("--preview", args->preview,
                  "Also write a PNG of the alignment before and after (top view of both clouds)");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Exit status: 0 registered (converged or max_iterations), 1 bad input file or failed\n"
      "registration (the JSON still says why), 2 usage or config error.\n");
  return cmd;
}

int RunRegister(const RegisterArgs& args, const PreviewWriter& write_preview) {
  const config::Config cfg =
      config::LoadConfig(args.config.config_file.empty()
                             ? std::nullopt
                             : std::optional<std::filesystem::path>(args.config.config_file),
                         args.config.overrides);
  const Eigen::Isometry3d T_init = ParseInit(args.init);

  const auto load_start = Clock::now();
  registration::PointCloud source = LoadCloud(args.source);
  registration::PointCloud target = LoadCloud(args.target);
  const double load_ms = MsSince(load_start);

  const auto start = Clock::now();
  const registration::IndexedCloud source_index(std::move(source), cfg.registration);
  const registration::IndexedCloud target_index(std::move(target), cfg.registration);
  const registration::RegistrationResult r =
      registration::Register(source_index, target_index, T_init, cfg.registration);
  const double time_ms = MsSince(start);

  const Eigen::AngleAxisd aa(r.T_target_source.linear());
  nlohmann::json trace = nlohmann::json::array();
  for (const auto& it : r.trace) {
    trace.push_back({{"iteration", it.iteration},
                     {"pairs_found", it.pairs_found},
                     {"pairs_kept", it.pairs_kept},
                     {"mean", it.mean_m},
                     {"stddev", it.stddev_m},
                     {"dmax", it.dmax_m},
                     {"branch", registration::ToString(it.branch)},
                     {"rms", it.rms_m},
                     {"step_translation", it.step_translation_m},
                     {"step_rotation_deg", it.step_rotation_deg},
                     {"accelerated", it.accelerated},
                     {"extrapolation_rejected", it.extrapolation_rejected}});
  }
  nlohmann::json out = {{"source", args.source},
                        {"target", args.target},
                        {"matrix", MatrixToJson(r.T_target_source.matrix())},
                        {"rotation_vector", ToJson(Eigen::Vector3d(aa.angle() * aa.axis()))},
                        {"translation", ToJson(Eigen::Vector3d(r.T_target_source.translation()))},
                        {"converged", r.converged},
                        {"status", registration::ToString(r.status)},
                        {"iterations", r.iterations},
                        {"sample_points", r.sample_points},
                        {"inliers", r.inliers},
                        {"inlier_ratio", r.inlier_ratio},
                        {"rms", r.rms_m},
                        {"final_dmax", r.dmax_m},
                        {"reference_distance", r.reference_distance_m},
                        {"conditioning", r.conditioning},
                        {"covariance", MatrixToJson(r.covariance)},
                        {"source_points", source_index.cloud().size()},
                        {"target_points", target_index.cloud().size()},
                        {"time_ms", time_ms},
                        {"load_ms", load_ms},
                        {"trace", trace}};
  if (!r.message.empty()) out["message"] = r.message;
  if (!args.preview.empty()) {
    if (!write_preview) throw UsageError("--preview: this program writes no PNG");
    io::PreviewOptions preview;
    preview.title = std::filesystem::path(args.source).filename().string() + " -> " +
                    std::filesystem::path(args.target).filename().string() + ": " +
                    registration::ToString(r.status);
    write_preview(args.preview, source_index.cloud(), target_index.cloud(), T_init,
                  r.T_target_source, preview);
    out["preview"] = args.preview;
  }
  std::cout << out.dump(2) << "\n";

  const bool usable = r.status == registration::RegistrationStatus::kConverged ||
                      r.status == registration::RegistrationStatus::kMaxIterations;
  if (!usable) std::cerr << "rovermap: registration failed: " << r.message << "\n";
  return usable ? kExitOk : kExitFailure;
}

}  // namespace rovermap::apps
