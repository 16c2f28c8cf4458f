#include "python/src/Convert.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include "io/FileUtil.hpp"
#include "io/PointCloudIo.hpp"
#include "mapper/PoseChain.hpp"

namespace rovermap::python {
namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Any array-like as a C-contiguous float64 array; a list of lists works too.
DoubleArray AsDoubles(py::handle value, const char* name) {
  if (value.is_none()) throw py::value_error(std::string(name) + ": expected an array, got None");
  try {
    return DoubleArray::ensure(value).cast<DoubleArray>();
  } catch (const py::error_already_set&) {
  } catch (const py::cast_error&) {
  }
  throw py::value_error(std::string(name) + ": expected a numeric array, got " +
                        std::string(py::str(py::type::of(value).attr("__name__"))));
}

std::string Shape(const py::array& a) {
  std::ostringstream text;
  text << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) text << (i ? ", " : "") << a.shape(i);
  text << (a.ndim() == 1 ? ",)" : ")");
  return text.str();
}

// A Python value as the YAML text of a `key=value` override.
std::string YamlText(py::handle value, const std::string& key) {
  if (value.is_none()) return "null";
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::int_>(value)) return std::string(py::str(value));
  if (py::isinstance<py::float_>(value)) {
    // repr is the shortest text that reads back to the same double.
    const double x = value.cast<double>();
    if (!std::isfinite(x)) return std::isnan(x) ? ".nan" : (x > 0 ? ".inf" : "-.inf");
    return std::string(py::repr(value));
  }
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value) ||
      py::isinstance<py::array>(value)) {
    std::string text = "[";
    bool first = true;
    for (py::handle item : value) {
      text += (first ? "" : ", ") + YamlText(item, key);
      first = false;
    }
    return text + "]";
  }
  if (IsPath(value)) return ToPath(value).string();
  // numpy scalars and the like
  if (py::hasattr(value, "item")) return YamlText(value.attr("item")(), key);
  throw py::value_error(key + ": cannot use a value of type " +
                        std::string(py::str(py::type::of(value).attr("__name__"))));
}

// {"registration": {"max_iterations": 30}} and {"registration.max_iterations": 30} alike.
void Flatten(py::handle dict, const std::string& prefix, std::vector<std::string>* overrides) {
  for (auto item : dict.cast<py::dict>()) {
    const std::string key = prefix + std::string(py::str(item.first));
    if (py::isinstance<py::dict>(item.second)) {
      Flatten(item.second, key + ".", overrides);
    } else {
      overrides->push_back(key + "=" + YamlText(item.second, key));
    }
  }
}

}  // namespace

bool IsPath(py::handle value) {
  return py::isinstance<py::str>(value) || py::isinstance<py::bytes>(value) ||
         py::hasattr(value, "__fspath__");
}

std::filesystem::path ToPath(py::handle value) {
  py::object path = py::module_::import("os").attr("fsdecode")(value);
  return std::filesystem::path(path.cast<std::string>());
}

registration::PointCloud CloudFromArray(py::handle points, const char* name) {
  const DoubleArray a = AsDoubles(points, name);
  if (a.ndim() != 2 || (a.shape(1) != 3 && a.shape(1) != 6)) {
    throw py::value_error(std::string(name) + ": expected an (N, 3) array of points or (N, 6) " +
                          "with normals, got shape " + Shape(a));
  }
  const auto n = static_cast<std::size_t>(a.shape(0));
  const bool with_normals = a.shape(1) == 6;
  const double* data = a.data();
  const std::size_t stride = with_normals ? 6 : 3;
  registration::PointCloud cloud;
  cloud.points.resize(n);
  if (with_normals) cloud.normals.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double* row = data + i * stride;
    cloud.points[i] = Eigen::Vector3d(row[0], row[1], row[2]);
    if (with_normals) {
      const Eigen::Vector3d normal(row[3], row[4], row[5]);
      if (!normal.allFinite() || std::abs(normal.norm() - 1.0) > 1e-3) {
        throw py::value_error(std::string(name) + ": row " + std::to_string(i) +
                              ": the normal (columns 3-5) is not a unit vector");
      }
      cloud.normals[i] = normal;
    }
  }
  return cloud;
}

registration::PointCloud CloudFrom(py::handle cloud, const char* name) {
  if (IsPath(cloud)) return io::ReadPointCloud(ToPath(cloud));
  return CloudFromArray(cloud, name);
}

void SetCovariances(py::handle covariances, const char* name, registration::PointCloud* cloud) {
  if (covariances.is_none()) return;
  const DoubleArray a = AsDoubles(covariances, name);
  if (a.ndim() != 3 || a.shape(1) != 3 || a.shape(2) != 3 ||
      static_cast<std::size_t>(a.shape(0)) != cloud->size()) {
    throw py::value_error(std::string(name) + ": expected an (" + std::to_string(cloud->size()) +
                          ", 3, 3) array, one covariance per point, got shape " + Shape(a));
  }
  cloud->covariances.resize(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    // Row-major in numpy; the matrix is symmetric, but read it as given.
    cloud->covariances[i] =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a.data() + 9 * i);
  }
}

py::array_t<double> ToArray(const std::vector<double>& values) {
  return py::array_t<double>(static_cast<py::ssize_t>(values.size()), values.data());
}

py::array_t<double> ToArray(const std::vector<Eigen::Vector3d>& points) {
  py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  if (!points.empty()) std::memcpy(a.mutable_data(), points.data(), points.size() * 3 * 8);
  return a;
}

py::array_t<double> ViewOf(const std::vector<Eigen::Vector3d>& points, py::handle owner) {
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "Vector3d is 3 packed doubles");
  py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}},
                        {py::ssize_t{3 * sizeof(double)}, py::ssize_t{sizeof(double)}},
                        points.empty() ? nullptr : points.front().data(), owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

Eigen::Isometry3d PoseFrom(py::handle pose, const char* name) {
  const DoubleArray a = AsDoubles(pose, name);
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    throw py::value_error(std::string(name) + ": expected a 4x4 homogeneous transform, got shape " +
                          Shape(a));
  }
  const Eigen::Matrix4d m =
      Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(a.data());
  Eigen::Isometry3d T;
  T.matrix() = m;
  const bool last_row = (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() <= 1e-12;
  if (!last_row || !mapper::IsFiniteRigid(T)) {
    throw py::value_error(std::string(name) +
                          ": not a finite rigid transform (rotation orthonormal within 1e-6, "
                          "determinant +1, last row 0 0 0 1)");
  }
  T.makeAffine();
  return T;
}

py::array_t<double> ToArray(const Eigen::Isometry3d& pose) {
  py::array_t<double> a({4, 4});
  Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(a.mutable_data()) = pose.matrix();
  return a;
}

py::array_t<double> ToArray(const std::vector<Eigen::Isometry3d>& poses) {
  py::array_t<double> a({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
  for (std::size_t i = 0; i < poses.size(); ++i) {
    Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(a.mutable_data() + 16 * i) =
        poses[i].matrix();
  }
  return a;
}

std::vector<Eigen::Isometry3d> PosesFrom(py::handle poses, const char* name) {
  const DoubleArray a = AsDoubles(poses, name);
  if (a.ndim() != 3 || (a.shape(1) != 3 && a.shape(1) != 4) || a.shape(2) != 4) {
    throw py::value_error(std::string(name) + ": expected an (N, 4, 4) or (N, 3, 4) array of " +
                          "poses, got shape " + Shape(a));
  }
  const py::ssize_t rows = a.shape(1);
  std::vector<Eigen::Isometry3d> out(static_cast<std::size_t>(a.shape(0)));
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double* m = a.data() + static_cast<py::ssize_t>(i) * rows * 4;
    Eigen::Matrix4d full = Eigen::Matrix4d::Identity();
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < 4; ++c) full(r, c) = m[r * 4 + c];
    out[i].matrix() = full;
    if ((rows == 4 &&
         !((full.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() <= 1e-12)) ||
        !out[i].linear().allFinite() || !out[i].translation().allFinite()) {
      throw py::value_error(std::string(name) + "[" + std::to_string(i) +
                            "]: not a finite homogeneous transform");
    }
  }
  return out;
}

io::GeodeticOrigin OriginFrom(py::handle origin, const char* name) {
  io::GeodeticOrigin out;
  try {
    if (py::isinstance<py::dict>(origin)) {
      const py::dict d = origin.cast<py::dict>();
      out.latitude_deg = d["latitude"].cast<double>();
      out.longitude_deg = d["longitude"].cast<double>();
      if (d.contains("altitude")) out.altitude_m = d["altitude"].cast<double>();
      return out;
    }
    const auto v = origin.cast<std::vector<double>>();
    if (v.size() == 2 || v.size() == 3) {
      out.latitude_deg = v[0];
      out.longitude_deg = v[1];
      if (v.size() == 3) out.altitude_m = v[2];
      return out;
    }
  } catch (const py::error_already_set&) {
  } catch (const py::cast_error&) {
  }
  throw py::value_error(std::string(name) +
                        ": expected (latitude deg, longitude deg[, altitude m]) or a dict with "
                        "those keys");
}

config::Config ConfigFrom(py::handle config, const py::kwargs& overrides,
                          const std::string& section) {
  std::vector<std::string> texts;
  std::optional<std::filesystem::path> file;
  if (config.is_none()) {
  } else if (IsPath(config)) {
    file = ToPath(config);
  } else if (py::isinstance<py::dict>(config)) {
    Flatten(config, "", &texts);
  } else {
    throw py::value_error("config: expected None, a YAML file's path or a dict of keys, got " +
                          std::string(py::str(py::type::of(config).attr("__name__"))));
  }
  for (auto item : overrides) {
    std::string key = std::string(py::str(item.first));
    for (std::size_t at = key.find("__"); at != std::string::npos; at = key.find("__"))
      key.replace(at, 2, ".");
    if (key.find('.') == std::string::npos) key = section + "." + key;
    texts.push_back(key + "=" + YamlText(item.second, key));
  }
  // A file that cannot be read is an I/O error (OSError) here, not a usage error as in the
  // commands.
  if (file) return config::ParseConfig(io::ReadWholeFile(*file), *file, texts);
  return config::ParseConfig("", {}, texts);
}

py::object ToPython(const nlohmann::json& value) {
  return py::module_::import("json").attr("loads")(value.dump());
}

}  // namespace rovermap::python
