#pragma once
// Debian's liboctomap is built with its debug output on: reading or writing a tree prints
// ("Reading octree type OcTree", " done.") on stderr. Library code here never prints, so while
// one of these objects lives, stderr points at /dev/null. Not thread-safe against other
// threads' stderr output (which it would swallow meanwhile).

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>

namespace rovermap::dem {

class QuietStderr {
 public:
  QuietStderr() {
    std::fflush(stderr);
    saved_ = ::dup(2);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    std::fflush(stderr);
    if (saved_ >= 0) {
      ::dup2(saved_, 2);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_ = -1;
};

}  // namespace rovermap::dem
