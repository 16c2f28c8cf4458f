#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rovermap::io {

/// Closes a file descriptor on every exit path, including exceptions.
class FdGuard {
 public:
  explicit FdGuard(int fd) : fd_(fd) {}
  ~FdGuard();
  FdGuard(const FdGuard&) = delete;
  FdGuard& operator=(const FdGuard&) = delete;
  int Get() const { return fd_; }
  /// Closes explicitly so that a deferred write error (NFS, full disk) is seen.
  /// @return ::close's result.
  int Close();

 private:
  int fd_;
};

/// Writes all of `data` to `fd`, through short writes and interrupted ones (EINTR).
/// @return 0, or the errno of the write that failed.
[[nodiscard]] int WriteAll(int fd, std::string_view data);

/// Reads a whole file into memory (binary, unchanged bytes).
/// Throws IoError naming the file if it is missing, a directory or unreadable.
std::string ReadWholeFile(const std::filesystem::path& path);

/// The bytes of `path`; nullopt if it cannot be opened or read (the caller names the file;
/// errno says why). For the YAML readers, whose messages differ from ReadWholeFile's.
std::optional<std::string> ReadText(const std::filesystem::path& path);

/// Writes `contents` to `path` atomically: the bytes go to `<path>.tmp-XXXXXX` in the same
/// directory, are flushed to disk, and the temporary is renamed over `path`. Readers therefore
/// see either the old file or the complete new one, never a partial file. On failure the
/// temporary is removed and IoError (naming `path`) is thrown.
/// `flush` false skips the flush to disk: still atomic for readers, but after a power loss the
/// file may be empty (for files rewritten often whose loss costs nothing, as status.json).
void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents,
                         bool flush = true);

/// The first half of WriteFileAtomically: `contents` written and flushed to a new
/// `<path>.tmp-XXXXXX`, whose name is returned for CommitTemporaryFile.
std::filesystem::path WriteTemporaryFile(const std::filesystem::path& path,
                                         std::string_view contents, bool flush = true);

/// Flushes a directory's entries (a rename in it) to disk, for durability across power loss.
/// @throw IoError naming the directory.
void SyncDirectory(const std::filesystem::path& directory);

/// Renames a finished temporary file over `path` (the last step of every atomic write).
/// On failure the temporary is removed and IoError (naming `path`) is thrown.
void CommitTemporaryFile(const std::filesystem::path& temp, const std::filesystem::path& path);

/// Whether `name` is one of WriteTemporaryFile's temporaries: `<file>.tmp-XXXXXX`, six of
/// [a-z0-9] after ".tmp-".
bool IsTemporaryFileName(std::string_view name);

/// Removes the temporaries (IsTemporaryFileName) directly in `directory`: those a killed writer
/// left, never renamed. Only call it while no other writer works there.
/// @return the files removed, sorted; none when `directory` does not exist or cannot be read.
std::vector<std::filesystem::path> RemoveTemporaryFiles(const std::filesystem::path& directory);

}  // namespace rovermap::io
