// rovermap.Mapper: the pipeline `rovermap replay` and `rovermap serve` drive (mapper::Mapper),
// fed one frame at a time from Python.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <memory>
#include <sstream>

#include "io/Ros2Bag.hpp"
#include "io/Sequence.hpp"
#include "mapper/Degeneracy.hpp"
#include "mapper/Mapper.hpp"
#include "python/src/Bindings.hpp"
#include "python/src/Convert.hpp"
#include "python/src/Handles.hpp"
#include "service/DriftReport.hpp"
#include "service/Outputs.hpp"
#include "service/StatusLine.hpp"

namespace rovermap::python {
namespace {

using ImageArray = py::array_t<std::uint8_t, py::array::c_style>;

struct MapperHandle {
  config::Config cfg;
  std::unique_ptr<mapper::Mapper> mapper;
  std::string sequence;  ///< where the sequence came from, for summary.json
};

// What sequence.yaml would say, from a path, a Sequence or keyword arguments.
io::SequenceInfo InfoFrom(py::handle sequence, py::handle sensor, py::handle camera,
                          py::handle T_body_sensor, py::handle origin, const std::string& body,
                          const config::Config& cfg) {
  if (!sequence.is_none()) {
    if (!sensor.is_none() || !camera.is_none() || !T_body_sensor.is_none() || !origin.is_none()) {
      throw py::value_error(
          "sequence: give either a sequence or sensor/camera/T_body_sensor/origin, not both");
    }
    if (py::isinstance<SequenceHandle>(sequence))
      return sequence.cast<const SequenceHandle&>().source->info();
    const std::filesystem::path path = ToPath(sequence);
    // A sequence directory is read without its frames; a bag (ROS 2 bags may be directories)
    // has to be opened.
    if (std::filesystem::is_directory(path) && !io::IsRos2Bag(path)) {
      return io::ReadSequenceInfo(path);
    }
    return io::OpenFrameSource(path, config::BagOptionsFrom(cfg.bag))->info();
  }
  io::SequenceInfo info;
  if (origin.is_none()) {
    throw py::value_error(
        "origin: required without a sequence: (latitude deg, longitude deg[, altitude m]) of "
        "the world frame (the DEM's georeference)");
  }
  info.origin = OriginFrom(origin, "origin");
  io::ParseBody(body);  // @throw std::invalid_argument naming the value
  info.body = body;
  if (!camera.is_none()) info.camera = camera.cast<io::CameraModel>();
  const std::string type =
      sensor.is_none() ? (info.camera ? "stereo" : "cloud") : sensor.cast<std::string>();
  if (type == "stereo") {
    info.sensor_type = io::SensorType::kStereo;
    if (!info.camera) throw py::value_error("camera: a stereo sensor needs a Camera");
  } else if (type == "cloud") {
    info.sensor_type = io::SensorType::kCloud;
  } else {
    throw py::value_error("sensor: expected \"stereo\" or \"cloud\", got \"" + type + "\"");
  }
  if (!T_body_sensor.is_none()) info.T_body_sensor = PoseFrom(T_body_sensor, "T_body_sensor");
  return info;
}

MapperHandle MakeMapper(py::handle sequence, py::handle sensor, py::handle camera,
                        py::handle T_body_sensor, py::handle origin, const std::string& body,
                        py::handle config, const py::kwargs& overrides) {
  MapperHandle h;
  h.cfg = ConfigFrom(config, overrides, "mapper");
  const io::SequenceInfo info =
      InfoFrom(sequence, sensor, camera, T_body_sensor, origin, body, h.cfg);
  h.sequence = info.directory.string();
  const config::Config& c = h.cfg;
  try {
    h.mapper = std::make_unique<mapper::Mapper>(
        info, mapper::PipelineOptions{c.mapper, c.registration, c.stereo, c.dem, c.octomap,
                                      c.terrain});
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(e.what());  // an option the key checks let through
  }
  return h;
}

// The frame to process: a Frame from a Sequence, (left, right) images, or points.
mapper::FrameResult ProcessFrame(MapperHandle& h, py::handle data, py::handle odometry_pose,
                                 py::handle timestamp, py::handle groundtruth_pose,
                                 py::handle covariances) {
  mapper::Mapper& m = *h.mapper;
  const io::SequenceInfo& info = m.sequence();
  const bool stereo = info.sensor_type == io::SensorType::kStereo;
  io::Frame frame;
  ImageArray left, right;  // hold the numpy buffers the images point into
  if (py::isinstance<io::Frame>(data)) {
    frame = data.cast<const io::Frame&>();  // images are shared, points copied
  } else if (py::isinstance<py::tuple>(data) || py::isinstance<py::list>(data)) {
    if (!stereo) throw py::value_error("data: this mapper's sensor is a cloud: give (N, 3) points");
    const py::sequence pair = data.cast<py::sequence>();
    if (pair.size() != 2) throw py::value_error("data: expected (left, right) images");
    const io::CameraModel& cam = *info.camera;
    for (int i = 0; i < 2; ++i) {
      const char* name = i == 0 ? "left" : "right";
      const py::array a = py::array::ensure(pair[i]);
      if (!a || a.dtype().kind() != 'u' || a.itemsize() != 1 || a.ndim() != 2 ||
          a.shape(0) != cam.height || a.shape(1) != cam.width) {
        throw py::value_error(std::string(name) + ": expected a " + std::to_string(cam.height) +
                              "x" + std::to_string(cam.width) +
                              " uint8 array (the camera's size, 8-bit grey)");
      }
      ImageArray& image = i == 0 ? left : right;
      image = ImageArray::ensure(a);  // C-contiguous: no copy when it already is
      (i == 0 ? frame.left : frame.right) =
          cv::Mat(cam.height, cam.width, CV_8UC1, const_cast<std::uint8_t*>(image.data()));
    }
  } else {
    if (stereo) throw py::value_error("data: this mapper's sensor is stereo: give (left, right)");
    frame.cloud = CloudFromArray(data, "points");
    SetCovariances(covariances, "covariances", &frame.cloud);
  }
  if (!odometry_pose.is_none()) {
    frame.T_world_body_odom = PoseFrom(odometry_pose, "odometry_pose");
  } else if (!py::isinstance<io::Frame>(data)) {
    throw py::value_error("odometry_pose: required (4x4 T_world_body by dead reckoning)");
  }
  if (!timestamp.is_none()) frame.timestamp = timestamp.cast<double>();
  if (!groundtruth_pose.is_none())
    frame.T_world_body_truth = PoseFrom(groundtruth_pose, "groundtruth_pose");
  frame.index = m.results().size();
  if (frame.left.empty() == stereo) {  // only a Frame can get here with the wrong kind
    throw py::value_error("data: the frame's sensor does not match this mapper's");
  }
  py::gil_scoped_release release;
  return m.ProcessFrame(frame);
}

py::array_t<double> Components(const Eigen::Isometry3d& T) {
  const mapper::TransformComponents c = mapper::CorrectionComponents(T);
  const std::vector<double> v = {c.dx_m, c.dy_m, c.dz_m, c.droll_deg, c.dpitch_deg, c.dyaw_deg};
  return py::array_t<double>(6, v.data());
}

py::list DirectionList(unsigned mask) {
  py::list names;
  std::istringstream words(mapper::DirectionNames(mask));
  for (std::string w; words >> w;) names.append(w);
  return names;
}

py::dict Times(const mapper::StageTimes& t) {
  py::dict d;
  d["load_ms"] = t.load_ms;
  d["stereo_ms"] = t.stereo_ms;
  d["prepare_ms"] = t.prepare_ms;
  d["register_ms"] = t.register_ms;
  d["fuse_dem_ms"] = t.fuse_dem_ms;
  d["fuse_octomap_ms"] = t.fuse_octomap_ms;
  d["total_ms"] = t.total_ms;
  return d;
}

template <typename F>
py::array_t<double> PosesOf(const MapperHandle& h, F&& pose) {
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& r : h.mapper->results()) poses.push_back(pose(r));
  return ToArray(poses);
}

}  // namespace

void BindMapper(py::module_& m) {
  using mapper::FrameResult;
  py::class_<FrameResult>(m, "FrameResult", "What happened to one frame: one drift.csv row")
      .def_readonly("index", &FrameResult::index)
      .def_readonly("timestamp", &FrameResult::timestamp, "[s]")
      .def_property_readonly(
          "status", [](const FrameResult& r) { return mapper::ToString(r.status); },
          "first, registered, partial, fallback or bad_frame")
      .def_property_readonly(
          "fallback_reason",
          [](const FrameResult& r) { return mapper::ToString(r.fallback_reason); })
      .def_readonly("detail", &FrameResult::detail)
      .def_property_readonly(
          "pose", [](const FrameResult& r) { return ToArray(r.step.T_world_body); },
          "4x4 T_world_body, registered and chained")
      .def_property_readonly("odometry_pose",
                             [](const FrameResult& r) { return ToArray(r.step.T_world_body_odom); })
      .def_property_readonly("groundtruth_pose",
                             [](const FrameResult& r) -> py::object {
                               if (!r.T_world_body_truth) return py::none();
                               return ToArray(*r.T_world_body_truth);
                             })
      .def_property_readonly(
          "increment", [](const FrameResult& r) { return ToArray(r.step.used_increment); },
          "4x4 T_prev_curr as chained")
      .def_property_readonly("odometry_increment",
                             [](const FrameResult& r) { return ToArray(r.step.odom_increment); })
      .def_property_readonly(
          "correction",
          [](const FrameResult& r) { return Components(r.step.increment_correction); },
          "what registration changed in this step: dx dy dz [m], droll dpitch dyaw [deg] "
          "(drift.csv)")
      .def_property_readonly(
          "cumulative_correction",
          [](const FrameResult& r) { return Components(r.step.cumulative_correction); },
          "the total correction of dead reckoning so far, same six")
      .def_property_readonly(
          "covariance", [](const FrameResult& r) { return r.step.covariance; },
          "6x6 of the pose, right perturbation in the body frame [rx ry rz (rad) tx ty tz (m)]")
      .def_property_readonly("fallback", [](const FrameResult& r) { return r.step.fallback; })
      .def_property_readonly(
          "odometry_directions",
          [](const FrameResult& r) { return DirectionList(r.odometry_directions); },
          "directions kept from dead reckoning, e.g. ['x', 'y', 'yaw']")
      .def_property_readonly(
          "image_check", [](const FrameResult& r) { return std::string(ToString(r.image_check)); },
          "the image check's outcome: used, disagreed, failed or none (drift.csv's word)")
      .def_readonly("matcher_status", &FrameResult::matcher_status)
      .def_readonly("iterations", &FrameResult::iterations)
      .def_readonly("inliers", &FrameResult::inliers)
      .def_readonly("inlier_ratio", &FrameResult::inlier_ratio)
      .def_readonly("rms", &FrameResult::rms_m, "[m]")
      .def_readonly("conditioning", &FrameResult::conditioning)
      .def_readonly("points", &FrameResult::points)
      .def_readonly("outliers_removed", &FrameResult::outliers_removed)
      .def_readonly("dropped_nonfinite", &FrameResult::dropped_nonfinite)
      .def_property_readonly("times", [](const FrameResult& r) { return Times(r.time); })
      .def("__repr__", [](const FrameResult& r) {
        return "<FrameResult " + std::to_string(r.index) + " " + mapper::StatusLine(r) + ">";
      });

  py::class_<MapperHandle>(m, "Mapper",
                           "The mapping pipeline of `rovermap replay` and `rovermap serve`, one "
                           "frame at a time")
      .def(py::init(&MakeMapper), py::arg("sequence") = py::none(), py::kw_only(),
           py::arg("sensor") = py::none(), py::arg("camera") = py::none(),
           py::arg("T_body_sensor") = py::none(), py::arg("origin") = py::none(),
           py::arg("body") = "earth", py::arg("config") = py::none(),
           R"(sequence: a sequence directory, a ROS bag (.bag, .mcap, .db3 or a rosbag2
directory) or a Sequence (its sensor, calibration and origin); or, without one: sensor
("stereo" or "cloud"), camera (a Camera; stereo needs one,
a cloud uses it for its points' error model), T_body_sensor (4x4), origin (latitude,
longitude[, altitude]) and body.
config: None, a YAML file's path or a dict of keys; **overrides: mapper keys (reference=
"local_map") or any key as section__key (registration__max_iterations=30).)")
      .def("process_frame", &ProcessFrame, py::arg("data"), py::arg("odometry_pose") = py::none(),
           py::arg("timestamp") = py::none(), py::kw_only(),
           py::arg("groundtruth_pose") = py::none(), py::arg("covariances") = py::none(),
           R"(Registers, chains and fuses the next frame; returns its FrameResult.
data: a Frame (from a Sequence; its poses and time unless given), (left, right) uint8 images
of the camera's size (stereo), or (N, 3) points in the sensor frame (cloud; optional
covariances (N, 3, 3)). odometry_pose: 4x4 T_world_body by dead reckoning; timestamp [s].
A frame the pipeline cannot use is not an error: its status is bad_frame.)")
      .def(
          "skip_frame",
          [](MapperHandle& h, py::handle odometry_pose, double timestamp, const std::string& why,
             py::handle groundtruth_pose) {
            std::optional<Eigen::Isometry3d> truth;
            if (!groundtruth_pose.is_none()) truth = PoseFrom(groundtruth_pose, "groundtruth_pose");
            return h.mapper->SkipFrame(h.mapper->results().size(), timestamp,
                                       PoseFrom(odometry_pose, "odometry_pose"),
                                       mapper::FallbackReason::kBadFrame, why, truth);
          },
          py::arg("odometry_pose"), py::arg("timestamp"), py::arg("why") = "", py::kw_only(),
          py::arg("groundtruth_pose") = py::none(),
          "A frame that could not be read: its pose from dead reckoning, nothing fused")
      .def(
          "write_outputs",
          [](const MapperHandle& h, py::handle out_dir) {
            const std::filesystem::path out = ToPath(out_dir);
            nlohmann::json summary;
            {
              py::gil_scoped_release release;
              std::filesystem::create_directories(out);
              mapper::RunInfo run;
              run.sequence = h.sequence;
              run.wall_ms = mapper::ProcessingMs(h.mapper->results());
              summary = mapper::WriteOutputs(out, *h.mapper, run, h.cfg.eval);
            }
            return ToPython(summary);
          },
          py::arg("out_dir"),
          R"(Writes replay's outputs (dem.tif, map.bt, trajectory.tum, odometry.tum, drift.csv,
dem.png, drift.png, summary.json) into out_dir (created; outputs there are replaced, each
atomically). Returns summary.json as a dict. Raises OSError naming a file it cannot write.)")
      .def_property_readonly(
          "results", [](const MapperHandle& h) { return h.mapper->results(); },
          "every frame's FrameResult so far")
      .def("__len__", [](const MapperHandle& h) { return h.mapper->results().size(); })
      .def_property_readonly(
          "trajectory",
          [](const MapperHandle& h) {
            return PosesOf(h, [](const FrameResult& r) { return r.step.T_world_body; });
          },
          "(N, 4, 4) registered poses")
      .def_property_readonly(
          "odometry",
          [](const MapperHandle& h) {
            return PosesOf(h, [](const FrameResult& r) { return r.step.T_world_body_odom; });
          },
          "(N, 4, 4) dead-reckoning poses")
      .def_property_readonly(
          "timestamps",
          [](const MapperHandle& h) {
            std::vector<double> t;
            for (const auto& r : h.mapper->results()) t.push_back(r.timestamp);
            return ToArray(t);
          },
          "(N,) [s]")
      .def_property_readonly(
          "elevation_map",
          [](py::object self) {
            const MapperHandle& h = self.cast<const MapperHandle&>();
            return ElevationMapHandle(&h.mapper->elevation_map(), h.mapper->georeference(), self);
          },
          "the DEM so far (read-only; it shares the mapper's memory)")
      .def_property_readonly("sensor", [](const MapperHandle& h) {
        return SensorName(h.mapper->sequence().sensor_type);
      });
}

}  // namespace rovermap::python
