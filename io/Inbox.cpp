#include "io/Inbox.hpp"

#include <system_error>
#include <utility>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {
namespace fs = std::filesystem;

namespace {

constexpr const char* kKinds[] = {"left.png", "right.png", "ply", "odom", "gt"};

StampedPose ReadOnePose(const fs::path& path) { return ParseFramePose(ReadWholeFile(path), path); }

}  // namespace

StampedPose ParseFramePose(std::string_view text, const fs::path& path) {
  const std::vector<StampedPose> poses = ParseTum(text, path);
  if (poses.size() != 1) {
    throw IoError(path.string() + ": holds " + std::to_string(poses.size()) +
                  " poses, a frame's file holds exactly one TUM line");
  }
  return poses.front();
}

Inbox::Inbox(fs::path directory) : directory_(std::move(directory)) {}

std::map<std::size_t, InboxFrameFiles> Inbox::Scan() const {
  std::map<std::size_t, InboxFrameFiles> found;
  std::error_code ec;
  fs::directory_iterator it(frames_dir(), ec);
  // No frames/ yet: nothing has arrived. Any other error (EACCES) would hide every frame.
  if (ec == std::errc::no_such_file_or_directory) return found;
  if (ec) throw IoError(frames_dir().string() + ": cannot list (" + ec.message() + ")");
  for (const fs::directory_entry& entry : it) {
    std::size_t index = 0;
    std::string kind;
    const std::string name = entry.path().filename().string();
    if (!ParseFrameFileName(name, &index, &kind)) continue;
    if (name.compare(0, name.find('.'), FrameStem(index)) != 0) continue;  // not zero-padded
    InboxFrameFiles& files = found[index];
    if (kind == "left.png") files.left = true;
    if (kind == "right.png") files.right = true;
    if (kind == "ply") files.ply = true;
    if (kind == "odom") files.odom = true;
    if (kind == "gt") files.gt = true;
  }
  return found;
}

Frame Inbox::ReadPoses(std::size_t index, const InboxFrameFiles& files) const {
  const fs::path stem = frames_dir() / FrameStem(index);
  Frame frame;
  frame.index = index;
  const StampedPose odom = ReadOnePose(stem.string() + ".odom");
  frame.timestamp = odom.timestamp;
  frame.T_world_body_odom = odom.T_world_body;
  if (files.gt) frame.T_world_body_truth = ReadOnePose(stem.string() + ".gt").T_world_body;
  return frame;
}

Frame Inbox::Read(std::size_t index, const InboxFrameFiles& files, const SequenceInfo& info) const {
  Frame frame = ReadPoses(index, files);
  ReadFrameData(frames_dir() / FrameStem(index), info, &frame);
  return frame;
}

void Inbox::Reject(std::size_t index, const std::string& reason) const {
  std::error_code ec;
  fs::create_directories(rejected_dir(), ec);
  if (ec) throw IoError(rejected_dir().string() + ": cannot create (" + ec.message() + ")");
  const std::string stem = FrameStem(index);
  // The reason first: a kill in between leaves it beside the files still to move.
  WriteFileAtomically(rejected_dir() / (stem + ".reason"), reason + "\n");
  for (const char* kind : kKinds) {
    const fs::path from = frames_dir() / (stem + "." + kind);
    if (!fs::exists(from, ec)) continue;
    fs::rename(from, rejected_dir() / from.filename(), ec);
    if (ec) throw IoError(from.string() + ": cannot move to rejected/ (" + ec.message() + ")");
  }
}

}  // namespace rovermap::io
