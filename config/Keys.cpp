#include "config/Keys.hpp"

#include <charconv>
#include <cmath>
#include <system_error>

namespace rovermap::config::detail {
namespace {

using registration::Convergence;
using registration::Criterion;
using registration::Geometry;
using registration::RegistrationOptions;
using registration::Residual;
using registration::Solver;

const EnumNames<Geometry> kGeometryNames = {{"surface", Geometry::kSurface},
                                            {"curve", Geometry::kCurve}};
const EnumNames<Criterion> kCriterionNames = {{"nonsymmetric", Criterion::kNonSymmetric},
                                              {"symmetric", Criterion::kSymmetric}};
const EnumNames<Solver> kSolverNames = {{"svd", Solver::kSvd},
                                        {"dual_quaternion", Solver::kDualQuaternion}};
const EnumNames<Residual> kResidualNames = {{"point_to_point", Residual::kPointToPoint},
                                            {"point_to_plane", Residual::kPointToPlane}};
const EnumNames<Convergence> kConvergenceNames = {{"absolute", Convergence::kAbsolute},
                                                  {"relative", Convergence::kRelative}};

// The table. Key names follow the struct fields, except where DESIGN.md §5 fixes the contract
// name (reference_distance). One line per key; DumpYaml and default.yaml follow this order.
std::vector<KeyEntry> BuildRegistry() {
  std::vector<KeyEntry> keys;

  using R = RegistrationOptions;
  SectionKeys<R> reg(keys, "registration", &Config::registration);
  reg.Enum("geometry", &R::geometry, kGeometryNames, "what the points sample (Zhang 1994, 4.2)");
  reg.Enum("criterion", &R::criterion, kCriterionNames, "symmetric: also target -> source");
  reg.Enum("solver", &R::solver, kSolverNames, "closed-form motion (Zhang 1994, App. A/B)");
  reg.Enum("residual", &R::residual, kResidualNames, "point_to_plane needs normals");
  reg.Double("reference_distance", &R::reference_distance_m, "m", AtLeast(0),
             "Zhang's D; 0 = from the point spacing");
  reg.Double("dmax_initial_factor", &R::dmax_initial_factor, "factor", GreaterThan(0),
             "initial Dmax = factor * D (the paper: 20)");
  reg.Int("histogram_bins", &R::histogram_bins, "count", AtLeast(2),
          "distance histogram bins (poor registration)");
  reg.Double("histogram_valley_ratio", &R::histogram_valley_ratio, "ratio", OpenClosed(0, 1),
             "valley used if <= ratio * peak (paper: 0.6)");
  reg.Int("max_iterations", &R::max_iterations, "count", GreaterThan(0), "iteration cap");
  reg.Enum("convergence", &R::convergence, kConvergenceNames, "relative: the paper's 1 % test");
  reg.Double("relative_tolerance", &R::relative_tolerance, "ratio", GreaterThan(0),
             "relative test: |step| / |value| of r and t");
  reg.Double("translation_tolerance_m", &R::translation_tolerance_m, "m", AtLeast(0),
             "absolute test: translation step; 0 = D / 100");
  reg.Double("rotation_tolerance_deg", &R::rotation_tolerance_deg, "deg", AtLeast(0),
             "absolute test: rotation step");
  reg.Double("orientation_threshold_deg", &R::orientation_threshold_deg, "deg", ClosedOpen(0, 180),
             "Theta: max normal/tangent angle; 0 = off");
  reg.Int("normal_neighbors", &R::normal_neighbors, "count", AtLeast(3),
          "PCA normal neighbours if the cloud has none");
  reg.Bool("coarse_to_fine", &R::coarse_to_fine, "subsample the source for the first iterations");
  reg.Int("coarse_iterations", &R::coarse_iterations, "count", AtLeast(0),
          "iterations on the subsampled source");
  reg.Int("coarse_step", &R::coarse_step, "count", AtLeast(1), "source stride while coarse");
  reg.Bool("use_uncertainty", &R::use_uncertainty, "weight, gate pairs by covariances, not Dmax");
  reg.Double("mahalanobis_gate", &R::mahalanobis_gate, "chi^2", GreaterThan(0),
             "on the squared Mahalanobis distance (3 dof, 95 %)");
  reg.Int("min_pairs", &R::min_pairs, "count", AtLeast(3), "fewer pairs after gating = failure");

  return keys;
}

// Shortest round-trip text; no forced ".0", for messages.
std::string FormatNumber(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

void CheckBounds(double value, const Bounds& bounds, const std::string& text) {
  const bool above_lo = bounds.lo_open ? value > bounds.lo : value >= bounds.lo;
  const bool below_hi = bounds.hi_open ? value < bounds.hi : value <= bounds.hi;
  if (!above_lo || !below_hi)
    throw ValueError("must be " + Describe(bounds) + " (got " + text + ")");
}

// YAML allows a leading '+', std::from_chars does not.
const char* SkipPlus(const std::string& text) {
  const char* first = text.data();
  if (text.size() > 1 && text[0] == '+' && text[1] != '-') ++first;
  return first;
}

}  // namespace

const std::vector<KeyEntry>& Registry() {
  static const std::vector<KeyEntry> keys = BuildRegistry();
  return keys;
}

std::string Describe(const Bounds& bounds) {
  const bool has_lo = std::isfinite(bounds.lo);
  const bool has_hi = std::isfinite(bounds.hi);
  if (has_lo && has_hi) {
    return "in " + std::string(bounds.lo_open ? "(" : "[") + FormatNumber(bounds.lo) + ", " +
           FormatNumber(bounds.hi) + (bounds.hi_open ? ")" : "]");
  }
  if (has_lo) return std::string(bounds.lo_open ? "> " : ">= ") + FormatNumber(bounds.lo);
  if (has_hi) return std::string(bounds.hi_open ? "< " : "<= ") + FormatNumber(bounds.hi);
  return "";
}

std::string ScalarText(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return node.Scalar();
    case YAML::NodeType::Sequence:
      throw ValueError("expected a single value (got a list)");
    case YAML::NodeType::Map:
      throw ValueError("expected a single value (got a mapping)");
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      break;
  }
  throw ValueError("missing value");
}

int ParseInt(const YAML::Node& node, const Bounds& bounds) {
  const std::string text = ScalarText(node);
  const char* last = text.data() + text.size();
  long long value = 0;
  const auto [ptr, ec] = std::from_chars(SkipPlus(text), last, value);
  if (ec == std::errc() && ptr == last &&
      (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max())) {
    throw ValueError("too large for an integer (got " + text + ")");
  }
  if (ec != std::errc() || ptr != last) throw ValueError("expected an integer (got " + text + ")");
  CheckBounds(static_cast<double>(value), bounds, text);
  return static_cast<int>(value);
}

double ParseDouble(const YAML::Node& node, const Bounds& bounds) {
  const std::string text = ScalarText(node);
  const char* last = text.data() + text.size();
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(SkipPlus(text), last, value);
  if (ec == std::errc::result_out_of_range && ptr == last) {
    throw ValueError("out of range for a number (got " + text + ")");
  }
  if (ec != std::errc() || ptr != last) throw ValueError("expected a number (got " + text + ")");
  if (!std::isfinite(value)) throw ValueError("must be finite (got " + text + ")");
  CheckBounds(value, bounds, text);
  return value;
}

bool ParseBool(const YAML::Node& node) {
  const std::string text = ScalarText(node);
  bool value = false;
  if (!YAML::convert<bool>::decode(node, value)) {
    throw ValueError("expected true or false (got " + text + ")");
  }
  return value;
}

std::string FormatDouble(double value) {
  std::string text = FormatNumber(value);
  // Keep 20.0 visibly a real number in the YAML.
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

}  // namespace rovermap::config::detail
