// rovermap.ElevationMap: the DEM's grid and fusion (dem::ElevationMap), on numpy arrays.
#include <pybind11/stl.h>

#include <filesystem>
#include <memory>
#include <optional>

#include "io/DemLayers.hpp"
#include "io/GeoTiff.hpp"
#include "io/TerrainOutputs.hpp"
#include "python/src/Bindings.hpp"
#include "python/src/Convert.hpp"
#include "python/src/Handles.hpp"
#include "terrain/TerrainLayers.hpp"

namespace rovermap::python {
namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

py::dict StatsDict(const dem::FusionStats& s) {
  py::dict d;
  d["points"] = s.points;
  d["fused"] = s.fused;
  d["candidate"] = s.candidate;
  d["swapped"] = s.swapped;
  d["rejected_outliers"] = s.rejected_outliers;
  d["dropped_nonfinite"] = s.dropped_nonfinite;
  d["dropped_out_of_grid"] = s.dropped_out_of_grid;
  d["dropped_imprecise"] = s.dropped_imprecise;
  d["new_tiles"] = s.new_tiles;
  return d;
}

py::dict Fuse(ElevationMapHandle& handle, py::handle points, py::handle covariances,
              std::uint32_t frame, py::handle sensor_origin, py::handle pose_covariance,
              py::handle normals) {
  dem::ElevationMap& map = handle.Mutable();
  registration::PointCloud cloud = CloudFromArray(points, "points");
  if (cloud.HasNormals()) {
    throw py::value_error("points: expected an (N, 3) array; give normals as normals=");
  }
  SetCovariances(covariances, "covariances", &cloud);
  if (!normals.is_none()) {
    registration::PointCloud n = CloudFromArray(normals, "normals");
    if (n.size() != cloud.size())
      throw py::value_error("normals: expected one per point (" + std::to_string(cloud.size()) +
                            "), got " + std::to_string(n.size()));
    cloud.normals = std::move(n.points);
  }
  dem::FrameContext ctx;
  ctx.frame = frame;
  if (!sensor_origin.is_none()) {
    const auto o = sensor_origin.cast<std::vector<double>>();
    if (o.size() != 3) throw py::value_error("sensor_origin: expected (x, y, z) [m]");
    ctx.sensor_origin_world = Eigen::Vector3d(o[0], o[1], o[2]);
  }
  if (!pose_covariance.is_none()) {
    const DoubleArray c = DoubleArray::ensure(pose_covariance);
    if (!c || c.ndim() != 2 || c.shape(0) != 6 || c.shape(1) != 6)
      throw py::value_error("pose_covariance: expected a 6x6 array [rx ry rz tx ty tz]");
    ctx.pose_covariance = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(c.data());
  }
  if (cloud.HasNormals()) ctx.normals = &cloud.normals;
  dem::FusionStats stats;
  {
    py::gil_scoped_release release;
    stats = map.FuseFrame(cloud.points, cloud.covariances, ctx);
  }
  return StatsDict(stats);
}

// f(x, y) over numpy-broadcast x and y; a float when both are scalars.
template <typename F>
py::object AtPositions(py::handle x, py::handle y, F&& f) {
  const bool scalars = py::isinstance<py::float_>(x) || py::isinstance<py::int_>(x);
  if (scalars && (py::isinstance<py::float_>(y) || py::isinstance<py::int_>(y))) {
    return py::float_(f(x.cast<double>(), y.cast<double>()));
  }
  const py::object np = py::module_::import("numpy");
  const py::tuple both = np.attr("broadcast_arrays")(np.attr("asarray")(x, "float64"),
                                                     np.attr("asarray")(y, "float64"));
  const DoubleArray xs = DoubleArray::ensure(both[0]);
  const DoubleArray ys = DoubleArray::ensure(both[1]);
  std::vector<py::ssize_t> shape(xs.shape(), xs.shape() + xs.ndim());
  py::array_t<double> out(shape);
  double* o = out.mutable_data();
  for (py::ssize_t i = 0; i < xs.size(); ++i) o[i] = f(xs.data()[i], ys.data()[i]);
  return std::move(out);
}

py::dict Layers(const ElevationMapHandle& handle) {
  io::DemLayers layers = io::RasteriseDem(handle.Map());
  const std::vector<py::ssize_t> shape = {layers.height, layers.width};
  const double cell = layers.cell_size_m;
  py::dict d;
  d["elevation"] = Adopt(std::move(layers.elevation_m), shape);
  d["stddev"] = Adopt(std::move(layers.stddev_m), shape);
  d["count"] = Adopt(std::move(layers.count), shape);
  d["cell_size"] = cell;
  // Cell edges in the grid frame (row 0 north): matplotlib's imshow(extent=...).
  d["extent"] = py::make_tuple(layers.min.x * cell, (layers.max.x + 1) * cell, layers.min.y * cell,
                               (layers.max.y + 1) * cell);
  d["grid_rotation"] = layers.grid_rotation_rad;
  d["valid_cells"] = layers.valid_cells;
  return d;
}

// The terrain layers of the published cells (docs/terrain.md), on to_numpy's grid.
py::dict Terrain(const ElevationMapHandle& handle, py::handle config, const py::kwargs& overrides) {
  const config::Config cfg = ConfigFrom(config, overrides, "terrain");
  const io::DemLayers layers = io::RasteriseDem(handle.Map());
  terrain::TerrainLayers t;
  {
    py::gil_scoped_release release;
    t = terrain::ComputeTerrain(io::GridViewOf(layers), cfg.terrain);
  }
  const std::vector<py::ssize_t> shape = {t.height, t.width};
  py::dict d;
  d["slope_deg"] = Adopt(std::move(t.slope_deg), shape);
  d["slope_stddev_deg"] = Adopt(std::move(t.slope_sigma_deg), shape);
  d["roughness_m"] = Adopt(std::move(t.roughness_m), shape);
  d["step_m"] = Adopt(std::move(t.step_m), shape);
  d["traversability"] = Adopt(std::move(t.traversability), shape);
  d["uncertain"] = Adopt(std::move(t.uncertain), shape);
  d["known_cells"] = t.known;
  d["hazard_cells"] = t.hazard;
  d["uncertain_cells"] = t.uncertain_cells;
  d["benign_cells"] = t.benign;
  d["footprint_cells"] = py::make_tuple(t.footprint_cols, t.footprint_rows);
  return d;
}

}  // namespace

ElevationMapHandle::ElevationMapHandle(const dem::ElevationMapOptions& options,
                                       std::optional<io::Georeference> georef)
    : georef_(std::move(georef)) {
  dem::ElevationMapOptions o = options;
  if (georef_) o.grid_rotation_rad = georef_->convergence_rad();
  owned_ = std::make_unique<dem::ElevationMap>(o);
  map_ = owned_.get();
}

ElevationMapHandle::ElevationMapHandle(const dem::ElevationMap* view, io::Georeference georef,
                                       py::object owner)
    : map_(view), georef_(std::move(georef)), owner_(std::move(owner)) {}

dem::ElevationMap& ElevationMapHandle::Mutable() {
  if (!owned_) {
    throw py::value_error(
        "this ElevationMap is the mapper's (read-only): fuse into a map of your own");
  }
  return *owned_;
}

void BindElevationMap(py::module_& m) {
  py::class_<ElevationMapHandle>(
      m, "ElevationMap",
      "The DEM grid with its two-hypothesis Kalman fusion per cell (docs/design.md sections 3 "
      "and 9a); the same as the mapper's")
      .def(py::init([](py::handle origin, const std::string& body, py::handle config,
                       const py::kwargs& overrides) {
             const config::Config cfg = ConfigFrom(config, overrides, "dem");
             std::optional<io::Georeference> georef;
             if (!origin.is_none())
               georef.emplace(OriginFrom(origin, "origin"), io::ParseBody(body));
             return ElevationMapHandle(cfg.dem, std::move(georef));
           }),
           py::arg("origin") = py::none(), py::arg("body") = "earth",
           py::arg("config") = py::none(),
           R"(An empty map. origin: (latitude, longitude[, altitude]) of the world (ENU) frame,
needed to write a GeoTIFF (the grid is then laid out north-up in its UTM zone); body: earth,
moon or mars. **overrides: dem keys, e.g. cell_size_m=0.1, min_support=1.)")
      .def("fuse", &Fuse, py::arg("points"), py::arg("covariances") = py::none(), py::kw_only(),
           py::arg("frame") = 0, py::arg("sensor_origin") = py::none(),
           py::arg("pose_covariance") = py::none(), py::arg("normals") = py::none(),
           R"(Fuses one frame of world points ((N, 3) [m]). covariances: (N, 3, 3) [m^2] in
the world frame (default: dem.default_point_stddev_m); frame: the frame's index (cells are
published once seen by dem.min_frame_span frames); sensor_origin, pose_covariance (6x6, rx ry
rz tx ty tz): the pose's uncertainty; normals: (N, 3). Returns what happened to the points.)")
      .def(
          "height_at",
          [](const ElevationMapHandle& h, py::handle x, py::handle y) {
            return AtPositions(x, y, [&](double a, double b) { return h.Map().HeightAt(a, b); });
          },
          py::arg("x"), py::arg("y"),
          "Published height [m] at world (x, y) (arrays broadcast); NaN where not published")
      .def(
          "variance_at",
          [](const ElevationMapHandle& h, py::handle x, py::handle y) {
            return AtPositions(x, y, [&](double a, double b) { return h.Map().VarianceAt(a, b); });
          },
          py::arg("x"), py::arg("y"), "Variance of that height [m^2]")
      .def("to_numpy", &Layers,
           R"(The published cells as north-up float32 rasters, as dem.tif holds them: a dict
with elevation, stddev, count (row 0 north, NaN / 0 where not published), cell_size [m], extent
(x_min, x_max, y_min, y_max of the cell edges in the grid frame [m]), grid_rotation [rad] and
valid_cells. The arrays own their memory (no copy is made beyond the rasterisation).)")
      .def("terrain", &Terrain, py::arg("config") = py::none(),
           R"(The terrain layers a planner reads (docs/terrain.md), on to_numpy's grid: a dict
with slope_deg, slope_stddev_deg, roughness_m, step_m, traversability (0 hazard .. 1 benign),
uncertain (1 where a limit lies within terrain.uncertainty_sigmas sigma) as float32 arrays (row
0 north, NaN where unknown), and known_cells, hazard_cells, uncertain_cells, benign_cells,
footprint_cells. config: a YAML file; **overrides: terrain keys, e.g. footprint_m=0.8,
max_step_m=0.2. Raises ValueError for a footprint smaller than two cells or larger than the
map.)")
      .def(
          "write_geotiff",
          [](const ElevationMapHandle& h, py::handle path) {
            if (!h.georeference()) {
              throw py::value_error(
                  "write_geotiff: the map has no georeference; make it with origin=(lat, lon, "
                  "alt)");
            }
            const std::filesystem::path file = ToPath(path);  // needs the GIL
            io::GeoTiffInfo info;
            {
              py::gil_scoped_release release;
              info = io::WriteDemGeoTiff(file, h.Map(), *h.georeference());
            }
            py::dict d;
            d["width"] = info.width;
            d["height"] = info.height;
            d["geotransform"] = info.geotransform;
            d["valid_cells"] = info.valid_cells;
            return d;
          },
          py::arg("path"),
          "Writes the published cells as dem.tif does (COG: elevation, stddev, count), "
          "atomically. Raises OSError naming the file.")
      .def_property_readonly(
          "cell_size", [](const ElevationMapHandle& h) { return h.Map().options().cell_size_m; })
      .def_property_readonly("cell_count",
                             [](const ElevationMapHandle& h) { return h.Map().CellCount(); })
      .def_property_readonly(
          "published_cell_count",
          [](const ElevationMapHandle& h) { return h.Map().PublishedCellCount(); })
      .def_property_readonly("tile_count",
                             [](const ElevationMapHandle& h) { return h.Map().TileCount(); })
      .def_property_readonly("memory_bytes",
                             [](const ElevationMapHandle& h) { return h.Map().MemoryBytes(); })
      .def_property_readonly(
          "epsg",
          [](const ElevationMapHandle& h) {
            return h.georeference() ? h.georeference()->epsg() : 0;
          },
          "EPSG code of the GeoTIFF's CRS (0 without an origin, or off Earth)")
      .def_property_readonly("read_only", [](const ElevationMapHandle& h) { return h.ReadOnly(); })
      .def("__repr__", [](const ElevationMapHandle& h) {
        return "<ElevationMap " + std::to_string(h.Map().options().cell_size_m) + " m cells, " +
               std::to_string(h.Map().CellCount()) + " cells>";
      });
}

}  // namespace rovermap::python
