// Faults while writing (docs/robustness.md, "Faults while writing"): a full disk or a file-size
// limit during any output is reported naming the file (exit status 1, docs/design.md §5), the
// previous version of that file stays byte for byte, and no temporary is left. The fault is
// RLIMIT_FSIZE in a child process: past the limit write() fails with EFBIG, as on a full disk, and
// no root is needed.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "config/Config.hpp"
#include "io/IoError.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "service/Checkpoint.hpp"
#include "service/Outputs.hpp"
#include "tests/support/CommandFixture.hpp"

namespace fs = std::filesystem;
using namespace rovermap;
using rovermap::testing::DataLines;
using rovermap::testing::Slurp;

namespace {

const fs::path kTinyCloud = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_cloud";    // 5 frames
const fs::path kTinyStereo = fs::path(ROVERMAP_DATASETS_DIR) / "sim_tiny_stereo";  // 3 frames

// The replay outputs in the order mapper::WriteOutputs writes them.
const std::vector<std::string> kOutputs = {"trajectory.tum", "odometry.tum", "drift.csv",
                                           "dem.tif",        "map.bt",       "dem.png",
                                           "drift.png",      "summary.json"};

// From now on no file may grow past `bytes`. Only the soft limit: the process may lift it again.
void LimitFileSize(rlim_t bytes) {
  std::signal(SIGXFSZ, SIG_IGN);  // EFBIG from write(), as a full disk gives ENOSPC
  rlimit limit{};
  ::getrlimit(RLIMIT_FSIZE, &limit);
  limit.rlim_cur = bytes;
  ::setrlimit(RLIMIT_FSIZE, &limit);
}

void LiftFileSizeLimit() {
  rlimit limit{};
  ::getrlimit(RLIMIT_FSIZE, &limit);
  limit.rlim_cur = limit.rlim_max;
  ::setrlimit(RLIMIT_FSIZE, &limit);
}

struct ChildResult {
  int status = -1;  ///< exit status, 128 + signal, or -1 if it had to be killed
  std::string message;
};

// Reads `fd` to its end (or until `timeout_s`), then reaps `pid`. `tick` is called about every
// 50 ms while the child runs (to signal it).
ChildResult Collect(pid_t pid, int fd, double timeout_s, const std::function<void()>& tick = {}) {
  ChildResult r;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  char chunk[4096];
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) > 0) {
      const ssize_t n = ::read(fd, chunk, sizeof(chunk));
      if (n <= 0) break;
      r.message.append(chunk, static_cast<std::size_t>(n));
    }
    if (tick) tick();
    if (std::chrono::steady_clock::now() > until) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
      ::close(fd);
      return r;
    }
  }
  ::close(fd);
  int status = 0;
  ::waitpid(pid, &status, 0);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

// Runs `body` in a forked child, as main() would: status 0 if it returns, 1 and the message
// of the io::IoError it throws, 3 for any other exception. GDAL's and OpenMP's thread pools do
// not survive a fork, so everything that writes or maps runs in children, never in the test.
ChildResult InChild(const std::function<void()>& body) {
  int fds[2];
  if (::pipe(fds) != 0) return {};
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    int code = 0;
    std::string message;
    try {
      body();
    } catch (const io::IoError& e) {
      code = 1;
      message = e.what();
    } catch (const std::exception& e) {
      code = 3;
      message = std::string("not an io::IoError: ") + e.what();
    }
    for (std::size_t done = 0; done < message.size();) {
      const ssize_t n = ::write(fds[1], message.data() + done, message.size() - done);
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    ::_exit(code);
  }
  ::close(fds[1]);
  return Collect(pid, fds[0], 120.0);
}

// `rovermap ARGS` with files limited to `limit` bytes and SIGXFSZ at its default (killing):
// rovermap itself must turn the limit into an error. stderr comes back through a pipe (a file
// would be limited too). `stop_when`, polled while it runs, sends SIGTERM once it holds.
ChildResult RunRovermap(const std::vector<std::string>& args, rlim_t limit = RLIM_INFINITY,
                        const std::function<bool()>& stop_when = {}) {
  std::vector<std::string> argv_strings = {ROVERMAP_EXECUTABLE};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  int fds[2];
  if (::pipe(fds) != 0) return {};
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (std::string& a : argv_strings) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::dup2(fds[1], 2);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::close(fds[0]);
    std::signal(SIGXFSZ, SIG_DFL);
    rlimit r{limit, limit};
    ::setrlimit(RLIMIT_FSIZE, &r);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  bool stopped = false;
  return Collect(pid, fds[0], 120.0, [&] {
    if (!stopped && stop_when && stop_when()) {
      ::kill(pid, SIGTERM);
      stopped = true;
    }
  });
}

// Byte equality of two versions of `name`, reported by size (the files are binary).
::testing::AssertionResult Same(const std::string& name, const std::string& a,
                                const std::string& b) {
  if (a == b) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << name << " differs: " << a.size() << " bytes against " << b.size();
}

std::map<std::string, std::string> ReadAll(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const std::string& name : kOutputs) files[name] = Slurp(dir / name);
  return files;
}

// Temporaries (`NAME.tmp-XXXXXX`) anywhere under `dir`.
std::vector<std::string> Temporaries(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.path().filename().string().find(".tmp-") != std::string::npos) {
      found.push_back(entry.path().string());
    }
  }
  return found;
}

mapper::PipelineOptions Defaults() {
  const config::Config c;
  return {c.mapper, c.registration, c.stereo, c.dem, c.octomap, c.terrain};
}

// A Mapper after the first `frames` frames of the tiny cloud sequence.
std::unique_ptr<mapper::Mapper> Mapped(std::size_t frames) {
  const io::SequenceReader reader(kTinyCloud);
  auto m = std::make_unique<mapper::Mapper>(reader.info(), Defaults());
  for (std::size_t k = 0; k < frames; ++k) m->ProcessFrame(reader.Read(k));
  return m;
}

class WriteFaults : public rovermap::testing::CommandFixture {};

// --- Each replay output, written by mapper::WriteOutputs, the limit set just before it. ---

class OutputFault : public WriteFaults, public ::testing::WithParamInterface<std::string> {};

TEST_P(OutputFault, LeavesThePreviousVersionAndNoTemporary) {
  const std::string target = GetParam();
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  const config::Config cfg;
  // The previous version: the first 3 frames.
  ASSERT_EQ(InChild([&] { mapper::WriteOutputs(out, *Mapped(3), {}, cfg.eval); }).status, 0);
  const auto before = ReadAll(out);
  const rlim_t limit = before.at(target).size() / 2;
  ASSERT_GT(limit, 0u);

  // The new version (5 frames) cannot be written past half the previous one's size.
  const auto at = std::find(kOutputs.begin(), kOutputs.end(), target);
  const ChildResult r = InChild([&] {
    const auto mapped = Mapped(5);
    if (at == kOutputs.begin()) LimitFileSize(limit);
    mapper::WriteOutputs(out, *mapped, {}, cfg.eval, [&](const std::string& written) {
      if (at != kOutputs.begin() && written == *(at - 1)) LimitFileSize(limit);
    });
  });
  EXPECT_EQ(r.status, 1) << r.message;
  EXPECT_NE(r.message.find((out / target).string()), std::string::npos) << r.message;
  const auto after = ReadAll(out);
  for (auto it = kOutputs.begin(); it != kOutputs.end(); ++it) {
    if (it < at) {
      EXPECT_FALSE(Same(*it, after.at(*it), before.at(*it))) << "not rewritten before " << target;
    } else {
      EXPECT_TRUE(Same(*it, after.at(*it), before.at(*it))) << "not the previous version";
    }
  }
  EXPECT_EQ(Temporaries(out), std::vector<std::string>{});
}

INSTANTIATE_TEST_SUITE_P(EveryOutput, OutputFault, ::testing::ValuesIn(kOutputs),
                         [](const auto& info) {
                           std::string name = info.param;
                           std::replace(name.begin(), name.end(), '.', '_');
                           return name;
                         });

// --- The serve checkpoint, through mapper::Checkpoint. ---

// A journal record cut short is cut off again: the journal still holds the earlier records,
// byte for byte, and a record appended later is not hidden behind a damaged one.
TEST_F(WriteFaults, FailedJournalAppendKeepsTheEarlierRecordsAndTheJournalGoesOn) {
  const fs::path cp_dir = dir_ / "cp";
  const fs::path journal = cp_dir / "journal.bin";
  const ChildResult r = InChild([&] {
    const io::SequenceReader reader(kTinyCloud);
    mapper::Mapper m(reader.info(), Defaults());
    mapper::Checkpoint cp(cp_dir, "config A");
    mapper::DaemonState state;
    for (std::size_t k = 0; k < 3; ++k) {
      const mapper::FrameResult result = m.ProcessFrame(reader.Read(k));
      state.next_index = k + 1;
      if (k == 2) {
        const std::string good = Slurp(journal);
        // The record's header and a few bytes of its payload fit: a torn record.
        LimitFileSize(good.size() + 20);
        try {
          cp.Append(&result, state);
        } catch (const io::IoError& e) {
          if (Slurp(journal) != good) throw std::runtime_error("journal changed by the failure");
          LiftFileSizeLimit();
          cp.Append(&result, state);  // the daemon restarted: frame 2 again
          throw;
        }
        throw std::runtime_error("the append past the limit succeeded");
      }
      cp.Append(&result, state);
    }
  });
  ASSERT_EQ(r.status, 1) << r.message;
  EXPECT_NE(r.message.find(journal.string()), std::string::npos) << r.message;

  // All three frames restore: the record appended after the failure is read.
  const ChildResult restored = InChild([&] {
    const io::SequenceReader reader(kTinyCloud);
    mapper::Mapper m(reader.info(), Defaults());
    mapper::Checkpoint cp(cp_dir, "config A");
    const auto state = cp.Restore(&m, [&](std::size_t k) { return reader.Read(k); });
    if (state.next_index != 3 || m.results().size() != 3 || cp.journal_records() != 3) {
      throw io::IoError("restored " + std::to_string(state.next_index) + " frames, " +
                        std::to_string(cp.journal_records()) + " records");
    }
  });
  EXPECT_EQ(restored.status, 0) << restored.message;
}

TEST_F(WriteFaults, FailedSnapshotKeepsThePreviousOneAndNoTemporary) {
  const fs::path cp_dir = dir_ / "cp";
  const fs::path snapshot = cp_dir / "state.bin";
  const auto save = [&](std::size_t frames, rlim_t limit) {
    return InChild([&] {
      const auto m = Mapped(frames);
      mapper::Checkpoint cp(cp_dir, "config A");
      LimitFileSize(limit);
      cp.Save(*m, {frames, {}, {}});
    });
  };
  ASSERT_EQ(save(2, RLIM_INFINITY).status, 0);
  const std::string previous = Slurp(snapshot);
  const ChildResult r = save(5, previous.size() / 2);
  EXPECT_EQ(r.status, 1) << r.message;
  EXPECT_NE(r.message.find(snapshot.string()), std::string::npos) << r.message;
  EXPECT_TRUE(Same("state.bin", Slurp(snapshot), previous));
  EXPECT_EQ(Temporaries(cp_dir), std::vector<std::string>{});
}

// --- `rovermap replay --force` over a previous run's outputs. ---

class ReplayFault : public WriteFaults {
 protected:
  // OUT holds the stereo sequence's outputs; `reference_` the cloud sequence's, unlimited.
  void SetUp() override {
    WriteFaults::SetUp();
    out_ = dir_ / "out";
    reference_ = dir_ / "reference";
    ASSERT_EQ(RunRovermap({"replay", kTinyStereo.string(), "--out", out_.string()}).status, 0);
    ASSERT_EQ(RunRovermap({"replay", kTinyCloud.string(), "--out", reference_.string()}).status, 0);
    previous_ = ReadAll(out_);
  }

  // Replays the cloud sequence over OUT with files limited to halfway between the largest
  // output before `target` and `target`: the run stops there with status 1 naming it; the
  // files before it are rewritten, `target` and those after it are the previous ones.
  void ExpectStopsAt(const std::string& target) {
    const auto at = std::find(kOutputs.begin(), kOutputs.end(), target);
    std::uintmax_t before = 0;
    for (auto it = kOutputs.begin(); it != at; ++it) {
      before = std::max(before, fs::file_size(reference_ / *it));
    }
    ASSERT_LT(before, fs::file_size(reference_ / target)) << "an earlier output would fail first";
    const rlim_t limit = (before + fs::file_size(reference_ / target)) / 2;
    const ChildResult r =
        RunRovermap({"replay", kTinyCloud.string(), "--out", out_.string(), "--force"}, limit);
    EXPECT_EQ(r.status, 1) << r.message;
    EXPECT_NE(r.message.find((out_ / target).string()), std::string::npos) << r.message;
    const auto now = ReadAll(out_);
    for (auto it = kOutputs.begin(); it != kOutputs.end(); ++it) {
      EXPECT_EQ(Same(*it, now.at(*it), previous_.at(*it)), it >= at)
          << *it << (it < at ? " was not rewritten" : " is not the previous version");
    }
    EXPECT_EQ(Temporaries(out_), std::vector<std::string>{});
  }

  fs::path out_;
  fs::path reference_;
  std::map<std::string, std::string> previous_;
};

TEST_F(ReplayFault, FirstOutputTrajectoryTum) { ExpectStopsAt("trajectory.tum"); }

TEST_F(ReplayFault, DriftCsv) { ExpectStopsAt("drift.csv"); }

// GDAL 3.6 did not report the short write: a truncated dem.tif replaced the previous one.
TEST_F(ReplayFault, DemTif) { ExpectStopsAt("dem.tif"); }

// --- `rovermap mosaic --force` over a previous mosaic: the COG, then its report m.json. ---

class MosaicFault : public WriteFaults {
 protected:
  void SetUp() override {
    WriteFaults::SetUp();
    out_ = dir_ / "out";
    fs::create_directories(out_);
  }

  // `rovermap mosaic INPUTS --out FOLDER/m.tif --force` (created FOLDER), without
  // co-registration, files limited to `limit` bytes.
  static ChildResult Mosaic(const std::vector<fs::path>& inputs, const fs::path& folder,
                            rlim_t limit = RLIM_INFINITY, const std::string& set = "") {
    fs::create_directories(folder);
    std::vector<std::string> args = {"mosaic"};
    for (const fs::path& input : inputs) args.push_back(input.string());
    args.insert(args.end(), {"--out", (folder / "m.tif").string(), "--force", "--set",
                             "mosaic.coregister=false"});
    if (!set.empty()) args.insert(args.end(), {"--set", set});
    return RunRovermap(args, limit);
  }

  // The mosaic of `inputs` over the previous one in OUT, with files limited to `limit` bytes:
  // status 1 naming `target`; the previous m.tif, m.json and terrain layers byte for byte,
  // nothing else.
  void ExpectFailsKeepingThePrevious(const std::vector<fs::path>& inputs, rlim_t limit,
                                     const std::string& target) {
    const std::string cog = Slurp(out_ / "m.tif");
    const std::string report = Slurp(out_ / "m.json");
    const bool had_terrain = fs::exists(out_ / "m_terrain.tif");
    const std::string terrain = had_terrain ? Slurp(out_ / "m_terrain.tif") : "";
    ASSERT_FALSE(cog.empty());
    const ChildResult r = Mosaic(inputs, out_, limit);
    EXPECT_EQ(r.status, 1) << r.message;
    EXPECT_NE(r.message.find((out_ / target).string()), std::string::npos) << r.message;
    EXPECT_TRUE(Same("m.tif", Slurp(out_ / "m.tif"), cog));
    EXPECT_TRUE(Same("m.json", Slurp(out_ / "m.json"), report));
    if (had_terrain) {
      EXPECT_TRUE(Same("m_terrain.tif", Slurp(out_ / "m_terrain.tif"), terrain));
    }
    std::vector<std::string> left;  // the temporaries are .m.tif.staging-*, .m.tif.tmp-*, ...
    for (const auto& entry : fs::directory_iterator(out_))
      left.push_back(entry.path().filename().string());
    std::sort(left.begin(), left.end());
    std::vector<std::string> kept = {"m.json", "m.tif"};
    if (had_terrain) kept.insert(kept.end(), {"m_terrain.png", "m_terrain.tif"});
    EXPECT_EQ(left, kept);
    last_message_ = r.message;
  }

  fs::path out_;
  std::string last_message_;
};

// The previous mosaic is of one terrain, the new one of two; the limit falls in the staging
// GeoTIFF the tiles go into (half the COG), then in the COG itself (all but its last byte).
TEST_F(MosaicFault, CogFullKeepsThePreviousMosaic) {
  const std::vector<fs::path> inputs = {kTinyCloud / "terrain.tif", kTinyStereo / "terrain.tif"};
  ASSERT_EQ(Mosaic({inputs[0]}, out_).status, 0);
  const ChildResult reference = Mosaic(inputs, dir_ / "reference");
  ASSERT_EQ(reference.status, 0) << reference.message;
  const rlim_t size = fs::file_size(dir_ / "reference" / "m.tif");
  ExpectFailsKeepingThePrevious(inputs, size / 2, "m.tif");
  EXPECT_NE(last_message_.find("staging GeoTIFF"), std::string::npos) << last_message_;
  // Measured: the staging GeoTIFF (256-cell tiles, no overviews) is the smaller file.
  ExpectFailsKeepingThePrevious(inputs, size - 1, "m.tif");
  EXPECT_NE(last_message_.find("cannot write the COG"), std::string::npos) << last_message_;
}

// The COG is renamed into place only once m.json is written: a full disk on m.json
// keeps the previous COG too. A report outgrows its COG with many inputs: the previous mosaic
// is of 23 small DEMs, the new one of 24 (a longer report, the COG of the same size).
TEST_F(MosaicFault, ReportFullKeepsThePreviousMosaicAndReport) {
  ASSERT_EQ(
      Mosaic({kTinyCloud / "terrain.tif"}, dir_ / "small", RLIM_INFINITY, "mosaic.cell_size_m=3")
          .status,
      0);
  std::vector<fs::path> inputs;
  for (int k = 0; k < 24; ++k) {
    inputs.push_back(dir_ / ("dem" + std::to_string(k) + ".tif"));
    fs::copy_file(dir_ / "small" / "m.tif", inputs.back());
  }
  ASSERT_EQ(Mosaic({inputs.begin(), inputs.end() - 1}, out_).status, 0);
  const rlim_t cog = fs::file_size(out_ / "m.tif");
  const rlim_t report = fs::file_size(out_ / "m.json");
  ASSERT_LT(cog, report) << "the limit must fall on m.json, not on the COG";
  ExpectFailsKeepingThePrevious(inputs, (cog + report) / 2, "m.json");
}

// --- `rovermap serve`: it stops, exit 1 naming the file (docs/serve.md); a restart loses
// nothing. ---

class ServeFault : public WriteFaults {
 protected:
  void SetUp() override {
    WriteFaults::SetUp();
    inbox_ = dir_ / "inbox";
    out_ = dir_ / "out";
  }

  // Frames [from, to) of the tiny cloud sequence into the inbox, with their .gt and .odom.
  void Drop(std::size_t from, std::size_t to) {
    fs::create_directories(inbox_ / "frames");
    fs::copy_file(kTinyCloud / "sequence.yaml", inbox_ / "sequence.yaml",
                  fs::copy_options::skip_existing);
    const auto odometry = DataLines(kTinyCloud / "odometry.tum");
    const auto truth = DataLines(kTinyCloud / "groundtruth.tum");
    for (std::size_t k = from; k < to; ++k) {
      char stem[16];
      std::snprintf(stem, sizeof(stem), "%06zu", k);
      const fs::path frame = inbox_ / "frames" / stem;
      fs::copy_file(kTinyCloud / "frames" / (std::string(stem) + ".ply"), frame.string() + ".ply");
      std::ofstream(frame.string() + ".gt") << truth.at(k) << "\n";
      std::ofstream(frame.string() + ".odom") << odometry.at(k) << "\n";
    }
  }

  ChildResult Serve(const std::vector<std::string>& sets, rlim_t limit = RLIM_INFINITY,
                    std::size_t stop_at = 0) {
    std::vector<std::string> args = {"serve",
                                     "--inbox",
                                     inbox_.string(),
                                     "--out",
                                     out_.string(),
                                     "--set",
                                     "serve.poll_interval_s=0.05"};
    for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
    // A run that failed may have left a status.json ahead of its last publication (the frames
    // go on while a publication is written): wait for this run's own.
    if (stop_at > 0) fs::remove(out_ / "status.json");
    const auto reached = [this, stop_at] {
      const nlohmann::json s = nlohmann::json::parse(Slurp(out_ / "status.json"), nullptr, false);
      return !s.is_discarded() && s.is_object() && s.value("next_frame", std::size_t{0}) >= stop_at;
    };
    return RunRovermap(args, limit, stop_at > 0 ? std::function<bool()>(reached) : nullptr);
  }

  // A restart without the limit resumes, takes the rest and, stopped, publishes what an
  // uninterrupted replay writes; every frame is logged done once over `first_log` and it.
  void ExpectRestartLosesNothing(const std::vector<std::string>& sets,
                                 const std::string& first_log) {
    const ChildResult again = Serve(sets, RLIM_INFINITY, 5);
    EXPECT_EQ(again.status, 0) << again.message;
    EXPECT_NE(again.message.find("serve: resumed at frame"), std::string::npos) << again.message;
    const fs::path replay = dir_ / "replay";
    ASSERT_EQ(RunRovermap({"replay", kTinyCloud.string(), "--out", replay.string()}).status, 0);
    for (const char* name : {"trajectory.tum", "map.bt"}) {
      EXPECT_TRUE(Same(name, Slurp(out_ / name), Slurp(replay / name)));
    }
    // "serve: frame 3 registered, 12 ms, 0 waiting" (or first, partial, fallback).
    std::map<std::size_t, int> done;
    std::istringstream lines(first_log + again.message);
    for (std::string line; std::getline(lines, line);) {
      std::istringstream words(line);
      std::string serve, frame, status;
      std::size_t index = 0;
      if (!(words >> serve >> frame >> index >> status) || serve != "serve:" || frame != "frame")
        continue;
      if (!status.empty() && status.back() == ',') status.pop_back();
      if (status == "first" || status == "registered" || status == "partial" ||
          status == "fallback")
        ++done[index];
    }
    EXPECT_EQ(done, (std::map<std::size_t, int>{{0, 1}, {1, 1}, {2, 1}, {3, 1}, {4, 1}}))
        << first_log << again.message;
  }

  fs::path inbox_;
  fs::path out_;
};

// The journal fills up after a few frames: the daemon stops; the records before hold.
TEST_F(ServeFault, JournalFullStopsTheDaemonAndTheRestartLosesNothing) {
  Drop(0, 5);
  // Room for status.json (340 bytes) and two of the five frames' records (1770 bytes each,
  // measured); no snapshot or publication before the journal is full.
  const std::vector<std::string> sets = {"serve.checkpoint_every=100", "serve.publish_every=100"};
  const rlim_t limit = 4500;
  const ChildResult r = Serve(sets, limit);
  EXPECT_EQ(r.status, 1) << r.message;
  const fs::path journal = out_ / "checkpoint" / "journal.bin";
  EXPECT_NE(r.message.find(journal.string()), std::string::npos) << r.message;
  EXPECT_GT(fs::file_size(journal), 0u);
  EXPECT_LE(fs::file_size(journal), limit);
  EXPECT_EQ(Temporaries(out_), std::vector<std::string>{});
  ExpectRestartLosesNothing(sets, r.message);
}

TEST_F(ServeFault, SnapshotFullStopsTheDaemonKeepingThePreviousState) {
  Drop(0, 3);
  const std::vector<std::string> sets = {"serve.checkpoint_every=2", "serve.checkpoint_share=0",
                                         "serve.publish_every=100"};
  const ChildResult first = Serve(sets, RLIM_INFINITY, 3);
  ASSERT_EQ(first.status, 0) << first.message;
  const fs::path snapshot = out_ / "checkpoint" / "state.bin";
  const std::string previous = Slurp(snapshot);
  ASSERT_FALSE(previous.empty());

  Drop(3, 5);  // two frames: a snapshot is due after them
  const ChildResult r = Serve(sets, previous.size() / 2);
  EXPECT_EQ(r.status, 1) << r.message;
  EXPECT_NE(r.message.find(snapshot.string()), std::string::npos) << r.message;
  EXPECT_TRUE(Same("state.bin", Slurp(snapshot), previous));
  EXPECT_EQ(Temporaries(out_), std::vector<std::string>{});
  ExpectRestartLosesNothing(sets, first.message + r.message);
}

TEST_F(ServeFault, PublicationFullStopsTheDaemonKeepingThePreviousOutputs) {
  Drop(0, 3);
  const std::vector<std::string> sets = {"serve.checkpoint_every=100", "serve.publish_every=2"};
  const ChildResult first = Serve(sets, RLIM_INFINITY, 3);
  ASSERT_EQ(first.status, 0) << first.message;
  const auto previous = ReadAll(out_);

  // dem.tif is the first output larger than the limit; the outputs before it are rewritten.
  Drop(3, 5);
  const rlim_t limit = previous.at("dem.tif").size() / 2;
  const ChildResult r = Serve(sets, limit);
  EXPECT_EQ(r.status, 1) << r.message;
  EXPECT_NE(r.message.find((out_ / "dem.tif").string()), std::string::npos) << r.message;
  const auto now = ReadAll(out_);
  EXPECT_FALSE(Same("trajectory.tum", now.at("trajectory.tum"), previous.at("trajectory.tum")));
  for (const char* kept : {"dem.tif", "map.bt", "dem.png", "drift.png", "summary.json"}) {
    EXPECT_TRUE(Same(kept, now.at(kept), previous.at(kept)));
  }
  EXPECT_EQ(Temporaries(out_), std::vector<std::string>{});
  ExpectRestartLosesNothing(sets, first.message + r.message);
}

}  // namespace
