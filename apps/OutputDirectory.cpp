// `--out DIR` checked before any work: a long run must not find at its end that DIR cannot be
// written, nor leave part of its outputs behind.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>

#include "apps/Commands.hpp"
#include "io/IoError.hpp"

namespace rovermap::apps {
namespace {

namespace fs = std::filesystem;

// A path component that is missing or lies under a regular file (ENOTDIR) does not exist yet.
bool NotFound(const std::error_code& error) {
  return error == std::errc::no_such_file_or_directory || error == std::errc::not_a_directory;
}

// DIR does not exist: its nearest existing ancestor must be a directory we may write into.
void CheckCreatable(const fs::path& out) {
  const std::string what = "--out " + out.string() + ": cannot create";
  fs::path ancestor = out;
  for (;;) {
    ancestor = ancestor.parent_path();
    if (ancestor.empty()) ancestor = ".";
    std::error_code error;
    const fs::file_status status = fs::status(ancestor, error);
    if (error && !NotFound(error)) {
      throw io::IoError(what + " (" + ancestor.string() + ": " + error.message() + ")");
    }
    if (!fs::exists(status)) continue;
    if (!fs::is_directory(status)) {
      throw io::IoError(what + " (" + ancestor.string() + " is not a directory)");
    }
    if (::access(ancestor.c_str(), W_OK | X_OK) != 0) {
      throw io::IoError(what + " (" + ancestor.string() + ": " + std::strerror(errno) + ")");
    }
    return;
  }
}

}  // namespace

bool CheckOutputDirectory(const fs::path& out, bool force, const std::string& force_hint) {
  std::error_code error;
  const fs::file_status status = fs::status(out, error);
  if (!fs::exists(status)) {
    CheckCreatable(out);
    return false;
  }
  if (!fs::is_directory(status)) throw UsageError("--out " + out.string() + ": not a directory");
  if (fs::is_empty(out, error)) return false;
  if (!force) {
    throw UsageError("--out " + out.string() + ": directory is not empty (use --force to " +
                     force_hint + ")");
  }
  return true;
}

}  // namespace rovermap::apps
