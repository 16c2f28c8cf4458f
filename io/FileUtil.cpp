#include "io/FileUtil.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <system_error>

#include "io/IoError.hpp"

namespace rovermap::io {
namespace {

[[noreturn]] void ThrowErrno(const std::filesystem::path& path, const char* what, int err) {
  throw IoError(path.string() + ": " + what + " (" + std::strerror(err) + ")");
}

// A temporary's name: the file's, then ".tmp-" and kSuffixLength characters of kAlphabet.
constexpr char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz0123456789";
constexpr std::string_view kTemporaryInfix = ".tmp-";
constexpr std::size_t kSuffixLength = 6;

std::string RandomSuffix() {
  std::random_device device;
  std::uniform_int_distribution<int> pick(0, static_cast<int>(sizeof(kAlphabet)) - 2);
  std::string suffix(kSuffixLength, 'x');
  for (char& c : suffix) c = kAlphabet[pick(device)];
  return suffix;
}

}  // namespace

std::optional<std::string> ReadText(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) return std::nullopt;
  std::ostringstream text;
  text << stream.rdbuf();
  if (stream.bad()) return std::nullopt;
  return text.str();
}

FdGuard::~FdGuard() {
  if (fd_ >= 0) ::close(fd_);
}

int FdGuard::Close() {
  const int rc = ::close(fd_);
  fd_ = -1;
  return rc;
}

int WriteAll(int fd, std::string_view data) {
  const char* next = data.data();
  std::size_t left = data.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, next, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    next += n;
    left -= static_cast<std::size_t>(n);
  }
  return 0;
}

std::string ReadWholeFile(const std::filesystem::path& path) {
  FdGuard fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.Get() < 0) ThrowErrno(path, "cannot open file", errno);
  struct stat info {};
  if (::fstat(fd.Get(), &info) != 0) ThrowErrno(path, "cannot stat file", errno);
  if (S_ISDIR(info.st_mode)) throw IoError(path.string() + ": is a directory, not a file");

  std::string data;
  if (S_ISREG(info.st_mode) && info.st_size > 0) {
    data.reserve(static_cast<std::size_t>(info.st_size));
  }
  // Read until EOF rather than trusting st_size: the file may be a pipe or still growing.
  char chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd.Get(), chunk, sizeof(chunk));
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      ThrowErrno(path, "cannot read file", errno);
    }
    data.append(chunk, static_cast<std::size_t>(n));
  }
  return data;
}

void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents, bool flush) {
  CommitTemporaryFile(WriteTemporaryFile(path, contents, flush), path);
}

std::filesystem::path WriteTemporaryFile(const std::filesystem::path& path,
                                         std::string_view contents, bool flush) {
  if (path.empty() || !path.has_filename()) {
    throw IoError(path.string() + ": not a file path");
  }
  std::filesystem::path temp;
  int raw_fd = -1;
  for (int attempt = 0; attempt < 100 && raw_fd < 0; ++attempt) {
    temp = path;
    temp += std::string(kTemporaryInfix) + RandomSuffix();
    // O_EXCL: never clobber another writer's temporary; 0666 lets the umask decide.
    raw_fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (raw_fd < 0 && errno != EEXIST) ThrowErrno(path, "cannot create temporary file", errno);
  }
  if (raw_fd < 0) throw IoError(path.string() + ": cannot create a unique temporary file");

  FdGuard fd(raw_fd);
  const auto fail = [&](const char* what, int err) {
    if (fd.Get() >= 0) fd.Close();
    ::unlink(temp.c_str());
    ThrowErrno(path, what, err);
  };
  if (const int err = WriteAll(fd.Get(), contents); err != 0) fail("cannot write file", err);
  // Flush before the rename so that a crash cannot leave a renamed but empty file.
  if (flush && ::fsync(fd.Get()) != 0) fail("cannot flush file", errno);
  if (fd.Close() != 0) fail("cannot close file", errno);
  return temp;
}

void SyncDirectory(const std::filesystem::path& directory) {
  FdGuard fd(::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (fd.Get() < 0) ThrowErrno(directory, "cannot open directory", errno);
  if (::fsync(fd.Get()) != 0) ThrowErrno(directory, "cannot flush directory", errno);
}

void CommitTemporaryFile(const std::filesystem::path& temp, const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    ::unlink(temp.c_str());
    throw IoError(path.string() + ": cannot rename temporary file into place (" + ec.message() +
                  ")");
  }
}

bool IsTemporaryFileName(std::string_view name) {
  const std::size_t tail = kTemporaryInfix.size() + kSuffixLength;
  if (name.size() <= tail) return false;  // a temporary of a file with a name
  const std::string_view suffix = name.substr(name.size() - kSuffixLength);
  return name.substr(name.size() - tail, kTemporaryInfix.size()) == kTemporaryInfix &&
         suffix.find_first_not_of(std::string_view(kAlphabet, sizeof(kAlphabet) - 1)) ==
             std::string_view::npos;
}

std::vector<std::filesystem::path> RemoveTemporaryFiles(const std::filesystem::path& directory) {
  std::vector<std::filesystem::path> removed;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    std::error_code entry_ec;
    if (!entry.is_regular_file(entry_ec) || !IsTemporaryFileName(entry.path().filename().string()))
      continue;
    if (std::filesystem::remove(entry.path(), entry_ec)) removed.push_back(entry.path());
  }
  std::sort(removed.begin(), removed.end());
  return removed;
}

}  // namespace rovermap::io
