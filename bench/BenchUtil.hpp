#pragma once
// Small helpers shared by the benchmark harnesses.

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rovermap::bench {

/// The first three fields of /proc/loadavg: the machine is shared, so say how busy it was.
inline std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  if (!(in >> a >> b >> c)) return "n/a";
  return a + " " + b + " " + c;
}

inline double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The value after option argv[*i] (advances *i). @throw std::invalid_argument if missing.
inline std::string OptionValue(int argc, char** argv, int* i) {
  if (*i + 1 >= argc) throw std::invalid_argument(std::string(argv[*i]) + " needs a value");
  return argv[++*i];
}

/// `--runs N` with N >= 1.
inline int ParseRuns(const std::string& text) {
  const int runs = std::stoi(text);
  if (runs < 1) throw std::invalid_argument("--runs must be at least 1");
  return runs;
}

/// As the rovermap command does (apps/main.cpp): OpenMP waits passively unless the environment
/// says otherwise (OMP_WAIT_POLICY is read at start-up, so the process re-executes itself once
/// with it set). Call first thing in main.
inline void WaitPassivelyUnlessTold(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") == nullptr) {
    ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
    ::execv("/proc/self/exe", argv);
  }
}

}  // namespace rovermap::bench
