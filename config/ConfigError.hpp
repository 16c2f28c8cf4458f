#pragma once

#include <stdexcept>
#include <string>

namespace rovermap::config {

/// A configuration file, key or value was rejected. The message names the key and, when the
/// value came from a file, the file and line: `config.yaml:3: registration.max_iterations: must
/// be > 0 (got -3)`. Front ends report it as a usage error (exit status 2).
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace rovermap::config
