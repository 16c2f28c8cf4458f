// Opening what replay and import read, with the `bag.` options, and saying what it left out.
#include <iostream>
#include <memory>
#include <string>

#include "apps/Commands.hpp"
#include "io/FrameSource.hpp"

namespace rovermap::apps {

std::unique_ptr<io::FrameSource> OpenRecording(const std::string& path, const config::Config& cfg,
                                               const std::string& command) {
  std::unique_ptr<io::FrameSource> source =
      io::OpenFrameSource(path, config::BagOptionsFrom(cfg.bag));
  const io::SkippedFrames skipped = source->skipped();
  if (skipped.outside_pose_span > 0 || skipped.unpaired_images > 0) {
    std::cerr << command << ": " << path << ": " << source->frame_count() << " frames; skipped "
              << skipped.unpaired_images
              << " images without a partner within bag.pair_tolerance_s and "
              << skipped.outside_pose_span
              << " frames outside the time span of the odometry (or ground truth)\n";
  }
  return source;
}

}  // namespace rovermap::apps
