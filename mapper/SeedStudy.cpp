#include "mapper/SeedStudy.hpp"

#include <stdexcept>

#include "io/Sequence.hpp"
#include "mapper/Degeneracy.hpp"

namespace rovermap::mapper {

PreloadedSequence Preload(const std::filesystem::path& sequence_dir, const PipelineOptions& options,
                          std::size_t max_frames) {
  io::SequenceReader reader(sequence_dir);
  PreloadedSequence out;
  out.info = reader.info();
  out.truth = reader.groundtruth();
  const SensorSetup sensor = ResolveSensor(out.info, options.stereo, options.dem, ImageCheckOn(options.mapper));
  io::Frame frame;
  while ((max_frames == 0 || out.frames.size() < max_frames) && reader.Next(&frame)) {
    out.loaded.push_back(
        LoadFrame(frame, sensor, static_cast<std::size_t>(options.mapper.min_points)));
    frame.left.release();
    frame.right.release();
    frame.cloud = registration::PointCloud();
    out.frames.push_back(frame);
  }
  if (out.truth.size() > out.frames.size()) out.truth.resize(out.frames.size());
  return out;
}

std::vector<FrameResult> RunWithOdometry(const PreloadedSequence& sequence,
                                         const std::vector<Eigen::Isometry3d>& odometry,
                                         const PipelineOptions& options) {
  if (odometry.size() != sequence.frames.size()) {
    throw std::invalid_argument("RunWithOdometry: " + std::to_string(odometry.size()) +
                                " odometry poses for " + std::to_string(sequence.frames.size()) +
                                " frames");
  }
  Mapper mapper(sequence.info, options);
  std::vector<FrameResult> results;
  for (std::size_t i = 0; i < sequence.frames.size(); ++i) {
    io::Frame frame = sequence.frames[i];
    frame.T_world_body_odom = odometry[i];
    results.push_back(mapper.ProcessLoaded(frame, sequence.loaded[i]));
  }
  return results;
}

std::vector<Eigen::Isometry3d> OdometryOf(const PreloadedSequence& sequence) {
  std::vector<Eigen::Isometry3d> out;
  out.reserve(sequence.frames.size());
  for (const io::Frame& f : sequence.frames) out.push_back(f.T_world_body_odom);
  return out;
}

ChainedRun Chained(const std::vector<FrameResult>& results) {
  ChainedRun out;
  for (const FrameResult& r : results) {
    out.poses.push_back(r.step.T_world_body);
    out.yaw_from_odometry += r.index > 0 && (r.odometry_directions & kYaw) != 0;
    out.fell_back += r.status == FrameStatus::kFallback || r.status == FrameStatus::kBadFrame;
  }
  return out;
}

}  // namespace rovermap::mapper
