#pragma once
// A recording in a ROS 2 bag, read as a FrameSource without ROS: a rosbag2 bag directory
// (metadata.yaml naming its MCAP or SQLite files), or one .mcap or .db3 file. The same `bag.`
// keys and rules as the ROS 1 reader (io/BagRules.hpp); messages in CDR (io/Cdr.hpp).

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "io/BagOptions.hpp"
#include "io/BagRules.hpp"
#include "io/Frame.hpp"
#include "io/FrameSource.hpp"

namespace rovermap::io {

/// Whether `path` is read as a ROS 2 bag: a directory with metadata.yaml, or a file named
/// *.mcap or *.db3.
bool IsRos2Bag(const std::filesystem::path& path);

/// The storage files of the bag at `path`: those metadata.yaml names (for a directory), else
/// `path` itself.
/// @throw IoError naming metadata.yaml (and line) if it is not rosbag2's, uses rosbag2's own
///        compression, or names a file that is not there.
std::vector<std::filesystem::path> Ros2BagFiles(const std::filesystem::path& path);

/// Opens a ROS 2 bag and finds its frames as BagSource does a ROS 1 bag; then Next() reads them
/// in time order. Opening reads the header stamps of every image or cloud (decompressing the
/// MCAP chunks that hold them; of a SQLite file's messages, their first bytes only); an image is
/// read whole and decoded only when its frame is read.
class Ros2BagSource : public bag::BagFrameSource {
 public:
  /// @throw IoError naming the file (and, where it applies, topic and record) if the bag cannot
  ///        be read (missing, truncated, a chunk's CRC fails, an unknown compression, a message
  ///        encoding other than CDR, a CDR buffer shorter than its lengths), lacks a topic, holds
  ///        a topic of a type it does not read, or any of BagSource's reasons.
  explicit Ros2BagSource(const std::filesystem::path& path, const BagOptions& options = {});
  ~Ros2BagSource() override;
  Ros2BagSource(const Ros2BagSource&) = delete;
  Ros2BagSource& operator=(const Ros2BagSource&) = delete;

 private:
  cv::Mat ReadImage(const std::string& topic, const bag::MessageRef& ref) const override;
  registration::PointCloud ReadCloud(const bag::MessageRef& ref) const override;

  struct Bag;  // the open storage files and where each image or cloud is in them

  std::unique_ptr<Bag> bag_;
};

}  // namespace rovermap::io
