#pragma once
// How the `rovermap` command starts (apps/Launcher.cpp, apps/main.cpp).

#include <unistd.h>

#include <cstdlib>
#include <string>

namespace rovermap::apps {

/// The subcommands that keep OpenMP's threads busy frame after frame: they run with
/// OMP_WAIT_POLICY=PASSIVE unless the environment says otherwise (see main.cpp).
inline bool RunsManyFrames(int argc, char** argv) {
  if (argc < 2) return false;
  const std::string command = argv[1];
  return command == "replay" || command == "serve" || command == "campaign" ||
         command == "mosaic" || command == "simulate";
}

/// The subcommands whose OpenMP threads wait passively unless the environment says otherwise:
/// those that run many frames, and `register` (docs/benchmarks.md, "One-shot registration").
inline bool WaitsPassively(int argc, char** argv) {
  return RunsManyFrames(argc, argv) || (argc >= 2 && std::string(argv[1]) == "register");
}

/// Runs this program again with OMP_WAIT_POLICY=PASSIVE unless the environment sets it (libgomp
/// reads it when it loads, before main). Returns only when it did not: set already, or execv
/// failed, in which case the program goes on as it is.
inline void RunAgainWithPassiveOpenMp(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
  ::execv("/proc/self/exe", argv);
}

/// Whether the launcher runs this command line itself: `register` without --preview (a PNG:
/// OpenCV's image codecs) and without help (whose text rovermap-full prints for every
/// subcommand). Anything else is rovermap-full's.
inline bool RunsInLauncher(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) != "register") return false;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;  // what follows is positional
    if (arg == "--preview" || arg.rfind("--preview=", 0) == 0 || arg == "-h" || arg == "--help" ||
        arg == "--help-all")
      return false;
  }
  return true;
}

}  // namespace rovermap::apps
