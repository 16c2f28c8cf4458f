#pragma once
// A scratch directory private to the running test: CTest runs every test case as its own
// process, in parallel, so fixed names under /tmp would collide between cases.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace rovermap::testing {

/// <tmp>/rovermap_<suite>.<test>.<pid>/ (created; not removed, so a failure can be inspected).
inline std::filesystem::path ScratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = "rovermap_";
  name += info ? std::string(info->test_suite_name()) + "." + info->name() : std::string("global");
  name += "." + std::to_string(::getpid());
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / name;
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace rovermap::testing
