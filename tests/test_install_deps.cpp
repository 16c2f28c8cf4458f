// scripts/install_deps.sh waits, for a bounded time, for another package manager run that holds
// apt's or dpkg's lock, instead of failing at once. The real locks need root, so apt-get, sudo
// and dpkg-query are stand-ins first on PATH: the fake apt-get (tests/support/fake-apt-get.sh)
// fails with apt 2.6's own lock messages as long as the test says the lock is held, and logs
// how it was called.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/CommandFixture.hpp"

namespace fs = std::filesystem;
using rovermap::testing::Slurp;

namespace {

class InstallDeps : public rovermap::testing::CommandFixture {
 protected:
  void SetUp() override {
    CommandFixture::SetUp();
    bin_ = dir_ / "bin";
    fs::create_directories(bin_);
    fs::copy_file(fs::path(ROVERMAP_SOURCE_DIR) / "tests/support/fake-apt-get.sh",
                  bin_ / "apt-get");
    Script("sudo", "#!/bin/sh\nexec \"$@\"\n");
    Script("dpkg-query", "#!/bin/sh\nexit 1\n");  // nothing installed: every package missing
  }

  void Script(const std::string& name, const std::string& text) {
    std::ofstream(bin_ / name) << text;
    fs::permissions(bin_ / name, fs::perms::owner_all);
  }

  // The lock on `command`'s side (update: apt's lists; install: dpkg's) is held for the next
  // `attempts` calls.
  void Hold(const std::string& command, int attempts) {
    std::ofstream(bin_ / (command + ".held")) << attempts << "\n";
  }

  // Runs the script; @return its exit status (stderr in err_).
  int Run(int wait_s) {
    const std::string cmd = "env PATH=" + bin_.string() + ":\"$PATH\" FAKE_APT=" + bin_.string() +
                            " ROVERMAP_APT_LOCK_WAIT_S=" + std::to_string(wait_s) +
                            " ROVERMAP_APT_LOCK_POLL_S=0.1 timeout 120 bash " +
                            ROVERMAP_SOURCE_DIR + "/scripts/install_deps.sh 2>" +
                            (dir_ / "err").string();
    const int rc = std::system(cmd.c_str());
    err_ = Slurp(dir_ / "err");
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  }

  std::vector<std::string> Calls() const {
    std::vector<std::string> calls;
    std::istringstream in(Slurp(bin_ / "calls"));
    for (std::string line; std::getline(in, line);) calls.push_back(line);
    return calls;
  }

  static int Count(const std::string& text, const std::string& what) {
    int n = 0;
    for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
    return n;
  }

  fs::path bin_;
  std::string err_;
};

TEST_F(InstallDeps, WaitsForTheListsAndDpkgLocksThenInstalls) {
  Hold("update", 2);
  Hold("install", 1);
  EXPECT_EQ(Run(60), 0) << err_;
  const std::vector<std::string> calls = Calls();
  ASSERT_EQ(calls.size(), 5u) << Slurp(bin_ / "calls");
  for (int i = 0; i < 3; ++i) EXPECT_NE(calls[i].find("update"), std::string::npos) << calls[i];
  // First at once; once a lock was seen, apt-get itself waits for dpkg's lock, up to the time
  // left.
  EXPECT_NE(calls[3].find("DPkg::Lock::Timeout=0 install"), std::string::npos) << calls[3];
  EXPECT_NE(calls[4].find("install"), std::string::npos) << calls[4];
  EXPECT_EQ(calls[4].find("DPkg::Lock::Timeout=0 "), std::string::npos) << calls[4];
  // Said once per command that had to wait, naming the lock and the bound.
  EXPECT_EQ(Count(err_, "waiting for it, at most 60 s"), 2) << err_;
  EXPECT_EQ(Count(err_, "/var/lib/apt/lists/lock"), 1) << err_;
  EXPECT_EQ(Count(err_, "/var/lib/dpkg/lock-frontend"), 1) << err_;
  EXPECT_EQ(Count(err_, "gave up"), 0) << err_;
}

TEST_F(InstallDeps, GivesUpAfterTheBoundNamingTheLock) {
  Hold("update", 1000000);
  EXPECT_EQ(Run(1), 1) << err_;
  EXPECT_GE(Calls().size(), 2u);  // retried,
  EXPECT_NE(err_.find("waiting for it, at most 1 s"), std::string::npos) << err_;
  EXPECT_NE(err_.find("gave up waiting for the package manager's lock after 1 s"),
            std::string::npos)
      << err_;
  // and apt's own message is passed on.
  EXPECT_NE(err_.find("E: Unable to lock directory /var/lib/apt/lists/"), std::string::npos)
      << err_;
  EXPECT_EQ(Count(Slurp(bin_ / "calls"), "install"), 0);  // install never tried
}

TEST_F(InstallDeps, OtherErrorsFailAtOnce) {
  std::ofstream(bin_ / "install.error") << "E: Unable to locate package libnot-there-dev\n";
  EXPECT_EQ(Run(60), 1) << err_;
  EXPECT_EQ(Calls().size(), 2u);  // update, then one install
  EXPECT_NE(err_.find("E: Unable to locate package libnot-there-dev"), std::string::npos) << err_;
  EXPECT_EQ(Count(err_, "waiting"), 0) << err_;
}

}  // namespace
