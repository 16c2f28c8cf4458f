#pragma once
// The OctoMap's insertion on a thread of its own. octomap::OcTree inserts single-threaded and
// is independent of the next frame's registration, so the two overlap; one frame at most waits,
// so memory stays flat, and frames go in order, so the tree equals a serial one.

#include <Eigen/Geometry>
#include <condition_variable>
#include <cstdint>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "dem/OctoMapFusion.hpp"

namespace rovermap::mapper {

class OctoMapWorker {
 public:
  /// @throw std::invalid_argument if `options` are invalid (dem::OctoMapFusion).
  explicit OctoMapWorker(const dem::OctoMapOptions& options);
  ~OctoMapWorker();
  OctoMapWorker(const OctoMapWorker&) = delete;
  OctoMapWorker& operator=(const OctoMapWorker&) = delete;

  /// Queues one frame's world points seen from `sensor_origin_world`; waits first while an
  /// earlier frame is still queued (not while it is being inserted). Never throws.
  void Insert(std::vector<Eigen::Vector3d> points_world, const Eigen::Vector3d& sensor_origin_world,
              std::uint32_t frame);

  /// Waits until every queued frame is in the tree, then gives the map (for writing).
  const dem::OctoMapFusion& Fusion() const;

  /// Waits until every queued frame is in the tree, then gives the map to change (restoring a
  /// checkpoint).
  dem::OctoMapFusion& MutableFusion();
  /// Milliseconds the last finished insertion took (for the report).
  double last_insert_ms() const;

  /// The tree's bytes as map.bt writes them (and map.ot's with `with_ot`), made on the worker's
  /// thread once every frame queued so far is in: the caller does not wait for the insertions
  /// (a publication's state is taken between frames; the writer waits for these instead).
  struct TreeBytes {
    std::string bt;
    std::string ot;  ///< empty unless asked for
    /// Set when the tree was moved before it was serialised (`corrections` given).
    std::optional<dem::OcTreeMoveStats> moved;
    double move_ms = 0.0;  ///< what moving it took [ms]
  };
  /// Per frame (the index InsertFrame was given), the rigid correction to move its voxels by
  /// (world frame, on the left; nullopt: they stay).
  using Corrections = std::vector<std::optional<Eigen::Isometry3d>>;
  /// With `corrections`, the bytes are those of the tree moved with them (dem::BatchOcTree::
  /// MovedCopy; the fused tree is left as it is): its voxels are read and moved on the worker's
  /// thread, the moved tree is built and serialised by the first get() of the future, on its
  /// caller's thread (a publication's writer), so the insertions go on meanwhile. Never throws;
  /// the future holds nullopt when the OctoMap is off.
  std::shared_future<std::optional<TreeBytes>> SerialiseWhenQueuedIn(
      bool with_ot, std::shared_ptr<const Corrections> corrections = nullptr) const;

 private:
  void Loop();
  struct Job {
    std::vector<Eigen::Vector3d> points;  // none: a serialisation only
    Eigen::Vector3d origin;
    std::uint32_t frame = 0;
    // Serialisations asked for once this job's points are in.
    struct Request {
      bool with_ot = false;
      std::shared_ptr<const Corrections> corrections;
      std::promise<std::optional<TreeBytes>> promise;  // without corrections
      // With corrections: the voxels moved on this thread (the tree is built where the bytes
      // are taken) and the time that took [ms].
      std::promise<std::pair<std::shared_ptr<dem::MovedVoxels>, double>> moved;
    };
    std::vector<Request> serialise;
  };
  void Serialise(std::vector<Job::Request>* requests) const;
  dem::OctoMapFusion fusion_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  mutable std::optional<Job> queued_;  // mutable: a serialisation is queued by const callers
  bool busy_ = false;
  bool stop_ = false;
  double last_insert_ms_ = 0.0;
  std::thread thread_;  // last: started once the members above exist
};

}  // namespace rovermap::mapper
