#pragma once
// Whether this test executable is the sanitizer build's (`make test-asan`; GCC defines
// __SANITIZE_ADDRESS__ with -fsanitize=address). The whole-sequence studies replay less there:
// the sanitizers look for memory and undefined behaviour, which repeats of the same code do not
// add to, and the Release suite holds every case to its bounds.

namespace rovermap::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif

}  // namespace rovermap::testing
