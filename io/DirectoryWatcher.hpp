#pragma once
// Waits for files to appear in a directory: inotify where the file system supports it (a
// producer's rename into the inbox wakes the daemon at once), polling otherwise (network and
// some FUSE file systems deliver no inotify events).

#include <filesystem>

namespace rovermap::io {

class DirectoryWatcher {
 public:
  /// Watches `directory` (created if missing) for files created, written or moved in.
  /// `use_inotify` false, or inotify unavailable: Wait sleeps its whole timeout.
  DirectoryWatcher(const std::filesystem::path& directory, bool use_inotify);
  ~DirectoryWatcher();
  DirectoryWatcher(const DirectoryWatcher&) = delete;
  DirectoryWatcher& operator=(const DirectoryWatcher&) = delete;

  /// True when inotify events arrive (else the caller must poll).
  bool watching() const { return fd_ >= 0; }

  /// Returns when something changed in the directory (true), or after `timeout_s` or a signal
  /// (false). Never throws.
  bool Wait(double timeout_s);

 private:
  int fd_ = -1;
};

}  // namespace rovermap::io
