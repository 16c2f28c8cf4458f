// read_points(), Camera, Frame and Sequence: recordings as `rovermap replay` reads them.
#include <pybind11/stl.h>

#include <memory>

#include "config/Config.hpp"
#include "io/FrameSource.hpp"
#include "io/PointCloudIo.hpp"
#include "python/src/Bindings.hpp"
#include "python/src/Convert.hpp"
#include "python/src/Handles.hpp"

namespace rovermap::python {
namespace {

// A frame's image as a read-only uint8 array over the cv::Mat's pixels (no copy); `owner` (the
// Python Frame) keeps the Mat alive.
py::object ImageView(const cv::Mat& image, py::handle owner) {
  if (image.empty()) return py::none();
  py::array_t<std::uint8_t> a(
      {static_cast<py::ssize_t>(image.rows), static_cast<py::ssize_t>(image.cols)},
      {static_cast<py::ssize_t>(image.step[0]), py::ssize_t{1}}, image.data, owner);
  a.attr("setflags")(py::arg("write") = false);
  return std::move(a);
}

py::object Covariances(const std::vector<Eigen::Matrix3d>& covariances) {
  if (covariances.empty()) return py::none();
  py::array_t<double> a(
      {static_cast<py::ssize_t>(covariances.size()), py::ssize_t{3}, py::ssize_t{3}});
  for (std::size_t i = 0; i < covariances.size(); ++i) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a.mutable_data() + 9 * i) =
        covariances[i];
  }
  return std::move(a);
}

using Sequence = SequenceHandle;

std::vector<Eigen::Isometry3d> Poses(const std::vector<io::StampedPose>& stamped) {
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& p : stamped) poses.push_back(p.T_world_body);
  return poses;
}

py::dict OriginDict(const io::GeodeticOrigin& origin) {
  py::dict d;
  d["latitude"] = origin.latitude_deg;
  d["longitude"] = origin.longitude_deg;
  d["altitude"] = origin.altitude_m;
  return d;
}

}  // namespace

void BindIo(py::module_& m) {
  m.def(
      "read_points",
      [](py::handle path, bool with_normals) -> py::object {
        const registration::PointCloud cloud = io::ReadPointCloud(ToPath(path));
        if (!with_normals) return ToArray(cloud.points);
        py::object normals = cloud.HasNormals() ? py::object(ToArray(cloud.normals)) : py::none();
        return py::make_tuple(ToArray(cloud.points), normals);
      },
      py::arg("path"), py::arg("with_normals") = false,
      "Points of a .ply or .xyz file as an (N, 3) array; with_normals=True: (points, normals or "
      "None). Raises OSError naming the file.");

  py::class_<io::CameraModel>(m, "Camera", "A rectified stereo pair (pinhole, shared intrinsics)")
      .def(py::init([](int width, int height, double fx, double fy, double cx, double cy,
                       double baseline) {
             return io::CameraModel{width, height, fx, fy, cx, cy, baseline};
           }),
           py::kw_only(), py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"),
           py::arg("cx"), py::arg("cy"), py::arg("baseline"),
           "width, height [px], fx, fy, cx, cy [px], baseline [m]")
      .def_readonly("width", &io::CameraModel::width)
      .def_readonly("height", &io::CameraModel::height)
      .def_readonly("fx", &io::CameraModel::fx)
      .def_readonly("fy", &io::CameraModel::fy)
      .def_readonly("cx", &io::CameraModel::cx)
      .def_readonly("cy", &io::CameraModel::cy)
      .def_readonly("baseline", &io::CameraModel::baseline_m)
      .def("__repr__", [](const io::CameraModel& c) {
        return "<Camera " + std::to_string(c.width) + "x" + std::to_string(c.height) + ", fx " +
               std::to_string(c.fx) + ", baseline " + std::to_string(c.baseline_m) + " m>";
      });

  py::class_<io::Frame>(m, "Frame", "One frame of a recording, as Sequence reads it")
      .def_readonly("index", &io::Frame::index)
      .def_readonly("timestamp", &io::Frame::timestamp, "[s]")
      .def_property_readonly(
          "odometry_pose", [](const io::Frame& f) { return ToArray(f.T_world_body_odom); },
          "4x4 T_world_body by dead reckoning")
      .def_property_readonly(
          "groundtruth_pose",
          [](const io::Frame& f) -> py::object {
            if (!f.T_world_body_truth) return py::none();
            return ToArray(*f.T_world_body_truth);
          },
          "4x4 T_world_body, or None")
      .def_property_readonly(
          "left",
          [](py::object self) { return ImageView(self.cast<const io::Frame&>().left, self); },
          "stereo: 8-bit grey image (a read-only view), else None")
      .def_property_readonly(
          "right",
          [](py::object self) { return ImageView(self.cast<const io::Frame&>().right, self); })
      .def_property_readonly(
          "points",
          [](py::object self) -> py::object {
            const io::Frame& f = self.cast<const io::Frame&>();
            if (f.cloud.empty()) return py::none();
            return ViewOf(f.cloud.points, self);
          },
          "cloud: (N, 3) points in the sensor frame (a read-only view), else None")
      .def_property_readonly("normals",
                             [](py::object self) -> py::object {
                               const io::Frame& f = self.cast<const io::Frame&>();
                               if (!f.cloud.HasNormals()) return py::none();
                               return ViewOf(f.cloud.normals, self);
                             })
      .def_property_readonly("covariances",
                             [](const io::Frame& f) { return Covariances(f.cloud.covariances); })
      .def_property_readonly("file", [](const io::Frame& f) { return f.file.string(); })
      .def("__repr__", [](const io::Frame& f) {
        return "<Frame " + std::to_string(f.index) + " at " + std::to_string(f.timestamp) + " s>";
      });

  py::class_<Sequence>(
      m, "Sequence",
      "A recorded sequence directory (or ROS 1 or ROS 2 bag), validated when opened; "
      "frames are read one at a time (seq[i], or iterate)")
      .def(py::init([](py::handle path, py::handle config, const py::kwargs& overrides) {
             const config::Config cfg = ConfigFrom(config, overrides, "bag");
             return Sequence{io::OpenFrameSource(ToPath(path), config::BagOptionsFrom(cfg.bag))};
           }),
           py::arg("path"), py::arg("config") = py::none(),
           "path: sequence directory, .bag, .mcap, .db3 or rosbag2 directory; config and "
           "**overrides as for Mapper (bag keys). "
           "Raises OSError naming the file at fault.")
      .def("__len__", [](const Sequence& s) { return s.source->frame_count(); })
      .def(
          "__getitem__",
          [](const Sequence& s, py::ssize_t i) {
            const auto n = static_cast<py::ssize_t>(s.source->frame_count());
            if (i < 0) i += n;
            if (i < 0 || i >= n) throw py::index_error("frame index out of range");
            io::Frame frame;
            {
              py::gil_scoped_release release;
              frame = s.source->Read(static_cast<std::size_t>(i));
            }
            return frame;
          },
          "Frame i. Raises OSError naming the file if it cannot be read.")
      .def_property_readonly(
          "sensor", [](const Sequence& s) { return SensorName(s.source->info().sensor_type); })
      .def_property_readonly("camera", [](const Sequence& s) { return s.source->info().camera; })
      .def_property_readonly(
          "T_body_sensor",
          [](const Sequence& s) { return ToArray(s.source->info().T_body_sensor); })
      .def_property_readonly("origin",
                             [](const Sequence& s) { return OriginDict(s.source->info().origin); })
      .def_property_readonly("body", [](const Sequence& s) { return s.source->info().body; })
      .def_property_readonly("frame_rate",
                             [](const Sequence& s) { return s.source->info().frame_rate_hz; })
      .def_property_readonly("path",
                             [](const Sequence& s) { return s.source->info().directory.string(); })
      .def_property_readonly(
          "timestamps",
          [](const Sequence& s) {
            std::vector<double> t;
            for (const auto& p : s.source->odometry()) t.push_back(p.timestamp);
            return ToArray(t);
          },
          "(N,) [s]")
      .def_property_readonly(
          "odometry", [](const Sequence& s) { return ToArray(Poses(s.source->odometry())); },
          "(N, 4, 4) dead-reckoning poses")
      .def_property_readonly(
          "groundtruth",
          [](const Sequence& s) -> py::object {
            if (!s.source->has_groundtruth()) return py::none();
            return ToArray(Poses(s.source->groundtruth()));
          },
          "(N, 4, 4) true poses, or None");
}

}  // namespace rovermap::python
