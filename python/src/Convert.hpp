#pragma once
// Conversions between Python values (numpy arrays, paths, dicts, keyword arguments) and the
// library's types, shared by the bindings. Every rejection is a ValueError naming the argument.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config/Config.hpp"
#include "io/Georeference.hpp"
#include "io/SensorType.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::python {

namespace py = pybind11;

/// True for str, bytes and os.PathLike objects.
bool IsPath(py::handle value);
/// os.fspath(value) as a path.
std::filesystem::path ToPath(py::handle value);

/// Points from an (N, 3) array, or (N, 6) with unit normals in columns 3-5 (the .xyz layout).
/// One copy into the matcher's layout. @throw py::value_error naming `name`.
registration::PointCloud CloudFromArray(py::handle points, const char* name);
/// A path (.ply, .xyz) or an array as CloudFromArray. @throw io::IoError, py::value_error.
registration::PointCloud CloudFrom(py::handle cloud, const char* name);
/// (N, 3, 3) per-point covariances [m^2] into `cloud`. @throw py::value_error naming `name`.
void SetCovariances(py::handle covariances, const char* name, registration::PointCloud* cloud);

/// (N,) float64 array of `values` (a copy).
py::array_t<double> ToArray(const std::vector<double>& values);
/// (N, 3) float64 array of `points` (a copy, owned by the array).
py::array_t<double> ToArray(const std::vector<Eigen::Vector3d>& points);
/// A read-only (N, 3) view of `points`, kept alive by `owner` (no copy).
py::array_t<double> ViewOf(const std::vector<Eigen::Vector3d>& points, py::handle owner);

/// A 4x4 homogeneous rigid transform (finite, R orthonormal within 1e-6, last row 0 0 0 1).
/// @throw py::value_error naming `name`.
Eigen::Isometry3d PoseFrom(py::handle pose, const char* name);
/// 4x4 float64 array.
py::array_t<double> ToArray(const Eigen::Isometry3d& pose);
/// (N, 4, 4) float64 array.
py::array_t<double> ToArray(const std::vector<Eigen::Isometry3d>& poses);
/// (N, 4, 4) or (N, 3, 4) array of rigid transforms. @throw py::value_error naming `name`.
std::vector<Eigen::Isometry3d> PosesFrom(py::handle poses, const char* name);

/// The configuration as the commands build it: the defaults, then `config` (None, a YAML file's
/// path, or a dict of keys: dotted "section.key" or nested sections), then `overrides` (keyword
/// arguments: `key` means `<section>.key`, `a__b` means `a.b`).
/// @throw config::ConfigError (ValueError) naming the key; io::IoError (OSError) naming the
///        file when it cannot be read.
config::Config ConfigFrom(py::handle config, const py::kwargs& overrides,
                          const std::string& section);

/// "stereo" or "cloud", as sequence.yaml spells them.
inline const char* SensorName(io::SensorType type) {
  return type == io::SensorType::kStereo ? "stereo" : "cloud";
}

/// A geodetic origin from (latitude deg, longitude deg, altitude m) or a dict with those keys
/// (altitude optional). @throw py::value_error naming `name`.
io::GeodeticOrigin OriginFrom(py::handle origin, const char* name);

/// A vector's elements as a numpy array of `shape` that owns them (moved, no copy).
template <typename T>
py::array_t<T> Adopt(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule free(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(std::move(shape), owned->data(), free);
}

/// A JSON value as Python objects (dict, list, float, ...; null as None).
py::object ToPython(const nlohmann::json& value);

}  // namespace rovermap::python
