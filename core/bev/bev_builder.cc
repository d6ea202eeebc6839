#include "core/bev/bev_builder.h"
#include "core/config/yaml_reader.h"
#include "core/io/image_header.h"

#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <limits>
#include <stdexcept>
#include <string>

namespace lanemap::bev {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void readGround(const config::YamlReader& n, ground::GroundExtractionOptions& g) {
  n.read("sectors", g.sectors);
  n.read("range_edges_m", g.range_edges_m);
  n.read("band_base_m", g.band_base_m);
  n.read("band_slope", g.band_slope);
  n.read("distance_threshold_m", g.distance_threshold_m);
  n.read("max_tilt_deg", g.max_tilt_deg);
  n.read("min_points", g.min_points);
  n.read("max_iterations", g.max_iterations);
  if (g.sectors < 1) n.fail("sectors", "must be >= 1");
  if (g.range_edges_m.size() < 2) n.fail("range_edges_m", "must have two range edges at least");
}

}  // namespace

BevBuilderOptions BevBuilderOptions::fromYaml(const YAML::Node& n) {
  const config::YamlReader r(n);
  BevBuilderOptions o = fromYaml(r);
  r.finishSections();  // the top level also holds lanemap-bev-builder's own keys (osm, store, ...)
  return o;
}

BevBuilderOptions BevBuilderOptions::fromYaml(const config::YamlReader& n) {
  BevBuilderOptions o;
  const auto grid = n.section("grid");
  grid.read("resolution_m", o.accumulator.grid.resolution_m);
  grid.read("tile_cells", o.accumulator.grid.tile_cells);
  o.projector.resolution_m = o.accumulator.grid.resolution_m;
  const auto p = n.section("projection");
  p.read("max_range_m", o.projector.max_range_m);
  p.read("sample_spacing_m", o.projector.sample_spacing_m);
  p.read("lane_separation", o.projector.lane_separation);
  p.read("max_separation_gap_m", o.projector.max_separation_gap_m);
  p.read("mesh_raster", o.projector.mesh_raster);
  p.read("crown_slope", o.crown.slope);
  p.read("crown_fade_m", o.crown.fade_m);
  if (!(o.crown.slope >= 0.0 && o.crown.slope <= 0.1)) p.fail("crown_slope", "must be in [0, 0.1] (a cross-slope, rise over run)");
  if (!(o.crown.fade_m >= 0.0)) p.fail("crown_fade_m", "must be >= 0");
  const auto corridor = n.section("corridor");
  corridor.read("half_width_m", o.accumulator.corridor.half_width_m);
  corridor.read("mask_cell_m", o.accumulator.corridor.mask_cell_m);
  corridor.read("include_rois", o.accumulator.corridor.include_rois);
  n.read("history_s", o.accumulator.history_s);
  const auto l = n.section("lidar");
  l.read("enabled", o.use_lidar);
  l.read("async", o.async_mesh);
  l.read("max_mesh_age_s", o.max_mesh_age_s);
  l.read("mesh_wait_s", o.mesh_wait_s);
  l.read("mesh_history_s", o.mesh_history_s);
  l.read("max_edge_m", o.ground.max_edge_m);
  l.read("max_range_m", o.ground.max_range_m);
  l.read("decimate_m", o.ground.decimate_m);
  l.read("index_cell_m", o.ground.index.cell_m);
  readGround(l.section("ground"), o.ground.extraction);
  const auto poses = n.section("poses");
  poses.read("keep_s", o.pose_keep_s);
  poses.read("max_gap_s", o.max_pose_gap_s);
  poses.read("smooth_s", o.pose_smooth_s);
  poses.read("time_jump_s", o.time_jump_s);
  n.read("max_pending_frames", o.max_pending_frames);
  n.read("close_delay_s", o.close_delay_s);
  if (!(o.projector.max_range_m > 0.0)) p.fail("max_range_m", "must be > 0");
  if (!(o.ground.index.cell_m > 0.0)) l.fail("index_cell_m", "must be > 0");
  if (!(o.pose_keep_s > 0.0)) poses.fail("keep_s", "must be > 0");
  if (!(o.pose_smooth_s >= 0.0 && o.pose_smooth_s <= 1.0)) poses.fail("smooth_s", "must be in [0, 1]");
  if (!(o.accumulator.grid.resolution_m > 0.0)) grid.fail("resolution_m", "must be > 0");
  return o;
}

bool decodeLabelImage(LabelEncoding encoding, const uint8_t* data, size_t size, int width, int height, cv::Mat* out) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) return false;  // as seg::decodeFrame
  if (encoding == LabelEncoding::kRaw) {
    if (size != static_cast<size_t>(width) * height) return false;
    *out = cv::Mat(height, width, CV_8UC1, const_cast<uint8_t*>(data)).clone();
    return true;
  }
  if (encoding != LabelEncoding::kPng || size == 0 || size > 0x7FFFFFFFu) return false;
  // A PNG whose header claims another size is refused before imdecode allocates for it.
  const auto header = io::pngSize(data, size);
  if (!header || header->width != width || header->height != height) return false;
  const cv::Mat buf(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data));
  cv::Mat img;
  try {
    img = cv::imdecode(buf, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    return false;
  }
  if (img.empty() || img.type() != CV_8UC1 || img.cols != width || img.rows != height) return false;
  *out = img;
  return true;
}

namespace {

// Releases a held mutex for a scope (and takes it again, also on an exception). The BEV builder's
// state other than the worker's queue and finished meshes is changed by the caller's thread only
// (every public method is called from one thread, the LCM thread or the log reader), so the caller
// may work without the lock on what it alone changes.
struct Unlocked {
  explicit Unlocked(std::mutex& m) : m(m) { m.unlock(); }
  ~Unlocked() { m.lock(); }
  Unlocked(const Unlocked&) = delete;
  Unlocked& operator=(const Unlocked&) = delete;
  std::mutex& m;
};

}  // namespace

BevBuilder::BevBuilder(const skeleton::Skeleton& skeleton, const camera::CameraModel& camera, BevBuilderOptions options)
    : skeleton_(skeleton),
      options_(options),
      projector_(camera, options.projector),
      accumulator_(skeleton, options.accumulator),
      poses_(options.pose_keep_s, options.max_pose_gap_s, options.pose_smooth_s),
      pose_order_(options.time_jump_s, 3) {
  if (options_.use_lidar && options_.async_mesh) worker_ = std::thread([this] { workerLoop(); });
}

BevBuilder::~BevBuilder() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void BevBuilder::addPose(const TimedPose& pose) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.poses_received;
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) {
    ++stats_.poses_invalid;
    return;
  }
  switch (pose_order_.check(pose.utime)) {
    case geo::TimeOrder::Verdict::kInOrder:
      break;
    case geo::TimeOrder::Verdict::kDuplicate:
      ++stats_.poses_duplicate;
      return;
    case geo::TimeOrder::Verdict::kOutOfOrder:
      ++stats_.poses_out_of_order;
      return;
    case geo::TimeOrder::Verdict::kRestart:
      // The time went back (a log restarted): roads already closing are complete and handed
      // over; frames and the sweep waiting for a pose of the old time never get one.
      ++stats_.pose_time_jumps;
      projectDecided(true);  // the frames decided in the old time go in, as if projected at once
      finishCloses(true);
      stats_.frames_time_jump += static_cast<int64_t>(pending_.size());
      pending_.clear();
      if (pending_sweep_) ++stats_.sweeps_no_pose;
      pending_sweep_.reset();
      poses_.clear();
      last_frame_utime_ = std::numeric_limits<int64_t>::min();
      newest_decided_utime_ = std::numeric_limits<int64_t>::min();
      break;
  }
  if (!poses_.add(pose)) {  // finite but a zero quaternion
    ++stats_.poses_invalid;
    return;
  }
  tryPendingSweep();  // first: a frame may be waiting for this sweep's mesh
  drainFrames();
  finishCloses(false);
}

void BevBuilder::addEncodedFrame(int64_t utime, LabelEncoding encoding, const std::vector<uint8_t>& data, int width,
                                 int height) {
  cv::Mat labels;
  if (!decodeLabelImage(encoding, data.data(), data.size(), width, height, &labels)) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.frames_received;
    ++stats_.frames_decode_error;
    return;
  }
  addFrame(utime, labels);
}

void BevBuilder::addFrame(int64_t utime, const cv::Mat& labels) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.frames_received;
  switch (projector_.check(labels)) {
    case LabelCheck::kOk: break;
    case LabelCheck::kUnknownClass: ++stats_.frames_unknown_class; return;
    default: ++stats_.frames_wrong_size; return;
  }
  if (utime <= last_frame_utime_) {
    ++stats_.frames_out_of_order;
    return;
  }
  last_frame_utime_ = utime;
  if (pending_.size() >= options_.max_pending_frames) {
    pending_.pop_front();
    ++stats_.frames_queue_full;
  }
  pending_.push_back(PendingFrame{utime, labels.clone()});
  drainFrames();
}

// Projects the waiting frames whose pose is known, oldest first; stops at the first that needs a
// later pose or message. First each frame's mesh is decided, in order and once (nearestDecodedSweep),
// as far as the frames can be; then the frames are projected. When a frame's mesh is still in the
// worker the caller waits for it (live: a few ms, so that a frame is never left waiting after the
// last message) or, with offline_pipeline, leaves it for a later message (a road closing first
// waits for the frames decided before it, finishCloses): the decisions, taken message by message,
// and what goes into each road are the same either way.
void BevBuilder::drainFrames() {
  decideMeshes();
  projectDecided(!options_.offline_pipeline);
}

void BevBuilder::decideMeshes() {
  for (auto& f : pending_) {
    if (f.mesh_decided) continue;
    Eigen::Isometry3d pose;
    const auto r = poses_.lookup(f.utime, &pose, finishing_);
    if (r == PoseBuffer::Lookup::kTooNew || r == PoseBuffer::Lookup::kEmpty) break;
    if (r != PoseBuffer::Lookup::kOk) continue;  // never projected: counted by projectDecided
    const int64_t nearest = nearestDecodedSweep(f.utime);
    const auto wait = meshWait(f.utime, nearest);
    if (wait == MeshWait::kSweepNeedsPoses) break;  // the next pose decodes it
    if (wait == MeshWait::kSweepToCome) {
      if (static_cast<double>(poses_.newest() - f.utime) < options_.mesh_wait_s * 1e6) break;
      ++stats_.frames_mesh_wait_expired;
    }
    f.mesh_decided = true;
    f.mesh_utime = nearest;
    newest_decided_utime_ = f.utime;
  }
}

void BevBuilder::projectDecided(bool wait_for_worker) {
  while (!pending_.empty()) {
    PendingFrame& f = pending_.front();
    Eigen::Isometry3d pose;
    const auto r = poses_.lookup(f.utime, &pose, finishing_);
    if (r == PoseBuffer::Lookup::kTooNew || r == PoseBuffer::Lookup::kEmpty) return;
    if (r == PoseBuffer::Lookup::kOk) {
      if (!f.mesh_decided) return;
      if (f.mesh_utime != 0 && inWorker(f.mesh_utime)) {
        if (!wait_for_worker) return;  // a later message (or finish) projects it
        // Releases mutex_ while the worker finishes (it publishes under mutex_), then looks again.
        const int64_t target = f.mesh_utime;
        cv_.wait(mutex_, [&] { return stop_ || !inWorker(target); });
        if (stop_) return;
        continue;
      }
      project(f.utime, f.labels, pose, f.mesh_utime);
    } else if (r == PoseBuffer::Lookup::kTooOld) {
      ++stats_.frames_late;
    } else {
      ++stats_.frames_no_pose;
    }
    pending_.pop_front();
  }
}

BevBuilder::MeshWait BevBuilder::meshWait(int64_t utime, int64_t nearest) const {
  if (!options_.use_lidar || finishing_ || newest_sweep_end_ == 0) return MeshWait::kNo;
  if (newest_sweep_end_ < utime - 1000000) return MeshWait::kNo;  // no sweep for a second: no LIDAR now
  // Only a sweep that may be nearer than the nearest decoded one is worth waiting for.
  const double best =
      nearest != 0 ? std::abs(static_cast<double>(nearest - utime)) : options_.max_mesh_age_s * 1e6;
  auto near = [&](int64_t mid) { return std::abs(static_cast<double>(mid - utime)) < best; };
  // A sweep waiting for its poses is decoded as soon as the poses pass its last packet.
  if (pending_sweep_ && near(pending_sweep_->packet_utime.front() +
                             (pending_sweep_->packet_utime.back() - pending_sweep_->packet_utime.front()) / 2)) {
    return MeshWait::kSweepNeedsPoses;
  }
  return newest_sweep_end_ + 5000 < utime ? MeshWait::kSweepToCome : MeshWait::kNo;
}

int64_t BevBuilder::nearestDecodedSweep(int64_t utime) const {
  int64_t target = 0;
  double best = options_.max_mesh_age_s * 1e6;
  auto consider = [&](int64_t mid) {
    const double d = std::abs(static_cast<double>(mid - utime));
    if (d < best || (d == best && (target == 0 || mid < target))) {
      best = d;
      target = mid;
    }
  };
  for (const auto& m : meshes_) {
    if (m->mesh) consider(m->utime);
  }
  if (working_) consider(working_utime_);
  for (const auto& w : work_) consider(w.utime_mid);
  return target;
}

bool BevBuilder::inWorker(int64_t sweep_utime) const {
  if (working_ && working_utime_ == sweep_utime) return true;
  for (const auto& w : work_) {
    if (w.utime_mid == sweep_utime) return true;
  }
  return false;
}

void BevBuilder::project(int64_t utime, const cv::Mat& labels, const Eigen::Isometry3d& pose, int64_t mesh_utime) {
  const auto t0 = std::chrono::steady_clock::now();
  std::shared_ptr<const ground::SweepGround> mesh;
  if (mesh_utime != 0) {
    for (const auto& m : meshes_) {
      if (m->utime == mesh_utime && m->mesh) mesh = m;
    }
  }
  const bool use_mesh = mesh != nullptr;
  if (on_mesh_choice_) on_mesh_choice_(utime, use_mesh ? mesh->utime : 0);
  FrameSplat splat;
  {
    // The projection reads only the frame, the pose and the mesh (held here): the worker may take
    // the lock meanwhile.
    const Unlocked unlocked(mutex_);
    std::optional<RoadCrown> crown;
    if (!use_mesh) crown = RoadCrown::around(skeleton_, pose, options_.crown);
    splat = projector_.project(labels, pose, use_mesh ? mesh->mesh.get() : nullptr, crown ? &*crown : nullptr);
  }
  splat.utime = utime;
  accumulator_.add(splat);
  ++stats_.frames_projected;
  ++(use_mesh ? stats_.frames_mesh : stats_.frames_flat);
  const double ms = msSince(t0);
  stats_.project_ms_sum += ms;
  stats_.project_ms_max = std::max(stats_.project_ms_max, ms);
  if (on_projected_) on_projected_(utime);
}

void BevBuilder::addSweep(SweepData sweep) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.sweeps_received;
  if (!options_.use_lidar) return;
  if (sweep.packets.empty() || sweep.packets.size() != sweep.packet_utime.size()) {
    ++stats_.sweeps_empty;
    return;
  }
  if (pending_sweep_) ++stats_.sweeps_no_pose;  // the older one never got its poses
  newest_sweep_end_ = std::max(newest_sweep_end_, sweep.packet_utime.back());
  pending_sweep_ = std::move(sweep);
  tryPendingSweep();
  drainFrames();  // a frame may have waited for this sweep (one without a mesh to come)
}

// Decodes the waiting sweep once the poses cover its last packet; builds (or queues) its mesh.
void BevBuilder::tryPendingSweep() {
  if (!pending_sweep_ || poses_.newest() < pending_sweep_->packet_utime.back() + poses_.leadUs()) return;
  std::vector<ground::SweepPacket> packets;
  for (size_t i = 0; i < pending_sweep_->packets.size(); ++i) {
    const auto& p = pending_sweep_->packets[i];
    packets.push_back(ground::SweepPacket{pending_sweep_->packet_utime[i], p.data(), p.size()});
  }
  std::optional<ground::SweepPoints> points;
  {
    // Decoding needs only the poses, which only the caller's thread changes: the worker may take
    // the lock meanwhile (to publish a mesh and take the next sweep).
    const Unlocked unlocked(mutex_);
    points = ground::sweepToEnu(packets, options_.lidar_to_vehicle, [this](int64_t u) { return poses_.at(u); });
  }
  pending_sweep_.reset();
  if (!points) {
    ++stats_.sweeps_no_pose;
    return;
  }
  if (!options_.async_mesh) {
    buildMesh(*points);
    return;
  }
  if (work_.size() >= kMaxQueuedSweeps && options_.offline_pipeline) {
    // Releases mutex_ while the worker catches up (it publishes under mutex_).
    cv_.wait(mutex_, [this] { return stop_ || work_.size() < kMaxQueuedSweeps; });
    if (stop_) return;
  }
  if (work_.size() >= kMaxQueuedSweeps) {
    work_.pop_front();
    ++stats_.sweeps_replaced;
  }
  work_.push_back(std::move(*points));
  cv_.notify_all();
}

// Called with mutex_ held (sync mode) or without it (worker); takes the lock only to publish.
void BevBuilder::buildMesh(const ground::SweepPoints& points) {
  const auto t0 = std::chrono::steady_clock::now();
  auto g = std::make_shared<const ground::SweepGround>(ground::buildSweepGround(points, options_.ground));
  const double ms = msSince(t0);
  auto publish = [&] {
    meshes_.push_back(g);
    while (meshes_.size() > 1 &&
           static_cast<double>(g->utime - meshes_.front()->utime) > options_.mesh_history_s * 1e6) {
      meshes_.pop_front();
    }
    ++stats_.sweeps_meshed;
    stats_.mesh_ms_sum += ms;
    stats_.mesh_ms_max = std::max(stats_.mesh_ms_max, ms);
  };
  if (options_.async_mesh) {
    std::lock_guard<std::mutex> lock(mutex_);
    publish();
  } else {
    publish();
  }
}

void BevBuilder::workerLoop() {
  for (;;) {
    ground::SweepPoints points;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      working_ = false;
      cv_.notify_all();
      cv_.wait(lock, [this] { return stop_ || !work_.empty(); });
      if (stop_) return;
      points = std::move(work_.front());
      work_.pop_front();
      working_ = true;
      working_utime_ = points.utime_mid;
    }
    buildMesh(points);
  }
}

void BevBuilder::roadEntered(int64_t road_id, int64_t utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (int64_t id : accumulator_.activeRoads()) {
    if (id != road_id && !closing_.count(id) && accumulator_.discard(id)) ++stats_.roads_discarded;
  }
  if (accumulator_.active(road_id)) return;
  // The replay counts the frames decided but still waiting for the worker (offline_pipeline) as
  // added: the road gets the frames it would get had each been projected at its decision.
  const auto newest = newest_decided_utime_ != std::numeric_limits<int64_t>::min() ? std::optional<int64_t>(newest_decided_utime_)
                                                                                 : std::nullopt;
  if (accumulator_.open(road_id, utime, newest)) {
    ++stats_.roads_opened;
  } else {
    ++stats_.events_unknown_road;
  }
}

void BevBuilder::roadClosed(int64_t road_id, int64_t utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!accumulator_.active(road_id)) {
    ++stats_.events_unknown_road;
    return;
  }
  closing_[road_id] = utime;
  finishCloses(false);
}

bool BevBuilder::restoreRoad(int64_t road_id, BevGrid grid, int64_t utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!accumulator_.restore(road_id, std::move(grid), utime)) return false;
  ++stats_.roads_opened;
  return true;
}

void BevBuilder::roadsAbandoned(int64_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (int64_t id : accumulator_.activeRoads()) {
    if (!closing_.count(id) && accumulator_.discard(id)) ++stats_.roads_discarded;
  }
}

// Hands over the closing roads whose delay has passed (all of them at the end of the input).
void BevBuilder::finishCloses(bool all) {
  auto due = [&](int64_t event_utime) {
    return all || static_cast<double>(poses_.newest()) - static_cast<double>(event_utime) >= options_.close_delay_s * 1e6;
  };
  // The frames decided so far go into the road before it closes, as when each is projected at its
  // decision (offline_pipeline leaves some for the worker).
  if (std::any_of(closing_.begin(), closing_.end(), [&](const auto& c) { return due(c.second); })) projectDecided(true);
  for (auto it = closing_.begin(); it != closing_.end();) {
    const bool frames_waiting = !all && !pending_.empty() && pending_.front().utime <= it->second;
    if (!due(it->second) || frames_waiting) {
      ++it;
      continue;
    }
    if (auto r = accumulator_.close(it->first, it->second)) {
      closed_.push_back(std::move(*r));
      ++stats_.roads_closed;
    }
    it = closing_.erase(it);
  }
}

void BevBuilder::finish() {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return !worker_.joinable() || (work_.empty() && !working_); });
    finishing_ = true;  // no more input: nothing to wait for
    drainFrames();
    finishCloses(true);
  }
}

std::vector<RoadBev> BevBuilder::takeClosed() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<RoadBev> out = std::move(closed_);
  closed_.clear();
  return out;
}

bool BevBuilder::withOpenRoad(const std::function<void(const RoadBev&)>& f) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const RoadBev* open = nullptr;
  for (const int64_t id : accumulator_.activeRoads()) {
    const RoadBev* r = accumulator_.active(id);
    if (r && (!open || r->opened_utime >= open->opened_utime)) open = r;
  }
  if (!open) return false;
  f(*open);
  return true;
}

BevBuilderStats BevBuilder::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

size_t BevBuilder::pendingFrames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pending_.size();
}

void BevBuilder::setProjectedCallback(std::function<void(int64_t frame_utime)> callback) {
  std::lock_guard<std::mutex> lock(mutex_);
  on_projected_ = std::move(callback);
}

std::shared_ptr<const ground::SweepGround> BevBuilder::latestMesh() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return meshes_.empty() ? nullptr : meshes_.back();
}

void BevBuilder::setMeshChoiceCallback(std::function<void(int64_t frame_utime, int64_t mesh_utime)> callback) {
  std::lock_guard<std::mutex> lock(mutex_);
  on_mesh_choice_ = std::move(callback);
}

}  // namespace lanemap::bev
