#pragma once

// Internal to config/: the table of keys behind LoadConfig and DumpYaml. It includes yaml-cpp,
// so nothing outside config/ may include it.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "config/Config.hpp"
#include "io/FileUtil.hpp"
#include "io/SequenceYaml.hpp"

namespace rovermap::config::detail {

/// A value was rejected. The message says why ("must be > 0 (got -3)"); the caller prefixes
/// the file, line and key.
class ValueError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One dotted key: how to read it into a Config and how to print its current value.
struct KeyEntry {
  std::string key;  ///< "registration.max_iterations"
  std::string doc;  ///< "[count] ...": the comment DumpYaml writes after the value
  // The same parts apart, for the reference page (config/KeyReference.hpp).
  std::string unit;   ///< "m", "count"; "" for switches, enumerations, names and text
  std::string help;   ///< the doc without its unit and range
  std::string valid;  ///< what the parser accepts: "> 0", "integer in [1, 63]", "one of: a, b"
  std::function<void(const YAML::Node&, Config&)> parse;  ///< @throw ValueError
  std::function<std::string(const Config&)> print;        ///< YAML text that parses back
};

/// Every key, grouped by section, in DumpYaml order.
const std::vector<KeyEntry>& Registry();

/// A check between keys, made once every source is applied (LoadConfig), in this order.
struct KeyRule {
  std::string key;    ///< the key its message names
  std::string valid;  ///< what the reference adds to that key's valid values
  /// nullopt when met, else the message after "KEY: "
  std::function<std::optional<std::string>(const Config&)> check;
};

/// Every rule between keys.
const std::vector<KeyRule>& Rules();

/// The dotted keys `file` sets, in the file's order (its values are not checked against each
/// other: LoadConfig does that). @throw ConfigError as LoadConfig.
std::vector<std::string> KeysSetIn(const std::filesystem::path& file);

// Shared with io/SequenceYaml: one file reader, one image size limit.
using io::kMaxImagePixels;
using io::kMaxImageSide;
using io::ReadText;

/// Most frames `simulate` makes (it holds about 1 kB per frame).
constexpr int kMaxSimFrames = 100000;

/// The valid range of a number; each end open or closed, infinite when absent.
struct Bounds {
  double lo = -std::numeric_limits<double>::infinity();
  bool lo_open = false;
  double hi = std::numeric_limits<double>::infinity();
  bool hi_open = false;
};
inline Bounds AnyValue() { return {}; }
inline Bounds AtLeast(double lo) { return {lo, false}; }
inline Bounds GreaterThan(double lo) { return {lo, true}; }
/// (lo, hi]
inline Bounds OpenClosed(double lo, double hi) { return {lo, true, hi, false}; }
/// [lo, hi)
inline Bounds ClosedOpen(double lo, double hi) { return {lo, false, hi, true}; }
/// "> 0", "in (0, 1]", or "" when unbounded; messages say "must be " + this.
std::string Describe(const Bounds& bounds);

/// Scalar readers: strict (1.5 is not an int, "maybe" is not a bool). @throw ValueError
std::string ScalarText(const YAML::Node& node);
int ParseInt(const YAML::Node& node, const Bounds& bounds);
double ParseDouble(const YAML::Node& node, const Bounds& bounds);
bool ParseBool(const YAML::Node& node);
/// A ROS topic or frame name; a null or "" value is "" when `allow_empty`.
std::string ParseName(const YAML::Node& node, bool allow_empty);
/// `text` in YAML double quotes (backslashes and quotes escaped).
std::string QuoteText(const std::string& text);
/// Shortest text that reads back to the same double, always with a '.' or exponent.
std::string FormatDouble(double value);

/// The spelling of each enumerator in the YAML.
template <typename E>
using EnumNames = std::vector<std::pair<std::string, E>>;

template <typename E>
std::string JoinNames(const EnumNames<E>& names, const std::string& separator = "|") {
  std::string joined;
  for (const auto& [name, value] : names) joined += (joined.empty() ? "" : separator) + name;
  return joined;
}

template <typename E>
E ParseEnum(const YAML::Node& node, const EnumNames<E>& names) {
  const std::string text = ScalarText(node);
  for (const auto& [name, value] : names) {
    if (name == text) return value;
  }
  throw ValueError("must be one of " + JoinNames(names) + " (got " + text + ")");
}

template <typename E>
std::string EnumName(E value, const EnumNames<E>& names) {
  for (const auto& [name, candidate] : names) {
    if (candidate == value) return name;
  }
  throw std::logic_error("config: enumerator without a name in its EnumNames table");
}

/// Adds the keys of one section (`Config::*section`) to a registry, one call per key, so a new
/// struct field needs one line. DumpYaml comments each value with "[unit] doc; range".
template <typename Section>
class SectionKeys {
 public:
  SectionKeys(std::vector<KeyEntry>& keys, std::string name, Section Config::*section)
      : keys_(keys), name_(std::move(name)), section_(section) {}

  void Int(const std::string& key, int Section::*field, const std::string& unit, Bounds bounds,
           const std::string& doc) {
    const std::string range = Describe(bounds);
    Add(
        key, Comment(unit, doc, bounds),
        {unit, doc, range.empty() ? "any integer" : "integer " + range},
        [s = section_, field, bounds](const YAML::Node& n, Config& c) {
          (c.*s).*field = ParseInt(n, bounds);
        },
        [s = section_, field](const Config& c) { return std::to_string((c.*s).*field); });
  }

  void Double(const std::string& key, double Section::*field, const std::string& unit,
              Bounds bounds, const std::string& doc) {
    const std::string range = Describe(bounds);
    Add(
        key, Comment(unit, doc, bounds), {unit, doc, range.empty() ? "any number" : range},
        [s = section_, field, bounds](const YAML::Node& n, Config& c) {
          (c.*s).*field = ParseDouble(n, bounds);
        },
        [s = section_, field](const Config& c) { return FormatDouble((c.*s).*field); });
  }

  /// A non-empty YAML list of numbers, each within `bounds` (a single number is a list of one).
  void DoubleList(const std::string& key, std::vector<double> Section::*field,
                  const std::string& unit, Bounds bounds, const std::string& doc) {
    const std::string each = Describe(bounds).empty() ? "" : "each " + Describe(bounds);
    Add(
        key, "[" + unit + ", list] " + doc + (each.empty() ? "" : "; " + each),
        {unit, doc, "list of numbers" + (each.empty() ? "" : ", " + each)},
        [s = section_, field, bounds](const YAML::Node& n, Config& c) {
          std::vector<double> values;
          if (n.IsSequence()) {
            for (const YAML::Node& item : n) values.push_back(ParseDouble(item, bounds));
          } else {
            values.push_back(ParseDouble(n, bounds));
          }
          if (values.empty()) throw ValueError("expected a non-empty list of numbers");
          (c.*s).*field = std::move(values);
        },
        [s = section_, field](const Config& c) {
          std::string text;
          for (double v : (c.*s).*field) text += (text.empty() ? "" : ", ") + FormatDouble(v);
          return "[" + text + "]";
        });
  }

  /// A topic or frame name: letters, digits and _ / . - (empty only if `allow_empty`).
  void Name(const std::string& key, std::string Section::*field, bool allow_empty,
            const std::string& doc) {
    Add(
        key, "[name] " + doc,
        {"", doc,
         std::string("topic or frame name (letters, digits, _ / . -)") +
             (allow_empty ? " or \"\"" : "")},
        [s = section_, field, allow_empty](const YAML::Node& n, Config& c) {
          (c.*s).*field = ParseName(n, allow_empty);
        },
        [s = section_, field](const Config& c) {
          const std::string& name = (c.*s).*field;
          return name.empty() ? std::string("\"\"") : name;
        });
  }

  /// Free text (any characters, "" allowed), printed double-quoted.
  void Text(const std::string& key, std::string Section::*field, const std::string& doc) {
    Add(
        key, "[text] " + doc, {"", doc, "any text"},
        [s = section_, field](const YAML::Node& n, Config& c) {
          (c.*s).*field = n.IsNull() ? std::string() : ScalarText(n);
        },
        [s = section_, field](const Config& c) { return QuoteText((c.*s).*field); });
  }

  void Bool(const std::string& key, bool Section::*field, const std::string& doc) {
    Add(
        key, "[true|false] " + doc, {"", doc, "true or false"},
        [s = section_, field](const YAML::Node& n, Config& c) { (c.*s).*field = ParseBool(n); },
        [s = section_, field](const Config& c) { return (c.*s).*field ? "true" : "false"; });
  }

  template <typename E>
  void Enum(const std::string& key, E Section::*field, const EnumNames<E>& names,
            const std::string& doc) {
    Add(
        key, "[" + JoinNames(names) + "] " + doc, {"", doc, "one of: " + JoinNames(names, ", ")},
        [s = section_, field, names](const YAML::Node& n, Config& c) {
          (c.*s).*field = ParseEnum(n, names);
        },
        [s = section_, field, names](const Config& c) { return EnumName((c.*s).*field, names); });
  }

 private:
  static std::string Comment(const std::string& unit, const std::string& doc,
                             const Bounds& bounds) {
    const std::string range = Describe(bounds);
    return "[" + unit + "] " + doc + (range.empty() ? "" : "; " + range);
  }

  // The reference's unit, help and valid values of a key.
  struct Parts {
    std::string unit;
    std::string help;
    std::string valid;
  };

  void Add(const std::string& key, std::string doc, Parts parts,
           std::function<void(const YAML::Node&, Config&)> parse,
           std::function<std::string(const Config&)> print) {
    keys_.push_back({name_ + "." + key, std::move(doc), std::move(parts.unit),
                     std::move(parts.help), std::move(parts.valid), std::move(parse),
                     std::move(print)});
  }

  std::vector<KeyEntry>& keys_;
  std::string name_;
  Section Config::*section_;
};

}  // namespace rovermap::config::detail
