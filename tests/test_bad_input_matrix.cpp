// The bad-input matrix (docs/robustness.md, "Bad input"): one test per row, each running the real
// `rovermap` command on a copy of bundled data broken one way, and checking the exit status
// (docs/design.md §5), that stderr names the file (and line or key) at fault, and what is left in
// the output: nothing, no temporary, or, for a bad frame, the full set with the frame flagged.
// Rows are named Command_BadInput and kept in that table's order.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/DemWriting.hpp"
#include "tests/support/ServeFixture.hpp"

namespace fs = std::filesystem;
using rovermap::testing::CommandResult;
using rovermap::testing::Constant;
using rovermap::testing::DataLines;
using rovermap::testing::NorthUp;
using rovermap::testing::Slurp;
using rovermap::testing::WriteDem;

namespace {

const fs::path kData = ROVERMAP_DATASETS_DIR;
const fs::path kTinyCloud = kData / "sim_tiny_cloud";    // 5 PLY frames
const fs::path kTinyStereo = kData / "sim_tiny_stereo";  // 3 stereo pairs, 480x360
const fs::path kBunny045 = kData / "stanford_bunny" / "bun045.ply";
const fs::path kBunny000 = kData / "stanford_bunny" / "bun000.ply";
const fs::path kPng = kTinyStereo / "frames" / "000000.left.png";
const fs::path kTerrain = kTinyCloud / "terrain.tif";  // a DEM GeoTIFF, 12 m square, UTM 32N
const std::vector<std::string> kReplayOutputs = {"dem.tif",      "map.bt",    "trajectory.tum",
                                                 "odometry.tum", "drift.csv", "summary.json",
                                                 "dem.png",      "drift.png"};

void Put(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

// Replaces the first `from` in the file by `to`; fails the row if `from` is not there.
void Edit(const fs::path& p, const std::string& from, const std::string& to) {
  std::string text = Slurp(p);
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << p;
  Put(p, text.replace(at, from.size(), to));
}

// 1-based number of the first line holding `needle` (0 if none).
int LineOf(const fs::path& p, const std::string& needle) {
  std::istringstream in(Slurp(p));
  int n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (line.find(needle) != std::string::npos) return n;
  }
  return 0;
}

// Physical line `n` (1-based) of a text file.
std::string Line(const fs::path& p, int n) {
  std::istringstream in(Slurp(p));
  std::string line;
  for (int i = 0; i < n && std::getline(in, line); ++i) {
  }
  return line;
}

void SetLine(const fs::path& p, int n, const std::string& text) {
  std::istringstream in(Slurp(p));
  std::string out;
  int i = 0;
  for (std::string line; std::getline(in, line);) out += (++i == n ? text : line) + "\n";
  Put(p, out);
}

void KeepBytes(const fs::path& p, std::size_t bytes) { Put(p, Slurp(p).substr(0, bytes)); }

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// chmod 000 for the scope of a row; `read_only`: chmod 555, a directory that may be listed and
// entered but not written.
class Locked {
 public:
  explicit Locked(fs::path p, bool read_only = false)
      : p_(std::move(p)), denied_(read_only ? W_OK : R_OK) {
    const fs::perms write =
        fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write;
    fs::permissions(p_, read_only ? fs::perms::all & ~write : fs::perms::none);
  }
  ~Locked() {
    std::error_code ec;
    fs::permissions(p_, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec, ec);
  }
  Locked(const Locked&) = delete;
  Locked& operator=(const Locked&) = delete;
  bool Denies() const { return ::access(p_.c_str(), denied_) != 0; }
  const fs::path& path() const { return p_; }
  /// test(1)'s operator for the access denied.
  const char* TestOperator() const { return denied_ == W_OK ? "-w" : "-r"; }

 private:
  fs::path p_;
  int denied_;  ///< R_OK or W_OK
};

// As root, chmod 000 denies nothing: the row then runs rovermap as nobody (setpriv, from
// util-linux, which every Debian has), with the scratch directory handed over to it.
#define DENY_OR_SKIP(locked)                                            \
  if (!DenyAccess(locked))                                              \
  GTEST_SKIP() << "chmod 000 denies nothing here and nobody is not at " \
                  "hand"

class BadInput : public rovermap::testing::ServeFixture {
 protected:
  // True once `locked` cannot be read (or written, if read-only) by the user the commands run
  // as.
  bool DenyAccess(const Locked& locked) {
    if (locked.Denies()) return true;
    const char* kSetpriv = "/usr/bin/setpriv";
    if (::geteuid() != 0 || ::access(kSetpriv, X_OK) != 0) return false;
    constexpr uid_t kNobody = 65534;
    if (::lchown(dir_.c_str(), kNobody, kNobody) != 0) return false;
    for (const auto& entry :
         fs::recursive_directory_iterator(dir_, fs::directory_options::skip_permission_denied)) {
      if (::lchown(entry.path().c_str(), kNobody, kNobody) != 0) return false;
    }
    run_as_ = {kSetpriv, "--reuid=65534", "--regid=65534", "--clear-groups"};
    // The locked directory itself (mode 000, owned by nobody now) is not descended into above.
    return ::lchown(locked.path().c_str(), kNobody, kNobody) == 0 &&
           Rovermap("--help").status == 0 &&
           std::system(("/usr/bin/setpriv --reuid=65534 --regid=65534 --clear-groups test " +
                        std::string(locked.TestOperator()) + " " + locked.path().string())
                           .c_str()) != 0;
  }

  // A copy of a bundled sequence (or file) that the row breaks.
  fs::path Copy(const fs::path& from, const std::string& name) {
    const fs::path to = dir_ / name;
    fs::copy(from, to, fs::copy_options::recursive);
    return to;
  }

  // A regular file, so that a path under it can never be created, even by root.
  fs::path UnderAFile(const std::string& leaf) {
    Put(dir_ / "a_file", "not a directory\n");
    return dir_ / "a_file" / leaf;
  }

  CommandResult Replay(const fs::path& seq, const std::string& extra = "") {
    return Rovermap("replay " + seq.string() + " --out " + (dir_ / "out").string() + " " + extra);
  }

  CommandResult Eval(const fs::path& estimate, const std::string& extra = "") {
    return Rovermap("eval --estimate " + estimate.string() + " --groundtruth " +
                    (kTinyCloud / "groundtruth.tum").string() + " " + extra);
  }

  // Nothing at `out` but the `allowed` names.
  static void ExpectNoOutput(const fs::path& out, const std::set<std::string>& allowed = {}) {
    if (!fs::exists(out)) return;
    for (const auto& entry : fs::recursive_directory_iterator(out))
      EXPECT_TRUE(allowed.count(entry.path().filename().string())) << entry.path() << " left";
  }

  static void ExpectNoTemporaries(const fs::path& dir) {
    for (const auto& entry : fs::recursive_directory_iterator(dir))
      EXPECT_FALSE(Has(entry.path().filename().string(), ".tmp-")) << entry.path();
  }

  // A replay that goes on over a bad frame: status 0, the full output set, the frame's
  // drift.csv row `bad_frame` with a detail naming `file`.
  void ExpectBadFrameSkipped(const CommandResult& r, std::size_t frame, const std::string& file) {
    const fs::path out = dir_ / "out";
    ASSERT_EQ(r.status, 0) << r.err;
    for (const std::string& name : kReplayOutputs) EXPECT_TRUE(fs::exists(out / name)) << name;
    ExpectNoTemporaries(out);
    const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
    EXPECT_EQ(summary["bad_frames"], 1);
    const std::vector<std::string> rows = DataLines(out / "drift.csv");  // header + frames
    ASSERT_GT(rows.size(), frame + 1);
    EXPECT_TRUE(Has(rows[frame + 1], "bad_frame")) << rows[frame + 1];
    EXPECT_TRUE(Has(rows[frame + 1], file)) << rows[frame + 1];
    EXPECT_TRUE(Has(r.err, file)) << r.err;  // the progress line says why
  }

  // The inbox of frames 0..2 of the tiny cloud sequence; `frame 1` broken by `damage`.
  fs::path InboxWithFrameOneBroken(const std::function<void(const fs::path& frames)>& damage) {
    const fs::path inbox = MakeInbox(kTinyCloud, 3, "inbox");
    damage(inbox / "frames");
    return inbox;
  }

  // serve over that inbox: frame 1 rejected with a reason naming `expect`, frames 0 and 2
  // processed, SIGTERM exits 0. Returns the daemon's log.
  std::string ExpectFrameOneRejected(const fs::path& inbox, const std::string& expect,
                                     std::size_t poses) {
    const fs::path out = dir_ / "out";
    const pid_t pid = Start(inbox, out, "log");
    const nlohmann::json status = WaitForNext(out, 3);
    EXPECT_FALSE(status.is_null()) << Slurp(dir_ / "log");
    if (status.is_null()) return Slurp(dir_ / "log");
    EXPECT_EQ(status["rejected"], 1);
    Stop(pid);
    const std::string reason = Slurp(inbox / "rejected" / "000001.reason");
    EXPECT_TRUE(Has(reason, expect)) << reason;
    EXPECT_FALSE(fs::exists(inbox / "frames" / "000001.odom"));
    EXPECT_TRUE(fs::exists(inbox / "rejected" / "000001.odom"));
    const std::string log = Slurp(dir_ / "log");
    EXPECT_TRUE(Has(log, expect)) << log;
    EXPECT_TRUE(Has(log, "serve: frame 2 ")) << log;  // the daemon went on
    EXPECT_EQ(DataLines(out / "trajectory.tum").size(), poses);
    ExpectNoTemporaries(out);
    return log;
  }

  // The folder the mosaic rows write into (created empty: whatever is left in it shows).
  fs::path MosaicFolder() {
    fs::create_directories(dir_ / "mosaic");
    return dir_ / "mosaic";
  }

  // `rovermap mosaic INPUTS --out MOSAIC/m.tif EXTRA`.
  CommandResult Mosaic(const std::string& inputs, const std::string& extra = "") {
    return Rovermap("mosaic " + inputs + " --out " + (MosaicFolder() / "m.tif").string() + " " +
                    extra);
  }

  // A refused mosaic: no JSON on stdout; in MOSAIC nothing but the `allowed` names (no COG, no
  // m.json, no temporary).
  void ExpectNoMosaic(const CommandResult& r, const std::set<std::string>& allowed = {}) {
    EXPECT_TRUE(r.out.empty()) << r.out;
    ExpectNoOutput(MosaicFolder(), allowed);
  }

  // `rovermap mosaic dem.tif --set SET`: exit 2 naming the key in `message`, nothing written.
  void ExpectMosaicConfigError(const std::string& set, const std::string& message) {
    const CommandResult r = Mosaic(Copy(kTerrain, "dem.tif").string(), "--set " + set);
    EXPECT_EQ(r.status, 2);
    EXPECT_TRUE(Has(r.err, message)) << r.err;
    ExpectNoMosaic(r);
  }

  // An 8 x 8 cell GeoTIFF in UTM 32N (with `crs` "", none; without `geotransform`, none).
  fs::path SmallDem(const std::string& name, int bands, bool geotransform,
                    const std::string& crs = "EPSG:32632") {
    const std::optional<std::array<double, 6>> g =
        geotransform ? std::optional(NorthUp(313360, 5154600, 1.0)) : std::nullopt;
    WriteDem(dir_ / name, 8, 8, g, crs, Constant(1.0f, 0.05f, 1.0f), bands);
    return dir_ / name;
  }

  // serve that must stop at start with `status`, naming `expect`; OUT holds at most its lock.
  void ExpectServeRefuses(const fs::path& inbox, int status, const std::string& expect,
                          const fs::path& out) {
    const pid_t pid = Start(inbox, out, "log");
    EXPECT_EQ(WaitExit(pid), status) << Slurp(dir_ / "log");
    EXPECT_TRUE(Has(Slurp(dir_ / "log"), expect)) << Slurp(dir_ / "log");
    ExpectNoOutput(out, {"serve.lock"});
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// register SOURCE TARGET: point files; the JSON on stdout only when both were read.

TEST_F(BadInput, Register_MissingFile) {
  const CommandResult r =
      Rovermap("register " + (dir_ / "nowhere.ply").string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "nowhere.ply: cannot open file")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_EmptyFile) {
  Put(dir_ / "empty.xyz", "");
  const CommandResult r =
      Rovermap("register " + (dir_ / "empty.xyz").string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "empty.xyz: empty file")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_WrongFormat) {
  const fs::path source = Copy(kPng, "image.ply");  // a PNG named .ply
  const CommandResult r = Rovermap("register " + source.string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "image.ply:1: not a PLY file")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_TruncatedBinaryPly) {
  const fs::path source = Copy(kTinyCloud / "frames" / "000000.ply", "cut.ply");
  KeepBytes(source, fs::file_size(source) / 2);
  const CommandResult r = Rovermap("register " + source.string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "cut.ply: truncated binary data: expected 1200 vertices")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_NonFiniteCoordinate) {
  const fs::path source = Copy(kBunny045, "bunny.ply");
  const int first_vertex = LineOf(source, "end_header") + 1;
  const std::string line = Line(source, first_vertex);
  SetLine(source, first_vertex, "nan" + line.substr(line.find(' ')));
  const CommandResult r = Rovermap("register " + source.string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "bunny.ply:" + std::to_string(first_vertex) + ": non-finite coordinate"))
      << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// The header promises 40097 vertices; the file holds 1000.
TEST_F(BadInput, Register_FewerVerticesThanTheHeader) {
  const fs::path source = Copy(kBunny045, "bunny.ply");
  const int header = LineOf(source, "end_header");
  std::istringstream in(Slurp(source));
  std::string kept;
  int n = 0;
  for (std::string line; std::getline(in, line) && n < header + 1000; ++n) kept += line + "\n";
  Put(source, kept);
  const CommandResult r = Rovermap("register " + source.string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "bunny.ply:")) << r.err;
  EXPECT_TRUE(Has(r.err, "expected 40097 vertices, found 1000")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_TooFewPoints) {
  Put(dir_ / "two.xyz", "0 0 0\n0.01 0 0\n");
  const CommandResult r =
      Rovermap("register " + (dir_ / "two.xyz").string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "two.xyz: need at least 3 points, found 2")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_UnknownConfigKey) {
  const CommandResult r = Rovermap("register " + kBunny045.string() + " " + kBunny000.string() +
                                   " --set registration.max_iteration=5");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "registration.max_iteration: unknown key")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_UnreadableDirectory) {
  const fs::path locked = dir_ / "locked";
  fs::create_directories(locked);
  fs::copy_file(kBunny045, locked / "bun045.ply");
  const Locked guard(locked);
  DENY_OR_SKIP(guard);
  const CommandResult r =
      Rovermap("register " + (locked / "bun045.ply").string() + " " + kBunny000.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "bun045.ply: cannot open file (Permission denied)")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Register_PreviewNotWritable) {
  const fs::path png = UnderAFile("preview.png");
  const CommandResult r =
      Rovermap("register " + kBunny045.string() + " " + kBunny000.string() +
               " --init \"0 0.5111 0 -0.049 0 -0.011\" --preview " + png.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "preview.png: cannot create temporary file (Not a directory)")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(Slurp(dir_ / "a_file"), "not a directory\n");
}

// ---------------------------------------------------------------------------------------------
// simulate --out DIR: its inputs are --config and --set; nothing is written before they pass.

TEST_F(BadInput, Simulate_MissingConfig) {
  const fs::path out = dir_ / "sim";
  const CommandResult r =
      Rovermap("simulate --out " + out.string() + " --config " + (dir_ / "nowhere.yaml").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "nowhere.yaml: no such config file")) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(BadInput, Simulate_WrongFormatConfig) {
  const fs::path config = Copy(kPng, "image.yaml");
  const fs::path out = dir_ / "sim";
  const CommandResult r =
      Rovermap("simulate --out " + out.string() + " --config " + config.string());
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "image.yaml:")) << r.err;
  EXPECT_TRUE(Has(r.err, "invalid YAML")) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// NaN is YAML's `.nan`: a number, but not a finite one.
TEST_F(BadInput, Simulate_NonFiniteValue) {
  Put(dir_ / "nan.yaml", "sim:\n  frames: 2\n  speed_m_s: .nan\n");
  const fs::path out = dir_ / "sim";
  const CommandResult r =
      Rovermap("simulate --out " + out.string() + " --config " + (dir_ / "nan.yaml").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "nan.yaml:3: sim.speed_m_s:")) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// A terrain cell given in metres as if in millimetres' thousandths: 0.4 mm cells.
TEST_F(BadInput, Simulate_WrongUnits) {
  const fs::path out = dir_ / "sim";
  const CommandResult r =
      Rovermap("simulate --out " + out.string() + " --set sim.terrain_cell_m=0.0004");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "sim.terrain_cell_m: too small for sim.terrain_size_m")) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(BadInput, Simulate_UnknownConfigKey) {
  Put(dir_ / "typo.yaml", "sim:\n  sensor: cloud\n  frame: 3\n");
  const fs::path out = dir_ / "sim";
  const CommandResult r =
      Rovermap("simulate --out " + out.string() + " --config " + (dir_ / "typo.yaml").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "typo.yaml:3: sim.frame: unknown key (did you mean sim.frames?)"))
      << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(BadInput, Simulate_UnreadableConfigDirectory) {
  const fs::path locked = dir_ / "locked";
  fs::create_directories(locked);
  Put(locked / "sim.yaml", "sim:\n  frames: 2\n");
  const Locked guard(locked);
  DENY_OR_SKIP(guard);
  const fs::path out = dir_ / "sim";
  const CommandResult r =
      Rovermap("simulate --out " + out.string() + " --config " + (locked / "sim.yaml").string());
  EXPECT_EQ(r.status, 2);
  // Not "no such config file": it is there, behind a directory we may not enter.
  EXPECT_TRUE(Has(r.err, "sim.yaml: cannot access config file (Permission denied)")) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(BadInput, Simulate_OutputNotWritable) {
  const fs::path out = UnderAFile("sim");
  const CommandResult r =
      Rovermap("simulate --out " + out.string() + " --set sim.sensor=cloud --set sim.frames=2");
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "--out " + out.string() + ": cannot create")) << r.err;
  EXPECT_TRUE(Has(r.err, "a_file is not a directory")) << r.err;
  EXPECT_FALSE(Has(r.err, "simulate: frame")) << r.err;  // refused before rendering
}

// ---------------------------------------------------------------------------------------------
// replay SEQ --out OUT: the whole sequence is checked before any output; a frame that cannot be
// used is skipped and flagged, never fatal.

TEST_F(BadInput, Replay_MissingFrameFile) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  fs::remove(seq / "frames" / "000002.ply");
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "000002.ply: missing frame file (odometry.tum:4 has a pose for frame 2"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_EmptyOdometry) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  Put(seq / "odometry.tum", "");
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "odometry.tum: no poses")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_EmptyFrame) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  Put(seq / "frames" / "000002.ply", "");
  ExpectBadFrameSkipped(Replay(seq), 2, "000002.ply");
}

// A stereo image in a cloud sequence: the sequence is inconsistent, not one frame.
TEST_F(BadInput, Replay_WrongKindOfFrame) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  fs::copy_file(kPng, seq / "frames" / "000001.left.png");
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "000001.left.png: a stereo frame in a sequence with sensor.type: cloud"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_TruncatedOdometry) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  const fs::path odometry = seq / "odometry.tum";
  const int last = static_cast<int>(LineOf(odometry, "2.000000000"));  // frame 4's line
  ASSERT_GT(last, 0);
  const std::string line = Line(odometry, last);
  SetLine(odometry, last, line.substr(0, line.find(' ', line.find(' ', line.find(' ') + 1) + 1)));
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "odometry.tum:" + std::to_string(last) + ": 3 columns, expected 8"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_TruncatedPng) {
  const fs::path seq = Copy(kTinyStereo, "seq");
  const fs::path png = seq / "frames" / "000001.right.png";
  KeepBytes(png, fs::file_size(png) / 3);
  ExpectBadFrameSkipped(Replay(seq), 1, "000001.right.png: cannot read or decode the image");
}

TEST_F(BadInput, Replay_NonFiniteCalibration) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  Edit(seq / "sequence.yaml", "fx: 300", "fx: .nan");
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  const int line = LineOf(seq / "sequence.yaml", "fx: .nan");
  EXPECT_TRUE(Has(r.err, "sequence.yaml:" + std::to_string(line) +
                             ": camera.fx: expected a finite number (got .nan)"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// Every point of frame 2 NaN (the PLY's properties are all doubles): each is dropped and
// counted (docs/design.md §9), which leaves no point, so the frame is a bad frame.
TEST_F(BadInput, Replay_NonFinitePoints) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  const fs::path ply = seq / "frames" / "000002.ply";
  std::string bytes = Slurp(ply);
  ASSERT_TRUE(Has(bytes, "binary_little_endian"));
  const std::size_t data = bytes.find("end_header\n") + 11;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t at = data; at + sizeof(nan) <= bytes.size(); at += sizeof(nan))
    bytes.replace(at, sizeof(nan), reinterpret_cast<const char*>(&nan), sizeof(nan));
  Put(ply, bytes);
  ExpectBadFrameSkipped(Replay(seq), 2, "000002.ply: no usable points, 1200 non-finite dropped");
}

// A quarter of frame 2's points NaN (x of every 4th vertex; 6 doubles a vertex), as an organised
// sensor writes pixels without a return: they are dropped and counted, the rest registered and
// fused (they made the whole frame a bad frame while the PLY reader refused them).
TEST_F(BadInput, Replay_SomeNonFinitePointsAreDroppedAndCounted) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  const fs::path ply = seq / "frames" / "000002.ply";
  std::string bytes = Slurp(ply);
  ASSERT_TRUE(Has(bytes,
                  "element vertex 1200\nproperty double x\nproperty double y\n"
                  "property double z\nproperty double nx\nproperty double ny\n"
                  "property double nz\nend_header\n"));
  const std::size_t data = bytes.find("end_header\n") + 11;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  constexpr std::size_t kVertexBytes = 6 * sizeof(double);
  for (std::size_t v = 0; v < 1200; v += 4)
    bytes.replace(data + v * kVertexBytes, sizeof(nan), reinterpret_cast<const char*>(&nan),
                  sizeof(nan));
  Put(ply, bytes);
  const CommandResult r = Replay(seq);
  ASSERT_EQ(r.status, 0) << r.err;
  const fs::path out = dir_ / "out";
  const nlohmann::json summary = nlohmann::json::parse(Slurp(out / "summary.json"));
  EXPECT_EQ(summary["bad_frames"], 0);
  EXPECT_EQ(summary["dropped_nonfinite"], 300);
  const std::vector<std::string> rows = DataLines(out / "drift.csv");
  ASSERT_GT(rows.size(), 3u);
  EXPECT_TRUE(Has(rows[3], ",registered,")) << rows[3];
}

// The latitude in micro-degrees.
TEST_F(BadInput, Replay_WrongUnitsLatitude) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  Edit(seq / "sequence.yaml", "latitude: 46.519100000000002", "latitude: 46519100");
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  const int line = LineOf(seq / "sequence.yaml", "latitude:");
  EXPECT_TRUE(Has(
      r.err, "sequence.yaml:" + std::to_string(line) + ": origin.latitude: must be in [-90, 90]"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// A right image of another camera's size (Middlebury's 741x497 for the 160x120 camera).
TEST_F(BadInput, Replay_WrongImageSize) {
  const fs::path seq = Copy(kTinyStereo, "seq");
  fs::copy_file(kData / "middlebury2014_motorcycle_quarter" / "im1.png",
                seq / "frames" / "000001.right.png", fs::copy_options::overwrite_existing);
  ExpectBadFrameSkipped(Replay(seq), 1,
                        "000001.right.png: image is 741x497, sequence.yaml camera is 160x120");
}

TEST_F(BadInput, Replay_UnknownKey) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  std::ofstream(seq / "sequence.yaml", std::ios::app) << "colour: red\n";
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  const int line = LineOf(seq / "sequence.yaml", "colour");
  EXPECT_TRUE(Has(r.err, "sequence.yaml:" + std::to_string(line) + ": colour: unknown key"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_NonIncreasingTimestamps) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  const int line = LineOf(seq / "odometry.tum", "1.000000000 ");  // frame 2, after 0.5 s
  Edit(seq / "odometry.tum", "1.000000000 ", "0.400000000 ");
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "odometry.tum:" + std::to_string(line) +
                             ": timestamp 0.400000 is not after the previous one"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_MismatchedGroundtruth) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  std::vector<std::string> lines = DataLines(seq / "groundtruth.tum");
  lines.pop_back();
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  Put(seq / "groundtruth.tum", text);
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "groundtruth.tum: 4 poses, but odometry.tum has 5")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_UnreadableSequenceDirectory) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  const Locked guard(seq);
  DENY_OR_SKIP(guard);
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  // Not "missing": the file is there, in a directory we may not read.
  EXPECT_TRUE(Has(r.err, "sequence.yaml: cannot access (Permission denied)")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_UnreadableFramesDirectory) {
  const fs::path seq = Copy(kTinyCloud, "seq");
  const Locked guard(seq / "frames");
  DENY_OR_SKIP(guard);
  const CommandResult r = Replay(seq);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "frames: cannot list (Permission denied)")) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Replay_OutputNotWritable) {
  const fs::path out = UnderAFile("out");
  const CommandResult r = Rovermap("replay " + kTinyCloud.string() + " --out " + out.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "--out " + out.string() + ": cannot create")) << r.err;
  EXPECT_TRUE(Has(r.err, "a_file is not a directory")) << r.err;
  EXPECT_FALSE(Has(r.err, "replay: frame")) << r.err;  // refused before the first frame
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// ---------------------------------------------------------------------------------------------
// serve --inbox INBOX --out OUT: a bad sequence.yaml stops it at start; a bad frame is moved to
// INBOX/rejected/ beside its reason and the daemon goes on.

TEST_F(BadInput, Serve_EmptySequenceYaml) {
  const fs::path inbox = dir_ / "inbox";
  fs::create_directories(inbox);
  Drop(inbox / "sequence.yaml", "");
  ExpectServeRefuses(inbox, 2, "sequence.yaml: expected a mapping of keys", dir_ / "out");
}

TEST_F(BadInput, Serve_UnknownKeyInSequenceYaml) {
  const fs::path inbox = dir_ / "inbox";
  fs::create_directories(inbox);
  Drop(inbox / "sequence.yaml", Slurp(kTinyCloud / "sequence.yaml") + "colour: red\n");
  const int line = LineOf(inbox / "sequence.yaml", "colour");
  ExpectServeRefuses(inbox, 2, "sequence.yaml:" + std::to_string(line) + ": colour: unknown key",
                     dir_ / "out");
}

// A regular file given as the inbox was waited on for ever.
TEST_F(BadInput, Serve_InboxNotADirectory) {
  const fs::path inbox = Copy(kTinyCloud / "sequence.yaml", "inbox");
  ExpectServeRefuses(inbox, 2, "--inbox " + inbox.string() + ": not a directory", dir_ / "out");
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

TEST_F(BadInput, Serve_TruncatedPly) {
  const fs::path inbox = InboxWithFrameOneBroken([](const fs::path& frames) {
    const std::string bytes = Slurp(frames / "000001.ply");
    Drop(frames / "000001.ply", bytes.substr(0, bytes.size() / 2));
  });
  // A bad frame keeps dead reckoning's pose: 3 poses.
  ExpectFrameOneRejected(inbox, "000001.ply: truncated binary data", 3);
}

// A frame of 10 points (mapper.min_points is 100): read, but too small to register.
TEST_F(BadInput, Serve_TooFewPoints) {
  const fs::path inbox = InboxWithFrameOneBroken([](const fs::path& frames) {
    std::string bytes = Slurp(frames / "000001.ply");
    const std::size_t data = bytes.find("end_header\n") + 11;
    const std::size_t vertex = 6 * sizeof(double);  // x y z nx ny nz
    bytes.resize(data + 10 * vertex);
    bytes.replace(bytes.find("element vertex 1200"), 19, "element vertex 10");
    Drop(frames / "000001.ply", bytes);
  });
  ExpectFrameOneRejected(inbox, "000001.ply: too few points (10 < mapper.min_points 100)", 3);
}

TEST_F(BadInput, Serve_NonFiniteOdometry) {
  const fs::path inbox = InboxWithFrameOneBroken([](const fs::path& frames) {
    std::string line = DataLines(frames / "000001.odom").at(0);
    line.replace(line.find(' ') + 1, line.find(' ', line.find(' ') + 1) - line.find(' ') - 1,
                 "inf");
    Drop(frames / "000001.odom", line + "\n");
  });
  // Without an odometry pose the frame is absent from the trajectory: 2 poses.
  ExpectFrameOneRejected(inbox, "000001.odom:1: not a finite number 'inf'", 2);
}

TEST_F(BadInput, Serve_NonIncreasingTimestamps) {
  const fs::path inbox = InboxWithFrameOneBroken([](const fs::path& frames) {
    std::string line = DataLines(frames / "000001.odom").at(0);
    line.replace(0, line.find(' '), "0.0");  // frame 0's time
    Drop(frames / "000001.odom", line + "\n");
  });
  ExpectFrameOneRejected(inbox, "000001.odom: timestamp 0 is not after the previous frame's 0", 2);
}

TEST_F(BadInput, Serve_OdometryWithTwoLines) {
  const fs::path inbox = InboxWithFrameOneBroken([](const fs::path& frames) {
    const std::string line = DataLines(frames / "000001.odom").at(0);
    Drop(frames / "000001.odom", line + "\n" + DataLines(frames / "000002.odom").at(0) + "\n");
  });
  ExpectFrameOneRejected(inbox, "000001.odom: holds 2 poses", 2);
}

TEST_F(BadInput, Serve_UnreadableFramesDirectory) {
  const fs::path inbox = MakeInbox(kTinyCloud, 2, "inbox");
  const Locked guard(inbox / "frames");
  DENY_OR_SKIP(guard);
  const fs::path out = dir_ / "out";
  const pid_t pid = Start(inbox, out, "log");
  // It used to wait for ever, the frames/ it could not list looking empty.
  EXPECT_EQ(WaitExit(pid), 1) << Slurp(dir_ / "log");
  EXPECT_TRUE(Has(Slurp(dir_ / "log"), "frames: cannot list (Permission denied)"))
      << Slurp(dir_ / "log");
  // The lock, the status ("running": it stopped at once) and an empty checkpoint/; no map.
  ExpectNoOutput(out, {"serve.lock", "status.json", "checkpoint"});
}

TEST_F(BadInput, Serve_OutputNotWritable) {
  const fs::path inbox = MakeInbox(kTinyCloud, 1, "inbox");
  const fs::path out = UnderAFile("out");
  const pid_t pid = Start(inbox, out, "log");
  EXPECT_EQ(WaitExit(pid), 1) << Slurp(dir_ / "log");
  EXPECT_TRUE(Has(Slurp(dir_ / "log"), out.string() + ": cannot create (Not a directory)"))
      << Slurp(dir_ / "log");
}

// ---------------------------------------------------------------------------------------------
// eval: trajectory files (TUM, KITTI) and GeoTIFFs; the JSON only when the inputs were read.

TEST_F(BadInput, Eval_MissingFile) {
  const CommandResult r = Eval(dir_ / "nowhere.tum");
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "nowhere.tum: cannot open file (No such file or directory)")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Eval_EmptyFile) {
  Put(dir_ / "empty.tum", "");
  const CommandResult r = Eval(dir_ / "empty.tum");
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "empty.tum: no poses in the file")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// KITTI poses (12 numbers a line) read as TUM.
TEST_F(BadInput, Eval_WrongFormat) {
  std::istringstream kitti(Slurp(kData / "kitti_odometry_00" / "KITTI_00_gt.txt"));
  std::string text;
  std::string line;
  for (int i = 0; i < 20 && std::getline(kitti, line); ++i) text += line + "\n";
  Put(dir_ / "kitti.txt", text);
  const CommandResult r = Eval(dir_ / "kitti.txt", "--format tum");
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "kitti.txt:1: more than 8 columns")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Eval_TruncatedLine) {
  const fs::path estimate = Copy(kTinyCloud / "odometry.tum", "estimate.tum");
  const int last = LineOf(estimate, "2.000000000");
  const std::string line = Line(estimate, last);
  SetLine(estimate, last, line.substr(0, line.size() / 2));  // cut inside its 5th number
  const CommandResult r = Eval(estimate);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "estimate.tum:" + std::to_string(last) + ":")) << r.err;
  EXPECT_TRUE(Has(r.err, "expected 8")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Eval_NonFinite) {
  const fs::path estimate = Copy(kTinyCloud / "odometry.tum", "estimate.tum");
  const int line = LineOf(estimate, "0.500000000 ");
  Edit(estimate, "0.500000000 0.15309351816027275", "0.500000000 inf");
  const CommandResult r = Eval(estimate);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "estimate.tum:" + std::to_string(line) + ": not a finite number 'inf'"))
      << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Eval_NonIncreasingTimestamps) {
  const fs::path estimate = Copy(kTinyCloud / "odometry.tum", "estimate.tum");
  const int line = LineOf(estimate, "1.500000000 ");
  Edit(estimate, "1.500000000 ", "1.000000000 ");
  const CommandResult r = Eval(estimate);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "estimate.tum:" + std::to_string(line) +
                             ": timestamp 1.000000 is not after the previous one"))
      << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// KITTI files have no timestamps: poses pair by index, which needs equal lengths. The inputs
// were read, so the JSON is printed and says why.
TEST_F(BadInput, Eval_MismatchedCounts) {
  std::istringstream kitti(Slurp(kData / "kitti_odometry_00" / "KITTI_00_gt.txt"));
  std::string text;
  std::string line;
  for (int i = 0; i < 20 && std::getline(kitti, line); ++i) {
    if (i == 19) Put(dir_ / "estimate.txt", text);  // 19 poses
    text += line + "\n";
  }
  Put(dir_ / "truth.txt", text);  // 20 poses
  const CommandResult r = Rovermap("eval --estimate " + (dir_ / "estimate.txt").string() +
                                   " --groundtruth " + (dir_ / "truth.txt").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "estimate.txt has 19 poses,")) << r.err;
  EXPECT_TRUE(Has(r.err, "truth.txt has 20")) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["estimates"][0]["status"], "no_pairs");
  EXPECT_TRUE(j["estimates"][0]["ate_rmse_m"].is_null());
}

TEST_F(BadInput, Eval_UnknownConfigKey) {
  const CommandResult r = Eval(kTinyCloud / "odometry.tum", "--set eval.rpe_delta=2");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "eval.rpe_delta: unknown key (did you mean eval.rpe_delta_m?)")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Eval_UnreadableDirectory) {
  const fs::path locked = dir_ / "locked";
  fs::create_directories(locked);
  fs::copy_file(kTinyCloud / "odometry.tum", locked / "estimate.tum");
  const Locked guard(locked);
  DENY_OR_SKIP(guard);
  const CommandResult r = Eval(locked / "estimate.tum");
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "estimate.tum: cannot open file (Permission denied)")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Eval_PlotNotWritable) {
  const fs::path plots = UnderAFile("plots");
  const CommandResult r = Eval(kTinyCloud / "odometry.tum", "--plot " + plots.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, plots.string() + ": cannot create the plot directory")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(BadInput, Eval_DemTruncated) {
  const fs::path dem = Copy(kTinyCloud / "terrain.tif", "dem.tif");
  KeepBytes(dem, fs::file_size(dem) / 2);
  const CommandResult r = Rovermap("eval --dem " + dem.string() + " --reference " +
                                   (kTinyCloud / "terrain.tif").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "dem.tif: cannot read band 1")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// A reference in another UTM zone (the simulator's terrain at 12.5° E, zone 33, against the
// tiny sequence's at 6.57° E, zone 32): metres of different grids. The JSON says why.
TEST_F(BadInput, Eval_DemOtherCrs) {
  const fs::path other = dir_ / "zone33";
  const CommandResult sim =
      Rovermap("simulate --out " + other.string() +
               " --set sim.sensor=cloud --set sim.frames=1 --set sim.terrain_size_m=4"
               " --set sim.cloud_stride_px=24 --set sim.origin_longitude_deg=12.5");
  ASSERT_EQ(sim.status, 0) << sim.err;
  const CommandResult r = Rovermap("eval --dem " + (kTinyCloud / "terrain.tif").string() +
                                   " --reference " + (other / "terrain.tif").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "different coordinate reference systems")) << r.err;
  EXPECT_TRUE(Has(r.err, "zone33/terrain.tif has 'WGS 84 / UTM zone 33N'")) << r.err;
  EXPECT_TRUE(Has(r.err, "UTM zone 32N")) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["status"], "crs_mismatch");
}

// ---------------------------------------------------------------------------------------------
// mosaic DEM.tif ... --out MOSAIC.tif: every input and --out are checked before any output; on
// any failure MOSAIC holds neither the COG nor its report m.json nor a temporary.

TEST_F(BadInput, Mosaic_MissingFile) {
  const fs::path dem = Copy(kTerrain, "dem.tif");
  const CommandResult r = Mosaic(dem.string() + " " + (dir_ / "nowhere.tif").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "nowhere.tif: no such file")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_EmptyFile) {
  Put(dir_ / "empty.tif", "");
  const CommandResult r = Mosaic((dir_ / "empty.tif").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "empty.tif: empty file")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_WrongFormat) {
  const fs::path image = Copy(kPng, "image.tif");  // a PNG named .tif
  const CommandResult r = Mosaic(image.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "image.tif: not a GeoTIFF")) << r.err;
  ExpectNoMosaic(r);
}

// The header is whole, the tiles are not: it fails while fusing, with the temporaries made.
TEST_F(BadInput, Mosaic_TruncatedGeoTiff) {
  const fs::path dem = Copy(kTerrain, "cut.tif");
  KeepBytes(dem, fs::file_size(dem) / 2);
  const CommandResult r = Mosaic(dem.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "cut.tif: GDAL's warper failed")) << r.err;
  EXPECT_TRUE(Has(r.err, "band 1")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_OneBand) {
  const fs::path dem = SmallDem("one_band.tif", 1, true);
  const CommandResult r = Mosaic(dem.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "one_band.tif: has 1 band(s); a DEM has 3")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_NoGeotransform) {
  const fs::path dem = SmallDem("no_geotransform.tif", 3, false);
  const CommandResult r = Mosaic(Copy(kTerrain, "dem.tif").string() + " " + dem.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "no_geotransform.tif: has no geotransform")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_NoCrs) {
  const fs::path dem = SmallDem("no_crs.tif", 3, true, "");
  const CommandResult r = Mosaic(Copy(kTerrain, "dem.tif").string() + " " + dem.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "no_crs.tif: has no CRS")) << r.err;
  ExpectNoMosaic(r);
}

// A first input in degrees (WGS 84): its CRS would be the mosaic's, whose cells are metres.
TEST_F(BadInput, Mosaic_WrongUnitsInput) {
  WriteDem(dir_ / "degrees.tif", 8, 8, NorthUp(6.57, 46.52, 1e-5), "EPSG:4326",
           Constant(1.0f, 0.05f, 1.0f));
  const CommandResult r =
      Mosaic((dir_ / "degrees.tif").string() + " " + Copy(kTerrain, "dem.tif").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(Has(r.err, "degrees.tif: its CRS is not projected")) << r.err;
  EXPECT_TRUE(Has(r.err, "set mosaic.crs")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_NonFiniteValue) {
  ExpectMosaicConfigError("mosaic.disagreement_sigma=nan",
                          "mosaic.disagreement_sigma: must be finite (got nan)");
}

TEST_F(BadInput, Mosaic_NegativeCellSize) {
  ExpectMosaicConfigError("mosaic.cell_size_m=-1", "mosaic.cell_size_m: must be >= 0 (got -1)");
}

TEST_F(BadInput, Mosaic_ZeroTileCells) {
  ExpectMosaicConfigError("mosaic.tile_cells=0", "mosaic.tile_cells: must be >= 16 (got 0)");
}

TEST_F(BadInput, Mosaic_UnknownConfigKey) {
  ExpectMosaicConfigError("mosaic.cell_size=0.5",
                          "mosaic.cell_size: unknown key (did you mean mosaic.cell_size_m?)");
}

// A geographic output CRS: cells of degrees, not metres.
TEST_F(BadInput, Mosaic_WrongUnitsCrs) {
  ExpectMosaicConfigError("mosaic.crs=EPSG:4326",
                          "mosaic.crs: must be a projected CRS (got 'EPSG:4326')");
}

TEST_F(BadInput, Mosaic_UnreadableDirectory) {
  const fs::path locked = dir_ / "locked";
  fs::create_directories(locked);
  fs::copy_file(kTerrain, locked / "dem.tif");
  MosaicFolder();  // handed over to nobody with the rest
  const Locked guard(locked);
  DENY_OR_SKIP(guard);
  const CommandResult r = Mosaic((locked / "dem.tif").string());
  EXPECT_EQ(r.status, 1);
  // Not "no such file": it is there, behind a directory we may not enter.
  EXPECT_TRUE(Has(r.err, "locked/dem.tif: cannot access (Permission denied)")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_OutputFolderMissing) {
  const fs::path out = dir_ / "nowhere" / "m.tif";
  const CommandResult r =
      Rovermap("mosaic " + Copy(kTerrain, "dem.tif").string() + " --out " + out.string());
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "--out " + out.string() + ": no folder")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "nowhere"));
}

TEST_F(BadInput, Mosaic_OutputNotWritable) {
  const fs::path dem = Copy(kTerrain, "dem.tif");
  const Locked guard(MosaicFolder(), /*read_only=*/true);
  DENY_OR_SKIP(guard);
  const CommandResult r = Mosaic(dem.string());
  EXPECT_EQ(r.status, 1);
  // Refused before the inputs are read (it fused them all, then failed).
  EXPECT_TRUE(Has(r.err, "--out " + (MosaicFolder() / "m.tif").string() + ": cannot write in"))
      << r.err;
  EXPECT_TRUE(Has(r.err, "(Permission denied)")) << r.err;
  ExpectNoMosaic(r);
}

TEST_F(BadInput, Mosaic_OutputExistsWithoutForce) {
  Put(MosaicFolder() / "m.tif", "previous mosaic\n");
  Put(MosaicFolder() / "m.json", "{}\n");
  const CommandResult r = Mosaic(Copy(kTerrain, "dem.tif").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Has(r.err, "m.tif exists (use --force to replace it)")) << r.err;
  ExpectNoMosaic(r, {"m.tif", "m.json"});
  EXPECT_EQ(Slurp(MosaicFolder() / "m.tif"), "previous mosaic\n");
  EXPECT_EQ(Slurp(MosaicFolder() / "m.json"), "{}\n");
}
