// rovermap.register(source, target, init=None, config=None, **overrides): `rovermap register`
// on arrays or files.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <chrono>

#include "core/Stopwatch.hpp"
#include "python/src/Bindings.hpp"
#include "python/src/Convert.hpp"
#include "registration/Icp.hpp"

namespace rovermap::python {
namespace {

struct Registration {
  registration::RegistrationResult result;
  std::size_t source_points = 0;
  std::size_t target_points = 0;
  double time_ms = 0.0;  ///< indexing and matching, as the command's time_ms
};

py::list TraceList(const std::vector<registration::IterationTrace>& trace) {
  py::list rows;
  for (const auto& it : trace) {
    py::dict row;
    row["iteration"] = it.iteration;
    row["pairs_found"] = it.pairs_found;
    row["pairs_kept"] = it.pairs_kept;
    row["pairs_rejected_by_orientation"] = it.pairs_rejected_by_orientation;
    row["mean"] = it.mean_m;
    row["stddev"] = it.stddev_m;
    row["dmax"] = it.dmax_m;
    row["branch"] = registration::ToString(it.branch);
    row["rms"] = it.rms_m;
    row["step_translation"] = it.step_translation_m;
    row["step_rotation_deg"] = it.step_rotation_deg;
    row["accelerated"] = it.accelerated;
    row["extrapolation_rejected"] = it.extrapolation_rejected;
    rows.append(row);
  }
  return rows;
}

Registration Register(py::handle source, py::handle target, py::handle init, py::handle config,
                      const py::kwargs& overrides) {
  const config::Config cfg = ConfigFrom(config, overrides, "registration");
  const Eigen::Isometry3d T_init =
      init.is_none() ? Eigen::Isometry3d::Identity() : PoseFrom(init, "init");
  registration::PointCloud source_cloud = CloudFrom(source, "source");
  registration::PointCloud target_cloud = CloudFrom(target, "target");
  Registration out;
  out.source_points = source_cloud.size();
  out.target_points = target_cloud.size();
  py::gil_scoped_release release;  // the matcher runs on its own threads; Python may go on
  const auto start = std::chrono::steady_clock::now();
  const registration::IndexedCloud source_index(std::move(source_cloud), cfg.registration);
  const registration::IndexedCloud target_index(std::move(target_cloud), cfg.registration);
  out.result = registration::Register(source_index, target_index, T_init, cfg.registration);
  out.time_ms = rovermap::core::MsSince(start);
  return out;
}

}  // namespace

void BindRegistration(py::module_& m) {
  py::class_<Registration>(m, "RegistrationResult",
                           "What register() found: T maps source points onto the target "
                           "(target = R source + t)")
      .def_property_readonly(
          "T", [](const Registration& r) { return ToArray(r.result.T_target_source); },
          "4x4 T_target_source")
      .def_property_readonly(
          "status", [](const Registration& r) { return registration::ToString(r.result.status); },
          "converged, max_iterations, too_few_points, too_few_pairs, solver_failed or "
          "invalid_input")
      .def_property_readonly("converged", [](const Registration& r) { return r.result.converged; })
      .def_property_readonly(
          "usable",
          [](const Registration& r) {
            return r.result.status == registration::RegistrationStatus::kConverged ||
                   r.result.status == registration::RegistrationStatus::kMaxIterations;
          },
          "converged or max_iterations: the command's exit status 0")
      .def_property_readonly("iterations",
                             [](const Registration& r) { return r.result.iterations; })
      .def_property_readonly("sample_points",
                             [](const Registration& r) { return r.result.sample_points; })
      .def_property_readonly("inliers", [](const Registration& r) { return r.result.inliers; })
      .def_property_readonly("inlier_ratio",
                             [](const Registration& r) { return r.result.inlier_ratio; })
      .def_property_readonly(
          "rms", [](const Registration& r) { return r.result.rms_m; }, "[m]")
      .def_property_readonly(
          "final_dmax", [](const Registration& r) { return r.result.dmax_m; }, "[m]")
      .def_property_readonly(
          "reference_distance", [](const Registration& r) { return r.result.reference_distance_m; },
          "D as used [m]")
      .def_property_readonly("conditioning",
                             [](const Registration& r) { return r.result.conditioning; })
      .def_property_readonly(
          "covariance", [](const Registration& r) { return r.result.covariance; },
          "6x6, left perturbation in the target frame, [rx ry rz (rad) tx ty tz (m)]")
      .def_property_readonly(
          "information", [](const Registration& r) { return r.result.information; }, "6x6")
      .def_property_readonly(
          "noise_information", [](const Registration& r) { return r.result.noise_information; },
          "6x6: the part of `information` the matched normals' own errors give (PCA normals)")
      .def_property_readonly(
          "trace", [](const Registration& r) { return TraceList(r.result.trace); },
          "one dict per iteration, the keys of the command's JSON trace")
      .def_property_readonly("message", [](const Registration& r) { return r.result.message; })
      .def_readonly("source_points", &Registration::source_points)
      .def_readonly("target_points", &Registration::target_points)
      .def_readonly("time_ms", &Registration::time_ms)
      .def("__repr__", [](const Registration& r) {
        return "<RegistrationResult " + std::string(registration::ToString(r.result.status)) +
               ", " + std::to_string(r.result.iterations) + " iterations, " +
               std::to_string(r.result.inliers) + " inliers, rms " +
               std::to_string(r.result.rms_m) + " m>";
      });

  m.def("register", &Register, py::arg("source"), py::arg("target"), py::arg("init") = py::none(),
        py::arg("config") = py::none(),
        R"(Registers `source` onto `target` (Zhang's iterative point matching).

source, target: an (N, 3) array of points, (N, 6) with unit normals in columns 3-5, or the
    path of a .ply or .xyz file.
init: 4x4 initial T_target_source (default identity).
config: None, a YAML config file's path, or a dict of keys ("registration.max_iterations" or
    nested {"registration": {...}}).
**overrides: registration keys, e.g. geometry="curve", max_iterations=30 (a__b for a.b).
Raises ValueError naming a bad key, value or array; OSError naming an unreadable file.
A failed registration is not an error: see the result's status and message.)");
}

}  // namespace rovermap::python
