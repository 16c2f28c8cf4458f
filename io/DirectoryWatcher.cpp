#include "io/DirectoryWatcher.hpp"

#include <poll.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <system_error>

namespace rovermap::io {

DirectoryWatcher::DirectoryWatcher(const std::filesystem::path& directory, bool use_inotify) {
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (!use_inotify) return;
  fd_ = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  if (fd_ < 0) return;
  if (::inotify_add_watch(fd_, directory.c_str(), IN_CLOSE_WRITE | IN_MOVED_TO | IN_CREATE) < 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

DirectoryWatcher::~DirectoryWatcher() {
  if (fd_ >= 0) ::close(fd_);
}

bool DirectoryWatcher::Wait(double timeout_s) {
  const int timeout_ms = static_cast<int>(
      std::clamp(std::isfinite(timeout_s) ? timeout_s : 0.0, 0.0, 3600.0) * 1000.0);
  if (fd_ < 0) {
    ::poll(nullptr, 0, timeout_ms);  // a signal ends it early: fine
    return false;
  }
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return false;
  // Drain every queued event: the caller rescans the directory anyway.
  alignas(inotify_event) char buffer[4096];
  while (::read(fd_, buffer, sizeof(buffer)) > 0) {
  }
  return true;
}

}  // namespace rovermap::io
