#include "io/SequenceYaml.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {
namespace {

// Messages: "FILE:LINE: KEY: reason".
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const YAML::Mark& mark, const std::string& key,
                         const std::string& reason) const {
    std::string where = file_;
    if (!mark.is_null()) where += ":" + std::to_string(mark.line + 1);
    throw IoError(where + ": " + (key.empty() ? "" : key + ": ") + reason);
  }

  // A mapping whose keys must all be in `allowed`; returns it.
  YAML::Node Map(const YAML::Node& node, const std::string& key,
                 const std::set<std::string>& allowed) const {
    if (!node.IsMap()) Fail(node.Mark(), key, "expected a mapping");
    for (const auto& item : node) {
      const std::string name = item.first.IsScalar() ? item.first.Scalar() : "?";
      if (allowed.count(name) == 0) {
        std::string list;
        for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
        Fail(item.first.Mark(), Join(key, name), "unknown key (expected one of " + list + ")");
      }
    }
    return node;
  }

  YAML::Node Required(const YAML::Node& map, const std::string& parent,
                      const std::string& name) const {
    const YAML::Node child = map[name];
    if (!child) Fail(map.Mark(), Join(parent, name), "missing");
    return child;
  }

  double Number(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) Fail(node.Mark(), key, "expected a number");
    const std::string& text = node.Scalar();
    const char* first = text.data();
    if (text.size() > 1 && text[0] == '+') ++first;
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(first, text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value)) {
      Fail(node.Mark(), key, "expected a finite number (got " + text + ")");
    }
    return value;
  }

  int Integer(const YAML::Node& node, const std::string& key) const {
    const double value = Number(node, key);
    if (value != std::floor(value) || std::abs(value) > 1e9) {
      Fail(node.Mark(), key, "expected an integer (got " + node.Scalar() + ")");
    }
    return static_cast<int>(value);
  }

  template <std::size_t N>
  std::array<double, N> Vector(const YAML::Node& node, const std::string& key) const {
    if (!node.IsSequence() || node.size() != N) {
      Fail(node.Mark(), key, "expected a list of " + std::to_string(N) + " numbers");
    }
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) out[i] = Number(node[i], key);
    return out;
  }

  std::string Word(const YAML::Node& node, const std::string& key,
                   const std::vector<std::string>& allowed) const {
    std::string list;
    for (const std::string& a : allowed) list += (list.empty() ? "" : "|") + a;
    if (node.IsScalar()) {
      for (const std::string& a : allowed) {
        if (node.Scalar() == a) return a;
      }
      Fail(node.Mark(), key, "must be one of " + list + " (got " + node.Scalar() + ")");
    }
    Fail(node.Mark(), key, "must be one of " + list);
  }

  static std::string Join(const std::string& parent, const std::string& name) {
    return parent.empty() ? name : parent + "." + name;
  }

 private:
  std::string file_;
};

}  // namespace

SequenceYaml ReadSequenceYaml(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    // EACCES on the directory is not "missing": say what the system said.
    if (error && error != std::errc::no_such_file_or_directory) {
      throw IoError(path.string() + ": cannot access (" + error.message() + ")");
    }
    throw IoError(path.string() + ": missing (every sequence needs a sequence.yaml)");
  }
  const std::optional<std::string> text = ReadText(path);
  if (!text) throw IoError(path.string() + ": cannot read");
  return ParseSequenceYaml(*text, path);
}

SequenceYaml ParseSequenceYaml(std::string_view text, const std::filesystem::path& path) {
  const Reader r(path.string());
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    r.Fail(e.mark, "", "invalid YAML: " + e.msg);
  }
  if (!root.IsMap()) r.Fail(root.Mark(), "", "expected a mapping of keys (sensor:, camera:, ...)");
  r.Map(root, "", {"sensor", "camera", "origin", "frame_rate", "body"});

  SequenceYaml out;
  const YAML::Node sensor = r.Map(r.Required(root, "", "sensor"), "sensor",
                                  {"type", "T_body_sensor", "calibration_sigma"});
  out.sensor_type =
      r.Word(r.Required(sensor, "sensor", "type"), "sensor.type", {"stereo", "cloud"});

  const std::string tkey = "sensor.T_body_sensor";
  const YAML::Node T = r.Map(r.Required(sensor, "sensor", "T_body_sensor"), tkey,
                             {"translation", "rotation_rpy_deg", "quaternion"});
  out.translation = r.Vector<3>(r.Required(T, tkey, "translation"), tkey + ".translation");
  if (T["rotation_rpy_deg"] && T["quaternion"]) {
    r.Fail(T.Mark(), tkey, "give rotation_rpy_deg or quaternion, not both");
  }
  if (T["rotation_rpy_deg"]) {
    out.rotation_rpy_deg = r.Vector<3>(T["rotation_rpy_deg"], tkey + ".rotation_rpy_deg");
  } else if (T["quaternion"]) {
    const auto q = r.Vector<4>(T["quaternion"], tkey + ".quaternion");
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (std::abs(norm - 1.0) > 1e-3) {
      r.Fail(T["quaternion"].Mark(), tkey + ".quaternion",
             "not a unit quaternion (norm " + std::to_string(norm) + ")");
    }
    out.quaternion_xyzw = q;
  } else {
    r.Fail(T.Mark(), tkey, "missing rotation_rpy_deg (or quaternion)");
  }

  if (const YAML::Node sigma = sensor["calibration_sigma"]) {
    const std::string key = "sensor.calibration_sigma";
    r.Map(sigma, key, {"rotation_deg", "scale"});
    auto bounded = [&](const char* name, double max, const char* max_text) {
      const YAML::Node node = r.Required(sigma, key, name);
      const double value = r.Number(node, key + "." + name);
      if (!(value >= 0.0 && value <= max)) {
        r.Fail(node.Mark(), key + "." + name, std::string("must be in [0, ") + max_text + "]");
      }
      return value;
    };
    out.calibration_sigma =
        RigCalibrationSigma{bounded("rotation_deg", 10.0, "10"), bounded("scale", 0.2, "0.2")};
  }

  if (const YAML::Node camera = root["camera"]) {
    r.Map(camera, "camera", {"width", "height", "fx", "fy", "cx", "cy", "baseline"});
    CameraModel c;
    auto positive = [&](const char* name) {
      const YAML::Node node = r.Required(camera, "camera", name);
      const double value = r.Number(node, std::string("camera.") + name);
      if (!(value > 0.0)) r.Fail(node.Mark(), std::string("camera.") + name, "must be > 0");
      return value;
    };
    c.width = r.Integer(r.Required(camera, "camera", "width"), "camera.width");
    c.height = r.Integer(r.Required(camera, "camera", "height"), "camera.height");
    if (c.width <= 0) r.Fail(camera["width"].Mark(), "camera.width", "must be > 0");
    if (c.height <= 0) r.Fail(camera["height"].Mark(), "camera.height", "must be > 0");
    // No image beyond OpenCV's decoding limits can ever match: refuse the size before any
    // stage sizes buffers by it.
    if (c.width > kMaxImageSide) {
      r.Fail(camera["width"].Mark(), "camera.width",
             "must be <= " + std::to_string(kMaxImageSide) + " px (got " + std::to_string(c.width) +
                 ")");
    }
    if (c.height > kMaxImageSide) {
      r.Fail(camera["height"].Mark(), "camera.height",
             "must be <= " + std::to_string(kMaxImageSide) + " px (got " +
                 std::to_string(c.height) + ")");
    }
    const long long pixels = static_cast<long long>(c.width) * c.height;
    if (pixels > kMaxImagePixels) {
      r.Fail(camera["width"].Mark(), "camera",
             std::to_string(c.width) + " x " + std::to_string(c.height) + " = " +
                 std::to_string(pixels) + " pixels, more than " + std::to_string(kMaxImagePixels) +
                 " (the largest image OpenCV reads)");
    }
    c.fx = positive("fx");
    c.fy = positive("fy");
    c.baseline_m = positive("baseline");
    c.cx = r.Number(r.Required(camera, "camera", "cx"), "camera.cx");
    c.cy = r.Number(r.Required(camera, "camera", "cy"), "camera.cy");
    if (c.cx < 0 || c.cx > c.width) {
      r.Fail(camera["cx"].Mark(), "camera.cx", "principal point outside the image width");
    }
    if (c.cy < 0 || c.cy > c.height) {
      r.Fail(camera["cy"].Mark(), "camera.cy", "principal point outside the image height");
    }
    out.camera = c;
  } else if (out.sensor_type == "stereo") {
    r.Fail(root.Mark(), "camera", "missing (required for sensor.type: stereo)");
  }

  const YAML::Node origin =
      r.Map(r.Required(root, "", "origin"), "origin", {"latitude", "longitude", "altitude"});
  out.latitude_deg = r.Number(r.Required(origin, "origin", "latitude"), "origin.latitude");
  out.longitude_deg = r.Number(r.Required(origin, "origin", "longitude"), "origin.longitude");
  out.altitude_m = r.Number(r.Required(origin, "origin", "altitude"), "origin.altitude");
  if (std::abs(out.latitude_deg) > 90.0) {
    r.Fail(origin["latitude"].Mark(), "origin.latitude", "must be in [-90, 90]");
  }
  if (std::abs(out.longitude_deg) > 180.0) {
    r.Fail(origin["longitude"].Mark(), "origin.longitude", "must be in [-180, 180]");
  }

  const YAML::Node rate = r.Required(root, "", "frame_rate");
  out.frame_rate_hz = r.Number(rate, "frame_rate");
  if (!(out.frame_rate_hz > 0.0)) r.Fail(rate.Mark(), "frame_rate", "must be > 0 [Hz]");

  if (root["body"]) out.body = r.Word(root["body"], "body", {"earth", "moon", "mars"});
  return out;
}

}  // namespace rovermap::io
