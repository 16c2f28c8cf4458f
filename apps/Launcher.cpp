// The `rovermap` command. A one-shot `register` runs here, in a program that loads a handful of
// shared libraries; every other command line runs in rovermap-full, which loads GDAL and OpenCV's
// image codecs, a start-up longer than a one-shot registration's own work (docs/benchmarks.md,
// "One-shot registration"), and which this process becomes (execv: the same process, its
// arguments and exit status unchanged).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>

#include "apps/Commands.hpp"
#include "apps/Startup.hpp"
#include "core/Heap.hpp"

namespace fs = std::filesystem;
using namespace rovermap::apps;

namespace {

// rovermap-full beside this program (the build tree), else in ../libexec/rovermap/ (installed).
fs::path FullProgram() {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  const fs::path dir = error ? fs::path(".") : self.parent_path();
  const fs::path beside = dir / "rovermap-full";
  if (fs::exists(beside, error)) return beside;
  return dir.parent_path() / "libexec" / "rovermap" / "rovermap-full";
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGXFSZ, SIG_IGN);  // as rovermap-full (see main.cpp)
  if (RunsInLauncher(argc, argv)) {
    // OpenMP threads that wait passively: spinning, a one-shot registration of the bunny took
    // 110-220 ms instead of 70-85 whenever another job shared the 2 cores, and gained nothing on
    // a quiet machine (docs/benchmarks.md, "One-shot registration"). libgomp reads the policy
    // before main, so it is set by running this small program again (once; a user's setting is
    // kept).
    RunAgainWithPassiveOpenMp(argv);
    // Freed blocks reused instead of mapped afresh: the trees and the sample's tables come and
    // go, and every fresh page is a fault.
    rovermap::core::KeepFreedMemoryInHeap();
    CLI::App app{"rovermap: incremental DEM mapping from correlation-stereo frames"};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Help for every subcommand");  // its messages name it
    RegisterArgs args;
    AddRegisterCommand(&app, &args);
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      const int code = app.exit(e);
      return code == 0 ? kExitOk : kExitUsage;
    }
    return RunReportingErrors([&] { return RunRegister(args, PreviewWriter()); });
  }
  // Set here, so that rovermap-full need not run itself again for it (see main.cpp).
  if (std::getenv("OMP_WAIT_POLICY") == nullptr && WaitsPassively(argc, argv))
    ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
  const fs::path full = FullProgram();
  ::execv(full.c_str(), argv);
  std::cerr << "rovermap: cannot run " << full.string() << ": " << std::strerror(errno) << "\n";
  return kExitFailure;
}
