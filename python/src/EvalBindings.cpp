// rovermap.eval: the trajectory and DEM metrics of `rovermap eval` (docs/design.md §8) on arrays
// or files.
#include <pybind11/stl.h>

#include "eval/DemComparison.hpp"
#include "eval/TrajectoryIo.hpp"
#include "eval/TrajectoryMetrics.hpp"
#include "io/GeoTiff.hpp"
#include "python/src/Bindings.hpp"
#include "python/src/Convert.hpp"

namespace rovermap::python {
namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::vector<double> Timestamps(py::handle t, std::size_t n, const char* name) {
  if (t.is_none()) return {};
  const DoubleArray a = DoubleArray::ensure(t);
  if (!a || a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n) {
    throw py::value_error(std::string(name) + ": expected " + std::to_string(n) +
                          " timestamps [s], one per pose");
  }
  std::vector<double> out(a.data(), a.data() + n);
  for (std::size_t i = 1; i < out.size(); ++i) {
    if (!(out[i] > out[i - 1]))
      throw py::value_error(std::string(name) + "[" + std::to_string(i) +
                            "]: timestamps must be strictly increasing");
  }
  return out;
}

eval::Trajectory TrajectoryFrom(py::handle value, py::handle timestamps, const char* name) {
  if (IsPath(value)) {
    if (!timestamps.is_none())
      throw py::value_error(std::string(name) + ": a file carries its own timestamps");
    return eval::ReadTrajectory(ToPath(value));
  }
  eval::Trajectory t;
  t.file = name;
  t.poses = PosesFrom(value, name);
  t.timestamps_s =
      Timestamps(timestamps, t.poses.size(), (std::string(name) + "_timestamps").c_str());
  t.format = eval::TrajectoryFormat::kTum;
  return t;
}

io::DemRaster RasterFrom(py::handle value, const char* name) {
  if (IsPath(value)) return io::ReadDemGeoTiff(ToPath(value));
  if (!py::isinstance<py::dict>(value)) {
    throw py::value_error(std::string(name) +
                          ": expected a GeoTIFF's path or a dict with elevation (2-D) and "
                          "geotransform (6 numbers, GDAL order)");
  }
  const py::dict d = value.cast<py::dict>();
  if (!d.contains("elevation") || !d.contains("geotransform"))
    throw py::value_error(std::string(name) + ": the dict needs elevation and geotransform");
  using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
  const FloatArray z = FloatArray::ensure(d["elevation"]);
  if (!z || z.ndim() != 2) throw py::value_error(std::string(name) + ": elevation must be 2-D");
  io::DemRaster r;
  r.file = name;
  r.height = static_cast<int>(z.shape(0));
  r.width = static_cast<int>(z.shape(1));
  r.elevation_m.assign(z.data(), z.data() + z.size());
  const auto g = d["geotransform"].cast<std::vector<double>>();
  if (g.size() != 6 || g[2] != 0.0 || g[4] != 0.0 || g[1] <= 0.0 || g[5] == 0.0)
    throw py::value_error(std::string(name) +
                          ": geotransform must be 6 numbers, north-up (g[2] = g[4] = 0, g[1] > 0)");
  std::copy(g.begin(), g.end(), r.geotransform.begin());
  if (d.contains("stddev") && !d["stddev"].is_none()) {
    const FloatArray s = FloatArray::ensure(d["stddev"]);
    if (!s || s.ndim() != 2 || s.shape(0) != z.shape(0) || s.shape(1) != z.shape(1))
      throw py::value_error(std::string(name) + ": stddev must have elevation's shape");
    r.stddev_m.assign(s.data(), s.data() + s.size());
  }
  if (d.contains("wkt")) r.wkt = d["wkt"].cast<std::string>();
  return r;
}

}  // namespace

void BindEval(py::module_& parent) {
  py::module_ m = parent.def_submodule("eval", "Trajectory and DEM metrics (rovermap eval)");
  m.def(
      "read_trajectory",
      [](py::handle path, const std::string& format) {
        const eval::Trajectory t =
            eval::ReadTrajectory(ToPath(path), eval::ParseTrajectoryFormat(format));
        py::object stamps = py::none();
        if (t.has_timestamps()) stamps = ToArray(t.timestamps_s);
        return py::make_tuple(stamps, ToArray(t.poses));
      },
      py::arg("path"), py::arg("format") = "auto",
      "A TUM or KITTI trajectory file: (timestamps or None for KITTI, (N, 4, 4) poses). "
      "Raises OSError naming the file and line.");
  m.def(
      "trajectory_metrics",
      [](py::handle estimate, py::handle groundtruth, py::handle estimate_timestamps,
         py::handle groundtruth_timestamps, py::handle config, const py::kwargs& overrides) {
        const config::Config cfg = ConfigFrom(config, overrides, "eval");
        const eval::Trajectory e = TrajectoryFrom(estimate, estimate_timestamps, "estimate");
        const eval::Trajectory g =
            TrajectoryFrom(groundtruth, groundtruth_timestamps, "groundtruth");
        return ToPython(eval::ToJson(eval::EvaluateTrajectory(e, g, cfg.eval)));
      },
      py::arg("estimate"), py::arg("groundtruth"), py::kw_only(),
      py::arg("estimate_timestamps") = py::none(), py::arg("groundtruth_timestamps") = py::none(),
      py::arg("config") = py::none(),
      R"(ATE (SE(3)-aligned and aligned at the first pose), RPE and KITTI segment errors, as
`rovermap eval` prints them (a dict with the keys of docs/design.md section 8: ate_rmse_m,
ate_rmse_origin_m, ...).
estimate, groundtruth: a TUM or KITTI file's path, or (N, 4, 4) / (N, 3, 4) poses; with
timestamps for both, poses are associated by time, else by index. **overrides: eval keys, e.g.
rpe_delta_m=0.5.)");
  m.def(
      "read_dem",
      [](py::handle path) {
        io::DemRaster r = io::ReadDemGeoTiff(ToPath(path));
        const std::vector<py::ssize_t> shape = {r.height, r.width};
        py::dict d;
        d["elevation"] = Adopt(std::move(r.elevation_m), shape);
        d["stddev"] = r.stddev_m.empty() ? py::object(py::none())
                                         : py::object(Adopt(std::move(r.stddev_m), shape));
        d["count"] =
            r.count.empty() ? py::object(py::none()) : py::object(Adopt(std::move(r.count), shape));
        d["geotransform"] = r.geotransform;
        d["wkt"] = r.wkt;
        d["epsg"] = r.epsg;
        return d;
      },
      py::arg("path"),
      "A DEM GeoTIFF (dem.tif): a dict with elevation, stddev, count (row 0 north; NaN = no "
      "data), geotransform (GDAL order), wkt and epsg. Raises OSError naming the file.");
  m.def(
      "compare_dems",
      [](py::handle dem, py::handle reference) {
        const io::DemRaster a = RasterFrom(dem, "dem");
        const io::DemRaster b = RasterFrom(reference, "reference");
        eval::DemComparison c;
        {
          py::gil_scoped_release release;
          c = eval::CompareDems(a, b);
        }
        return ToPython(eval::ToJson(c));
      },
      py::arg("dem"), py::arg("reference"),
      R"(DEM accuracy against a reference, as `rovermap eval --dem A --reference B`: rmse_m,
bias_m, p95_abs_m, coverage, within_2sigma, cells, ... Each is a GeoTIFF's path or a dict as
read_dem returns (elevation and geotransform required; stddev and wkt optional).)");
}

}  // namespace rovermap::python
