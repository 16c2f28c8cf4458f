#include "io/FrameSource.hpp"

#include <stdexcept>
#include <string>
#include <system_error>

#include "io/IoError.hpp"
#include "io/Ros2Bag.hpp"
#include "io/Sequence.hpp"
#ifdef ROVERMAP_WITH_ROSBAG
#include "io/BagSource.hpp"
#endif

namespace rovermap::io {

Frame IndexedFrameSource::Read(std::size_t index) const {
  if (index >= odometry_.size()) {
    throw std::out_of_range("FrameSource::Read: frame " + std::to_string(index) + " of " +
                            std::to_string(odometry_.size()));
  }
  Frame frame;
  frame.index = index;
  frame.timestamp = odometry_[index].timestamp;
  frame.T_world_body_odom = odometry_[index].T_world_body;
  if (!groundtruth_.empty()) frame.T_world_body_truth = groundtruth_[index].T_world_body;
  LoadFrame(&frame);
  return frame;
}

const std::vector<GnssFix>& FrameSource::gnss() const {
  static const std::vector<GnssFix> none;
  return none;
}

bool IndexedFrameSource::Next(Frame* frame) {
  if (next_ >= odometry_.size()) return false;
  const std::size_t index = next_++;
  *frame = Read(index);
  return true;
}

std::unique_ptr<FrameSource> OpenFrameSource(const std::filesystem::path& path,
                                             const BagOptions& bag_options) {
  if (IsRos2Bag(path)) return std::make_unique<Ros2BagSource>(path, bag_options);
  std::error_code error;
  if (path.extension() != ".bag" || std::filesystem::is_directory(path, error)) {
    return std::make_unique<SequenceReader>(path);
  }
#ifdef ROVERMAP_WITH_ROSBAG
  return std::make_unique<BagSource>(path, bag_options);
#else
  (void)bag_options;
  throw IoError(path.string() +
                ": this rovermap was built without ROS bag support (configure with "
                "-DROVERMAP_WITH_ROSBAG=ON; scripts/install_deps.sh installs the ROS packages)");
#endif
}

}  // namespace rovermap::io
