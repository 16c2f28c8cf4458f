#include "service/Checkpoint.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <sstream>
#include <streambuf>
#include <system_error>
#include <type_traits>
#include <utility>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::mapper {
namespace {

namespace fs = std::filesystem;

constexpr char kSnapshotMagic[8] = {'R', 'M', 'S', 'T', 'A', 'T', 'E', '9'};
constexpr std::uint32_t kRecordMagic = 0x334A4D52;  // "RMJ3"
constexpr const char* kSnapshotName = "state.bin";
constexpr const char* kJournalName = "journal.bin";

// An std::ostream's bytes appended to a string through a 64 KiB buffer (large writes go straight
// in): the OctoMap's state, most of a snapshot, is serialised into the snapshot itself. Through
// an ostringstream it was copied three more times (the stream's doubling, str(), the append).
class AppendBuffer : public std::streambuf {
 public:
  explicit AppendBuffer(std::string* out) : out_(out) { Reset(); }
  AppendBuffer(const AppendBuffer&) = delete;
  AppendBuffer& operator=(const AppendBuffer&) = delete;
  ~AppendBuffer() override { Flush(); }
  void Flush() {
    out_->append(pbase(), static_cast<std::size_t>(pptr() - pbase()));
    Reset();
  }

 protected:
  int_type overflow(int_type c) override {
    Flush();
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n > epptr() - pptr()) {
      Flush();
      if (n >= static_cast<std::streamsize>(buffer_.size())) {
        out_->append(s, static_cast<std::size_t>(n));
        return n;
      }
    }
    std::memcpy(pptr(), s, static_cast<std::size_t>(n));
    pbump(static_cast<int>(n));
    return n;
  }
  int sync() override {
    Flush();
    return 0;
  }

 private:
  void Reset() { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
  std::array<char, 1 << 16> buffer_{};
  std::string* out_;
};

// Plain values appended in the machine's byte order: the checkpoint is read back by the
// machine that wrote it.
class Writer {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    data_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void Bytes(const void* data, std::size_t size) {
    Put<std::uint64_t>(size);
    data_.append(static_cast<const char*>(data), size);
  }
  void String(std::string_view s) { Bytes(s.data(), s.size()); }
  /// As Bytes, for what `write` puts into an std::ostream, streamed in place (the size filled
  /// in after); returns what `write` returned.
  template <typename Write>
  bool Streamed(const Write& write) {
    const std::size_t at = data_.size();
    Put<std::uint64_t>(0);
    bool ok = false;
    {
      AppendBuffer buffer(&data_);
      std::ostream out(&buffer);
      ok = write(out);
    }
    const std::uint64_t size = data_.size() - at - sizeof(std::uint64_t);
    std::memcpy(data_.data() + at, &size, sizeof(size));
    return ok;
  }
  template <typename Derived>
  void Matrix(const Eigen::MatrixBase<Derived>& m) {
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      for (Eigen::Index c = 0; c < m.cols(); ++c) Put<double>(m(r, c));
  }
  void Pose(const Eigen::Isometry3d& T) { Matrix(T.matrix()); }
  void OptionalPose(const std::optional<Eigen::Isometry3d>& T) {
    Put<std::uint8_t>(T ? 1 : 0);
    if (T) Pose(*T);
  }
  // The field operations VisitResult calls, mirrored in Reader.
  template <typename Stored, typename Field>
  void Value(const Field& v) {
    Put<Stored>(static_cast<Stored>(v));
  }
  void Flag(bool b) { Put<std::uint8_t>(b ? 1 : 0); }
  template <typename E>
  void Enum(E e, E /*last*/) {
    Put<std::int32_t>(static_cast<std::int32_t>(e));
  }
  void Text(const std::string& s) { String(s); }
  /// Plain values stored as bytes (a vector of doubles, of Eigen vectors).
  template <typename T>
  void Array(const std::vector<T>& v) {
    Bytes(v.data(), v.size() * sizeof(T));
  }
  /// A container's elements, each with `visit(io, element)`.
  template <typename Container, typename Visit>
  void Seq(const Container& c, Visit&& visit) {
    Put<std::uint64_t>(c.size());
    for (const auto& e : c) visit(*this, e);
  }
  std::string& data() { return data_; }

 private:
  std::string data_;
};

// Reads what Writer wrote; running past the end is a damaged file.
class Reader {
 public:
  Reader(std::string_view data, std::string what) : data_(data), what_(std::move(what)) {}
  template <typename T>
  T Get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    std::memcpy(&value, Take(sizeof(T)), sizeof(T));
    return value;
  }
  std::string_view Bytes() {
    const auto size = Get<std::uint64_t>();
    if (size > data_.size() - offset_) Fail();
    return {Take(size), static_cast<std::size_t>(size)};
  }
  std::string String() { return std::string(Bytes()); }
  template <typename M>
  void Matrix(M* m) {
    for (Eigen::Index r = 0; r < m->rows(); ++r)
      for (Eigen::Index c = 0; c < m->cols(); ++c) (*m)(r, c) = Get<double>();
  }
  Eigen::Isometry3d Pose() {
    Eigen::Isometry3d T;
    Matrix(&T.matrix());
    return T;
  }
  std::optional<Eigen::Isometry3d> OptionalPose() {
    if (Get<std::uint8_t>() == 0) return std::nullopt;
    return Pose();
  }
  // Writer's field operations, reading into the field.
  template <typename Stored, typename Field>
  void Value(Field& v) {
    v = static_cast<Field>(Get<Stored>());
  }
  void Flag(bool& b) { b = Get<std::uint8_t>() != 0; }
  /// An enumerator stored as int32; a value beyond [0, last] is a damaged file.
  template <typename E>
  void Enum(E& e, E last) {
    const auto v = Get<std::int32_t>();
    if (v < 0 || v > static_cast<std::int32_t>(last)) Fail();
    e = static_cast<E>(v);
  }
  void Text(std::string& s) { s = String(); }
  template <typename T>
  void Array(std::vector<T>& v) {
    const std::string_view bytes = Bytes();
    if (bytes.size() % sizeof(T) != 0) Fail();
    v.resize(bytes.size() / sizeof(T));
    if (!v.empty()) std::memcpy(static_cast<void*>(v.data()), bytes.data(), bytes.size());
  }
  template <typename Container, typename Visit>
  void Seq(Container& c, Visit&& visit) {
    c.clear();
    c.resize(Count(left()));  // every element takes a byte at least
    for (auto& e : c) visit(*this, e);
  }
  template <typename Derived>
  void Matrix(Eigen::MatrixBase<Derived>& m) {
    Matrix(&m);
  }
  void Pose(Eigen::Isometry3d& T) { Matrix(&T.matrix()); }
  void OptionalPose(std::optional<Eigen::Isometry3d>& T) { T = OptionalPose(); }
  std::size_t Count(std::size_t max) {
    const auto n = Get<std::uint64_t>();
    if (n > max) Fail();
    return static_cast<std::size_t>(n);
  }
  bool AtEnd() const { return offset_ == data_.size(); }
  std::size_t left() const { return data_.size() - offset_; }
  [[noreturn]] void Fail() const {
    throw CheckpointError(what_ + ": damaged (truncated or malformed)");
  }

 private:
  const char* Take(std::size_t n) {
    if (n > data_.size() - offset_) Fail();
    const char* p = data_.data() + offset_;
    offset_ += n;
    return p;
  }
  std::string_view data_;
  std::string what_;
  std::size_t offset_ = 0;
};

// Every field of a ChainStep and a FrameResult in the file's order, for both directions: Io is
// Writer (with const fields) or Reader. A new field is added here, once.
template <typename Io, typename Step>
void VisitStep(Io& io, Step& s) {
  io.template Value<std::uint64_t>(s.index);
  io.Pose(s.T_world_body);
  io.Pose(s.T_world_body_odom);
  io.Pose(s.odom_increment);
  io.Pose(s.used_increment);
  io.Pose(s.increment_correction);
  io.Pose(s.cumulative_correction);
  io.Flag(s.fallback);
  io.Matrix(s.covariance);
  io.Matrix(s.systematic_cross);
}

template <typename Io, typename Result>
void VisitResult(Io& io, Result& f) {
  io.template Value<std::uint64_t>(f.index);
  io.template Value<double>(f.timestamp);
  io.Enum(f.status, FrameStatus::kBadFrame);
  io.Enum(f.fallback_reason, FallbackReason::kMissing);
  io.Text(f.detail);
  VisitStep(io, f.step);
  io.OptionalPose(f.T_world_body_truth);
  io.template Value<std::uint32_t>(f.odometry_directions);
  io.Enum(f.image_check, ImageCheckOutcome::kFailed);
  io.Text(f.matcher_status);
  io.template Value<std::int32_t>(f.iterations);
  io.template Value<std::uint64_t>(f.inliers);
  io.template Value<double>(f.inlier_ratio);
  io.template Value<double>(f.rms_m);
  io.template Value<double>(f.conditioning);
  io.template Value<std::uint64_t>(f.points);
  io.template Value<std::uint64_t>(f.outliers_removed);
  io.template Value<std::uint64_t>(f.dropped_nonfinite);
  auto& d = f.dem;
  for (auto* v :
       {&d.points, &d.fused, &d.candidate, &d.swapped, &d.rejected_outliers, &d.dropped_nonfinite,
        &d.dropped_out_of_grid, &d.dropped_imprecise, &d.new_tiles, &d.cells_cleared}) {
    io.template Value<std::uint64_t>(*v);
  }
  auto& t = f.time;
  for (auto* v : {&t.load_ms, &t.stereo_ms, &t.prepare_ms, &t.register_ms, &t.fuse_dem_ms,
                  &t.fuse_octomap_ms, &t.total_ms}) {
    io.template Value<double>(*v);
  }
  io.OptionalPose(f.T_world_body_registered);
  io.Matrix(f.increment_covariance);
  io.template Value<double>(f.reference_distance_m);
  io.Matrix(f.odometry_bias.bias);  // a column: the six entries in order
  io.Matrix(f.odometry_bias.information);
}

// The pose graph's sources (GraphRun's tracks): their matches and the ground they keep for the
// next ones. As above, every field once, in the file's order.
template <typename Io, typename P>
void VisitPost(Io& io, P& p) {
  io.Matrix(p.p);
  io.template Value<std::uint64_t>(p.points);
  io.template Value<double>(p.sigma_m);
}

template <typename Io, typename G>
void VisitGrid(Io& io, G& g) {
  io.Matrix(g.origin_world);
  io.template Value<double>(g.spacing_m);
  io.template Value<std::int32_t>(g.width);
  io.template Value<std::int32_t>(g.height);
  io.Array(g.z_m);
  io.Array(g.sigma_m);
}

template <typename Io, typename M>
void VisitMatch(Io& io, M& m) {
  io.template Value<std::uint64_t>(m.frame);
  io.template Value<std::uint64_t>(m.first_frame);
  io.template Value<std::uint64_t>(m.last_frame);
  io.Flag(m.matched);
  io.Text(m.reason);
  io.template Value<std::uint64_t>(m.posts);
  io.template Value<double>(m.rms_before_m);
  io.template Value<double>(m.rms_after_m);
  io.Pose(m.correction);
  io.Pose(m.T_world_body);
  io.Flag(m.vertical_absolute);
  io.template Value<double>(m.placement_sigma_m);
  io.Matrix(m.information);
  io.template Value<double>(m.sigma_x_m);
  io.template Value<double>(m.sigma_y_m);
  io.template Value<double>(m.sigma_yaw_deg);
  io.template Value<double>(m.relief_ratio);
  io.template Value<std::int32_t>(m.starts);
  io.template Value<double>(m.ms);
}

template <typename Io, typename R>
void VisitRevisit(Io& io, R& r) {
  io.template Value<std::uint64_t>(r.from_frame);
  VisitMatch(io, r.match);
  io.template Value<std::uint64_t>(r.factor.from);
  io.template Value<std::uint64_t>(r.factor.to);
  io.Pose(r.factor.T_from_to);
  io.Matrix(r.factor.information);
}

void PutResult(Writer* w, const FrameResult& f) { VisitResult(*w, f); }

FrameResult GetResult(Reader* r) {
  FrameResult f;
  VisitResult(*r, f);
  return f;
}

void PutIndices(Writer* w, const std::vector<std::size_t>& v) {
  w->Put<std::uint64_t>(v.size());
  for (std::size_t i : v) w->Put<std::uint64_t>(i);
}

std::vector<std::size_t> GetIndices(Reader* r) {
  std::vector<std::size_t> v(r->Count(r->left() / 8));
  for (std::size_t& i : v) i = r->Get<std::uint64_t>();
  return v;
}

void PutDaemon(Writer* w, const DaemonState& s) {
  w->Put<std::uint64_t>(s.next_index);
  PutIndices(w, s.missing);
  PutIndices(w, s.rejected);
}

DaemonState GetDaemon(Reader* r) {
  DaemonState s;
  s.next_index = r->Get<std::uint64_t>();
  s.missing = GetIndices(r);
  s.rejected = GetIndices(r);
  return s;
}

template <typename T>
void PutVector(Writer* w, const std::vector<T>& v) {
  w->Bytes(v.data(), v.size() * sizeof(T));
}

template <typename T>
std::vector<T> GetVector(Reader* r) {
  const std::string_view bytes = r->Bytes();
  if (bytes.size() % sizeof(T) != 0) r->Fail();
  std::vector<T> v(bytes.size() / sizeof(T));
  if (!v.empty()) std::memcpy(static_cast<void*>(v.data()), bytes.data(), bytes.size());
  return v;
}

void PutCloud(Writer* w, const registration::PointCloud& c) {
  PutVector(w, c.points);
  PutVector(w, c.normals);
  PutVector(w, c.covariances);
  PutVector(w, c.chain_ids);
}

registration::PointCloud GetCloud(Reader* r) {
  registration::PointCloud c;
  c.points = GetVector<Eigen::Vector3d>(r);
  c.normals = GetVector<Eigen::Vector3d>(r);
  c.covariances = GetVector<Eigen::Matrix3d>(r);
  c.chain_ids = GetVector<int>(r);
  return c;
}

// One journal record: magic, payload length, CRC-32 of the payload, payload.
struct RecordHeader {
  std::uint32_t magic = kRecordMagic;
  std::uint32_t length = 0;
  std::uint32_t crc = 0;
};

void WriteAll(int fd, std::string_view data, const fs::path& path) {
  if (const int err = io::WriteAll(fd, data); err != 0) {
    throw io::IoError(path.string() + ": cannot write (" + std::strerror(err) + ")");
  }
}

}  // namespace

std::string EncodeFrameResult(const FrameResult& result) {
  Writer w;
  PutResult(&w, result);
  return std::move(w.data());
}

FrameResult DecodeFrameResult(std::string_view bytes) {
  Reader r(bytes, "frame result");
  FrameResult result = GetResult(&r);
  if (!r.AtEnd()) r.Fail();
  return result;
}

// The Mapper's private state, written and read here only.
struct CheckpointAccess {
  static void Save(const Mapper& m, Writer* w) {
    w->Put<std::uint64_t>(m.results_.size());
    for (const FrameResult& f : m.results_) PutResult(w, f);
    // The chain is not saved: its steps are the results' (every frame chained has one).
    w->Put<double>(m.attitude_.variance());
    w->Put<std::uint8_t>(m.reference_index_ ? 1 : 0);
    w->Put<std::uint64_t>(m.reference_index_.value_or(0));
    w->Put<double>(m.last_reference_distance_m_);
    // The previous frame's cloud is not saved (a stereo frame's points with their covariances
    // are many megabytes; docs/benchmarks.md, "Figures behind the daemon's code"): restoring
    // loads that frame from the inbox again, which gives the same points.
    const bool previous =
        m.previous_ && m.reference_index_ && *m.reference_index_ < m.results_.size();
    w->Put<std::uint8_t>(previous ? 1 : 0);
    if (previous) w->Put<std::uint64_t>(m.results_[*m.reference_index_].index);
    w->Put<std::uint64_t>(m.local_map_.clouds().size());
    for (const registration::PointCloud& c : m.local_map_.clouds()) PutCloud(w, c);

    // The DEM: only the filled cells of each tile (a tile is mostly empty at the map's edge).
    const dem::ElevationMap& map = m.elevation_map_;
    const dem::CellBounds& bounds = map.bounds();
    w->Put<std::uint8_t>(bounds.Empty() ? 0 : 1);
    if (!bounds.Empty()) {
      w->Put(bounds.Min());
      w->Put(bounds.Max());
    }
    w->Put<std::uint64_t>(map.covariances_ignored());
    std::vector<dem::TileIndex> tiles = map.TileIndices();
    std::sort(tiles.begin(), tiles.end(), [](const dem::TileIndex& a, const dem::TileIndex& b) {
      return std::make_pair(a.x, a.y) < std::make_pair(b.x, b.y);
    });
    w->Put<std::uint64_t>(tiles.size());
    for (const dem::TileIndex& t : tiles) {
      const dem::Tile* tile = map.FindTile(t);
      w->Put(t);
      std::vector<std::uint32_t> where;
      std::vector<dem::CellRecord> records;
      std::vector<dem::CellEvidence> evidence;
      for (std::size_t i = 0; i < tile->cells.size(); ++i) {
        const dem::CellRecord& c = tile->cells[i];
        if (c.value.count == 0 && c.candidate.count == 0) continue;
        where.push_back(static_cast<std::uint32_t>(i));
        records.push_back(c);
        evidence.push_back(tile->evidence[i]);
      }
      PutVector(w, where);
      PutVector(w, records);
      PutVector(w, evidence);
    }
    if (!w->Streamed([&](std::ostream& out) { return m.octomap_.Fusion().Save(out); }))
      throw CheckpointError("cannot serialise the OctoMap");
  }

  // GraphRun's tracks: a flag and the state of each (a track the run has not is read and
  // dropped: a reference DEM usable before the restart and not now).
  template <typename Io, typename P>
  static void VisitPatches(Io& io, P& p) {
    io.Seq(p.frames_, [](auto& io2, auto& placed) {
      io2.template Value<std::uint64_t>(placed.frame);
      io2.Array(placed.centroid);
      io2.Array(placed.weight);
      io2.Array(placed.count);
      io2.Flag(placed.weighted);
    });
    io.Array(p.path_m_);
    io.Matrix(p.last_position_);
  }
  template <typename Io, typename Last, typename Seed, typename Patches, typename Matches>
  static void VisitReferenceTrack(Io& io, Last& last_match_m, Seed& seed, Patches& patches,
                                  Matches& matches) {
    io.template Value<double>(last_match_m);
    io.Pose(seed);
    VisitPatches(io, patches);
    io.Seq(matches, [](auto& io2, auto& m) { VisitMatch(io2, m); });
  }
  template <typename Io, typename Last, typename Patches, typename Saved, typename Matches>
  static void VisitRevisitTrack(Io& io, Last& last_look_m, Patches& patches, Saved& saved,
                                Matches& matches) {
    io.template Value<double>(last_look_m);
    VisitPatches(io, patches);
    io.Seq(saved, [](auto& io2, auto& s) {
      io2.Seq(s.posts, [](auto& io3, auto& post) { VisitPost(io3, post); });
      VisitGrid(io2, s.grid);
      io2.Matrix(s.box.min());
      io2.Matrix(s.box.max());
      io2.template Value<std::uint64_t>(s.frame);
      io2.template Value<double>(s.path_m);
    });
    io.Seq(matches, [](auto& io2, auto& m) { VisitRevisit(io2, m); });
  }

  static void SaveGraph(const GraphRun* g, Writer* w) {
    const ReferenceTrack* t = g ? g->track_.get() : nullptr;
    w->Put<std::uint8_t>(t ? 1 : 0);
    if (t) VisitReferenceTrack(*w, t->last_match_m_, t->seed_, t->patches_, t->matches_);
    const RevisitTrack* v = g ? g->revisit_.get() : nullptr;
    w->Put<std::uint8_t>(v ? 1 : 0);
    if (v) VisitRevisitTrack(*w, v->last_look_m_, v->patches_, v->saved_, v->matches_);
  }

  static void RestoreGraph(Reader* r, GraphRun* g) {
    if (r->Get<std::uint8_t>() != 0) {
      double last = 0.0;
      Eigen::Isometry3d seed = Eigen::Isometry3d::Identity();
      PatchAccumulator patches;
      std::vector<ReferenceMatch> matches;
      VisitReferenceTrack(*r, last, seed, patches, matches);
      if (ReferenceTrack* t = g ? g->track_.get() : nullptr) {
        t->last_match_m_ = last;
        t->seed_ = seed;
        t->patches_ = std::move(patches);
        t->matches_ = std::move(matches);
      }
    }
    if (r->Get<std::uint8_t>() != 0) {
      double last = 0.0;
      PatchAccumulator patches;
      std::vector<RevisitTrack::Saved> saved;
      std::vector<RevisitMatch> matches;
      VisitRevisitTrack(*r, last, patches, saved, matches);
      if (RevisitTrack* v = g ? g->revisit_.get() : nullptr) {
        v->last_look_m_ = last;
        v->patches_ = std::move(patches);
        v->saved_ = std::move(saved);
        v->matches_ = std::move(matches);
      }
    }
  }

  static void Restore(Reader* r, Mapper* m,
                      const std::function<io::Frame(std::size_t)>& read_frame) {
    std::vector<FrameResult> results(r->Count(r->left()));
    for (FrameResult& f : results) f = GetResult(r);
    m->results_ = std::move(results);
    m->chain_.reset();
    if (!m->results_.empty()) {
      std::vector<ChainStep> steps;
      steps.reserve(m->results_.size());
      for (const FrameResult& f : m->results_) steps.push_back(f.step);
      m->chain_ = std::make_unique<PoseChain>(steps);
    }
    m->attitude_.RestoreVariance(r->Get<double>());
    const bool has_reference = r->Get<std::uint8_t>() != 0;
    const auto reference = r->Get<std::uint64_t>();
    m->reference_index_ = has_reference ? std::optional<std::size_t>(reference) : std::nullopt;
    m->last_reference_distance_m_ = r->Get<double>();
    m->previous_.reset();
    m->previous_landmarks_ = {};
    if (r->Get<std::uint8_t>() != 0) {
      const auto index = r->Get<std::uint64_t>();
      LoadedFrame loaded = LoadFrame(read_frame(index), m->sensor_, m->options_.mapper.min_points);
      if (!loaded.ok) {
        throw ReapplyError(
            "frame " + std::to_string(index) +
            ": the registration reference could be read before, not now: " + loaded.reason);
      }
      // As the frame was prepared when it became the reference (merged voxels, their D).
      PreparedFrame prepared = m->Prepare(std::move(loaded));
      m->previous_ = std::move(prepared.source);
      m->previous_landmarks_ = std::move(prepared.loaded.landmarks);
    }
    std::vector<registration::PointCloud> local(r->Count(r->left()));
    for (registration::PointCloud& c : local) c = GetCloud(r);
    m->local_map_.Restore(std::move(local));

    dem::ElevationMap& map = m->elevation_map_;
    map = dem::ElevationMap(map.options());
    dem::CellBounds bounds;
    if (r->Get<std::uint8_t>() != 0) {
      bounds.Extend(r->Get<dem::CellIndex>());
      bounds.Extend(r->Get<dem::CellIndex>());
    }
    map.RestoreCounters(bounds, r->Get<std::uint64_t>());
    const auto cells_per_tile = static_cast<std::size_t>(map.options().tile_cells) *
                                static_cast<std::size_t>(map.options().tile_cells);
    const std::size_t tiles = r->Count(r->left());
    for (std::size_t k = 0; k < tiles; ++k) {
      const auto t = r->Get<dem::TileIndex>();
      const std::vector<std::uint32_t> where = GetVector<std::uint32_t>(r);
      const std::vector<dem::CellRecord> records = GetVector<dem::CellRecord>(r);
      const std::vector<dem::CellEvidence> evidence = GetVector<dem::CellEvidence>(r);
      if (where.size() != records.size() || where.size() != evidence.size()) r->Fail();
      std::vector<dem::CellRecord> cells(cells_per_tile);
      std::vector<dem::CellEvidence> cells_evidence(cells_per_tile);
      for (std::size_t i = 0; i < where.size(); ++i) {
        if (where[i] >= cells.size()) r->Fail();
        cells[where[i]] = records[i];
        cells_evidence[where[i]] = evidence[i];
      }
      map.RestoreTile(t, std::move(cells), std::move(cells_evidence));
    }
    std::istringstream octomap(r->String(), std::ios::in | std::ios::binary);
    try {
      m->octomap_.MutableFusion().Restore(octomap);
    } catch (const std::runtime_error& e) {
      throw CheckpointError(std::string("checkpoint: ") + e.what());
    }
  }
};

namespace {

// FNV-1a, 64 bits: the fingerprint as every record carries it.
std::string Digest(std::string_view text) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    h ^= static_cast<std::uint8_t>(c);
    h *= 0x100000001b3ULL;
  }
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

}  // namespace

Checkpoint::Checkpoint(fs::path directory, std::string fingerprint, FaultHook hook)
    : directory_(std::move(directory)), fingerprint_(Digest(fingerprint)), hook_(std::move(hook)) {
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (ec) throw io::IoError(directory_.string() + ": cannot create (" + ec.message() + ")");
  // Temporaries of a snapshot a kill interrupted.
  for (const fs::directory_entry& entry : fs::directory_iterator(directory_, ec)) {
    if (entry.path().filename().string().rfind(std::string(kSnapshotName) + ".tmp-", 0) == 0) {
      fs::remove(entry.path(), ec);
    }
  }
}

void Checkpoint::CheckFingerprint(const std::string& found, const fs::path& file) const {
  if (found == fingerprint_) return;
  throw CheckpointError(file.string() +
                        ": made with another configuration or sequence.yaml; restart with the "
                        "same ones, or remove " +
                        directory_.string() + " to start over");
}

bool Checkpoint::Exists() const {
  std::error_code ec;
  return fs::exists(directory_ / kSnapshotName, ec) || fs::exists(directory_ / kJournalName, ec);
}

DaemonState Checkpoint::Restore(Mapper* mapper,
                                const std::function<io::Frame(std::size_t)>& read_frame,
                                GraphRun* graph,
                                const std::function<void(const std::string&)>& log) {
  DaemonState state;
  std::error_code ec;
  const fs::path snapshot = directory_ / kSnapshotName;
  if (fs::exists(snapshot, ec)) {
    const std::string data = io::ReadWholeFile(snapshot);
    snapshot_bytes_ = data.size();
    Reader r(data, snapshot.string());
    if (data.size() < sizeof(kSnapshotMagic) + 4 ||
        std::memcmp(data.data(), kSnapshotMagic, sizeof(kSnapshotMagic)) != 0) {
      const bool other_version =
          data.size() >= sizeof(kSnapshotMagic) &&
          std::memcmp(data.data(), kSnapshotMagic, sizeof(kSnapshotMagic) - 1) == 0;
      throw CheckpointError(snapshot.string() +
                            (other_version ? ": a checkpoint of another rovermap version (format " +
                                                 std::string(1, data[sizeof(kSnapshotMagic) - 1]) +
                                                 ", this one reads " +
                                                 kSnapshotMagic[sizeof(kSnapshotMagic) - 1] + ")"
                                           : ": not a rovermap checkpoint"));
    }
    std::uint32_t crc = 0;
    std::memcpy(&crc, data.data() + data.size() - 4, 4);
    if (Crc32(std::string_view(data).substr(0, data.size() - 4)) != crc) {
      throw CheckpointError(snapshot.string() + ": damaged (checksum mismatch)");
    }
    Reader body(std::string_view(data).substr(sizeof(kSnapshotMagic), data.size() - 12),
                snapshot.string());
    CheckFingerprint(body.String(), snapshot);
    state = GetDaemon(&body);
    CheckpointAccess::Restore(&body, mapper, read_frame);
    CheckpointAccess::RestoreGraph(&body, graph);
    if (!body.AtEnd()) body.Fail();
  }

  // The journal: records up to the first torn or damaged one, which a kill left.
  const fs::path journal = directory_ / kJournalName;
  journal_records_ = 0;
  reapplied_ = 0;
  if (!fs::exists(journal, ec)) return state;
  const std::string data = io::ReadWholeFile(journal);
  std::size_t offset = 0;
  while (data.size() - offset >= sizeof(RecordHeader)) {
    RecordHeader header;
    std::memcpy(&header, data.data() + offset, sizeof(header));
    if (header.magic != kRecordMagic || header.length > data.size() - offset - sizeof(header))
      break;
    const std::string_view payload(data.data() + offset + sizeof(header), header.length);
    if (Crc32(payload) != header.crc) break;
    Reader r(payload, journal.string());
    CheckFingerprint(r.String(), journal);
    const DaemonState after = GetDaemon(&r);
    std::optional<FrameResult> frame;
    if (r.Get<std::uint8_t>() != 0) frame = GetResult(&r);
    offset += sizeof(header) + header.length;
    ++journal_records_;
    if (after.next_index <= state.next_index) continue;  // already in the snapshot
    ++reapplied_;
    if (frame) {
      FrameBins bins;  // the graph's matches take the frame's own points (mapper/Patches)
      FrameBins* want_bins = graph && graph->wants_bins() ? &bins : nullptr;
      if (frame->status == FrameStatus::kBadFrame) {
        mapper->Reapply(*frame, nullptr);
      } else {
        const io::Frame read = read_frame(frame->index);
        mapper->Reapply(*frame, &read, want_bins);
      }
      if (graph) {
        for (const std::string& line : graph->AfterFrame(*mapper, bins, "serve")) {
          if (log) log(line);
        }
      }
    }
    state = after;
  }
  if (offset != data.size()) {
    // Cut the torn tail so that the next record follows the last good one.
    if (::truncate(journal.c_str(), static_cast<off_t>(offset)) != 0) {
      throw io::IoError(journal.string() + ": cannot truncate (" + std::strerror(errno) + ")");
    }
  }
  return state;
}

void Checkpoint::Append(const FrameResult* frame, const DaemonState& after) {
  Writer w;
  w.String(fingerprint_);
  PutDaemon(&w, after);
  w.Put<std::uint8_t>(frame ? 1 : 0);
  if (frame) PutResult(&w, *frame);
  RecordHeader header;
  header.length = static_cast<std::uint32_t>(w.data().size());
  header.crc = Crc32(w.data());

  const fs::path journal = directory_ / kJournalName;
  const io::FdGuard fd(::open(journal.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666));
  if (fd.Get() < 0) {
    throw io::IoError(journal.string() + ": cannot open (" + std::strerror(errno) + ")");
  }
  struct stat before {};
  if (::fstat(fd.Get(), &before) != 0) {
    throw io::IoError(journal.string() + ": cannot stat (" + std::strerror(errno) + ")");
  }
  try {
    WriteAll(fd.Get(), {reinterpret_cast<const char*>(&header), sizeof(header)}, journal);
    Fault("journal:partial");
    WriteAll(fd.Get(), w.data(), journal);
    if (::fdatasync(fd.Get()) != 0) {
      throw io::IoError(journal.string() + ": cannot flush (" + std::strerror(errno) + ")");
    }
  } catch (...) {
    // A record cut short (full disk, file-size limit) is cut off: left there, it would hide
    // every record appended after it from Restore, which stops at the first damaged one (if
    // this fails too, Restore still drops it as the last record).
    [[maybe_unused]] const int cut = ::ftruncate(fd.Get(), before.st_size);
    throw;
  }
  ++journal_records_;
}

void Checkpoint::Save(const Mapper& mapper, const DaemonState& state, const GraphRun* graph) {
  Writer w;
  w.data().reserve(snapshot_bytes_ + snapshot_bytes_ / 4);  // the last one's size, and growth
  w.data().append(kSnapshotMagic, sizeof(kSnapshotMagic));
  w.String(fingerprint_);
  PutDaemon(&w, state);
  CheckpointAccess::Save(mapper, &w);
  CheckpointAccess::SaveGraph(graph, &w);
  w.Put<std::uint32_t>(Crc32(w.data()));
  snapshot_bytes_ = w.data().size();

  const fs::path snapshot = directory_ / kSnapshotName;
  const fs::path temp = io::WriteTemporaryFile(snapshot, w.data());
  Fault("checkpoint:written");
  io::CommitTemporaryFile(temp, snapshot);
  io::SyncDirectory(directory_);
  Fault("checkpoint:renamed");
  // The snapshot holds every journalled frame now.
  const fs::path journal = directory_ / kJournalName;
  if (::truncate(journal.c_str(), 0) != 0 && errno != ENOENT) {
    throw io::IoError(journal.string() + ": cannot truncate (" + std::strerror(errno) + ")");
  }
  journal_records_ = 0;
}

std::uint32_t Crc32(std::string_view data) {
  // Slicing by 8 (Intel's method): eight bytes per step through eight tables, several times
  // faster than the byte-wise loop (docs/benchmarks.md, "Figures behind the daemon's code");
  // a snapshot runs to megabytes and is written every few frames.
  static const std::array<std::array<std::uint32_t, 256>, 8> table = [] {
    std::array<std::array<std::uint32_t, 256>, 8> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1U) ? 0xEDB88320U ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (std::size_t k = 1; k < 8; ++k)
      for (std::size_t i = 0; i < 256; ++i)
        t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xFFU];
    return t;
  }();
  std::uint32_t crc = 0xFFFFFFFFU;
  const auto* p = reinterpret_cast<const unsigned char*>(data.data());
  std::size_t n = data.size();
  for (; n >= 8; n -= 8, p += 8) {
    // Words assembled byte by byte: the same result whatever the machine's byte order.
    const std::uint32_t lo =
        crc ^ (static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
               static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24);
    const std::uint32_t hi =
        static_cast<std::uint32_t>(p[4]) | static_cast<std::uint32_t>(p[5]) << 8 |
        static_cast<std::uint32_t>(p[6]) << 16 | static_cast<std::uint32_t>(p[7]) << 24;
    crc = table[7][lo & 0xFFU] ^ table[6][(lo >> 8) & 0xFFU] ^ table[5][(lo >> 16) & 0xFFU] ^
          table[4][lo >> 24] ^ table[3][hi & 0xFFU] ^ table[2][(hi >> 8) & 0xFFU] ^
          table[1][(hi >> 16) & 0xFFU] ^ table[0][hi >> 24];
  }
  for (; n > 0; --n, ++p) crc = table[0][(crc ^ *p) & 0xFFU] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFU;
}

}  // namespace rovermap::mapper
