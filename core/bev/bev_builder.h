// The bev_builder's logic, LCM-free (processes/bev_builder is a thin wrapper; tests and offline
// tools drive this class directly from a log): poses, semantic frames, LIDAR sweeps and road events
// in; one BEV grid per closed atomic road out (METHOD.md section 3).
//
// - Poses go into a PoseBuffer; a frame is projected with the pose interpolated at ITS utime. A
//   frame newer than the newest pose waits in a short queue (the segmenter and the pose source are
//   not synchronised) and is projected when a later pose arrives. Frames that are out of order,
//   older than the pose history (late), inside a pose gap, of the wrong size or type, with unknown
//   class ids, or undecodable are counted and skipped (stats()); nothing blocks.
// - Poses that are NaN/infinite or out of order are counted and ignored.
// - LIDAR: a sweep waits (at most one) until the poses cover its last packet, is decoded and moved
//   to ENU in the caller's thread (a few ms), and its ground mesh (extraction + Delaunay + index,
//   tens of ms) is built either in the caller's thread (async_mesh = false: deterministic, tests)
//   or in a worker thread (async_mesh = true, the process): the LCM thread then never waits for a
//   mesh; sweeps queue for the worker in order (at most 4 waiting; beyond, the oldest is dropped,
//   counted as sweeps_replaced; with offline_pipeline the caller waits instead: lanemap-offline,
//   whose reading and projecting then overlap the meshes on a second core).
// - Which mesh a frame uses is decided by time, not by what happens to be finished: the mesh of the
//   sweep whose middle is nearest to the frame's time, if within max_mesh_age_s (the mesh is in
//   ENU and the world is static, so a neighbouring sweep's mesh covers what the camera sees); else
//   the flat plane. So that the choice does not depend on CPU load, a frame waits (in the pending
//   queue, like a frame waiting for its pose) until the sweep covering its time has come in and
//   every sweep near its time that came in has its mesh: once a sweep ending at or after the frame's
//   time is in, no later sweep can be nearer. Waiting for the sweep to come ends anyway when the
//   poses are mesh_wait_s past the frame (counted: frames_mesh_wait_expired; a LIDAR that stalls);
//   there is none when no sweep has come for a second (no LIDAR) or at finish(); a frame at most
//   5 ms past the newest sweep's end counts as covered (the gap between two sweeps: the next one
//   could be nearer by those ms only). The choice is made once per frame, in frame order, as soon
//   as it can be: the nearest decoded sweep, its mesh finished or still in the worker. When it is
//   still in the worker, the caller's thread waits for the worker (one mesh, a few ms) rather than
//   leave the frame for a later message that may not come. It costs the live graph up to one sweep
//   (0.1 s) after the frame's time plus a mesh, less the segmenter's own latency, which usually
//   covers it. With offline_pipeline (lanemap-offline) the frame is left for a later message
//   instead; a road that closes first takes the frames decided before it, and a road that opens
//   replays the history as of the newest decided frame, so every road gets the frames it gets when
//   each frame is projected at its decision: the same grids, byte for byte.
// - Roads: ROAD_EVENT "entered" opens a RoadBev (road_bev.h); "reached intersection" closes it
//   once the poses are close_delay_s past the event (frames still waiting for their pose then go in
//   first), and the grid is handed over through takeClosed(). "Left map" / "pose lost" discard the
//   open roads (incomplete). finish() hands over the roads still closing (end of a log).
#pragma once

#include "core/bev/pose_buffer.h"
#include "core/geo/time_order.h"
#include "core/bev/projector.h"
#include "core/bev/road_bev.h"
#include "core/camera/camera_model.h"
#include "core/ground/sweep_ground.h"
#include "core/skeleton/skeleton.h"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace YAML { class Node; }
namespace lanemap::config { class YamlReader; }

namespace lanemap::bev {

inline constexpr size_t kMaxQueuedSweeps = 4;  // sweeps waiting for the mesh worker

struct BevBuilderOptions {
  ProjectorOptions projector;
  AccumulatorOptions accumulator;
  ground::SweepGroundOptions ground;
  bool use_lidar = true;           // false: flat ground only
  // crown.slope > 0: a frame with no mesh is projected on the crown of the road the car drives
  // (road_crown.h); 0 (the default): on the flat plane under the car.
  CrownOptions crown;
  bool async_mesh = true;          // build meshes in a worker thread
  // With async_mesh, for a reader that can wait (lanemap-offline): true: when kMaxQueuedSweeps
  // sweeps already wait for the worker the caller waits too, instead of dropping the oldest
  // (sweeps_replaced), and a frame whose mesh is still in the worker stays pending instead of the
  // caller waiting for it (a later message projects it; finish() waits). So the reader goes on
  // decoding and projecting while the worker meshes, nothing is lost, and as a frame's mesh is
  // chosen by time the map is the one of async_mesh = false (tested). false: the live process.
  bool offline_pipeline = false;
  double max_mesh_age_s = 0.5;     // a frame uses a mesh at most this far from its time
  double mesh_wait_s = 0.3;        // a frame waits at most this long (pose time) for its nearest mesh
  double mesh_history_s = 2.0;     // finished meshes kept for late frames
  double pose_keep_s = 10.0;       // pose history
  double max_pose_gap_s = 0.25;    // two poses further apart do not interpolate
  // Pose smoothing (PoseBuffer): a frame's and a LIDAR packet's pose is the local linear fit of
  // the poses within +- this (0: interpolation of the two around it only). Frames wait this much
  // longer for their poses.
  double pose_smooth_s = 0.0;
  // Poses whose time goes back by more than this, 3 in a row (a log restarted): the pose history
  // and the frames waiting for a pose are dropped (counted), and the builder starts over in the
  // new time. A single older pose is out of order.
  double time_jump_s = 1.0;
  size_t max_pending_frames = 30;  // frames waiting for a later pose (3 s at 10 Hz)
  double close_delay_s = 0.3;      // a closed road is handed over when poses are this far past it
  Eigen::Isometry3d lidar_to_vehicle = Eigen::Isometry3d::Identity();

  // From config/bev_builder.yaml's keys (all optional; see that file). An unknown key inside its
  // sections (grid, projection, corridor, lidar, poses) or a bad value throws config::ConfigError
  // naming the key; the top level's other keys are the process's (lanemap-bev-builder checks them).
  static BevBuilderOptions fromYaml(const YAML::Node& node);
  // The same from a config reader; the caller's finish() refuses unknown keys everywhere.
  static BevBuilderOptions fromYaml(const config::YamlReader& r);
};

struct BevBuilderStats {
  int64_t frames_received = 0, frames_projected = 0, frames_mesh = 0, frames_flat = 0;
  int64_t frames_decode_error = 0, frames_wrong_size = 0, frames_unknown_class = 0;
  int64_t frames_out_of_order = 0, frames_late = 0, frames_no_pose = 0, frames_queue_full = 0;
  int64_t poses_received = 0, poses_invalid = 0, poses_out_of_order = 0;
  int64_t poses_duplicate = 0, pose_time_jumps = 0, frames_time_jump = 0;  // frames dropped by a jump
  int64_t sweeps_received = 0, sweeps_meshed = 0, sweeps_no_pose = 0, sweeps_replaced = 0, sweeps_empty = 0;
  int64_t frames_mesh_wait_expired = 0;  // projected without waiting any longer for a nearer mesh
  int64_t roads_opened = 0, roads_closed = 0, roads_discarded = 0, events_unknown_road = 0;
  double project_ms_max = 0.0, project_ms_sum = 0.0;  // per projected frame
  double mesh_ms_max = 0.0, mesh_ms_sum = 0.0;        // per mesh (extraction + Delaunay + index)
};

// Label image of label_image_t: raw (one byte per pixel, row-major) or PNG.
enum class LabelEncoding : int8_t { kRaw = 0, kPng = 1 };
// Decodes into a CV_8UC1 of width x height; false when the data does not decode to that.
bool decodeLabelImage(LabelEncoding encoding, const uint8_t* data, size_t size, int width, int height, cv::Mat* out);

struct SweepData {
  int64_t utime = 0;
  std::vector<int64_t> packet_utime;
  std::vector<std::vector<uint8_t>> packets;
};

class BevBuilder {
 public:
  // The skeleton must outlive the builder.
  BevBuilder(const skeleton::Skeleton& skeleton, const camera::CameraModel& camera, BevBuilderOptions options);
  ~BevBuilder();
  BevBuilder(const BevBuilder&) = delete;
  BevBuilder& operator=(const BevBuilder&) = delete;

  void addPose(const TimedPose& pose);
  // A decoded label image (size and classes are checked here).
  void addFrame(int64_t utime, const cv::Mat& labels);
  // A label image as it comes in a message; counts decode errors.
  void addEncodedFrame(int64_t utime, LabelEncoding encoding, const std::vector<uint8_t>& data, int width, int height);
  void addSweep(SweepData sweep);
  void roadEntered(int64_t road_id, int64_t utime);
  void roadClosed(int64_t road_id, int64_t utime);
  void roadsAbandoned(int64_t utime);
  // A road recovered from its checkpoint after a restart (bev_store.h): active again with that
  // grid, frames go on into it. False for an unknown road, one already active, or a grid of
  // another resolution.
  bool restoreRoad(int64_t road_id, BevGrid grid, int64_t utime);
  // End of input: waits for the mesh worker, hands over roads that are closing.
  void finish();

  std::vector<RoadBev> takeClosed();
  // Calls f with the road being driven (the active road opened last) under the builder's lock, so
  // f must not call the builder; false (f not called) when no road is active. The viewer's
  // picture of the open road is drawn from it (lanemap-bev-builder, BEV_OPEN).
  bool withOpenRoad(const std::function<void(const RoadBev&)>& f) const;
  BevBuilderStats stats() const;
  // Frames waiting for a later pose (neither projected nor counted as skipped yet).
  size_t pendingFrames() const;
  // Called with a frame's utime when its projection into the grid has finished, in the thread that
  // fed the builder (inside addPose/addFrame/finish) with the builder's lock held: the callback must
  // not call the builder. lanemap-bev-builder measures its frame-to-BEV latency with it.
  void setProjectedCallback(std::function<void(int64_t frame_utime)> callback);
  // Called (same thread and lock rule) with each projected frame's utime and the utime (sweep
  // middle) of the mesh it was projected on, 0 for the flat plane. Diagnostics and tests.
  void setMeshChoiceCallback(std::function<void(int64_t frame_utime, int64_t mesh_utime)> callback);
  const Projector& projector() const { return projector_; }
  const RoadBevAccumulator& accumulator() const { return accumulator_; }
  std::shared_ptr<const ground::SweepGround> latestMesh() const;

 private:
  struct PendingFrame {
    int64_t utime;
    cv::Mat labels;
    bool mesh_decided = false;  // mesh_utime is its mesh's sweep (0: the flat plane)
    int64_t mesh_utime = 0;
  };
  void drainFrames();
  void decideMeshes();                         // each waiting frame's mesh, in order, as far as known
  void projectDecided(bool wait_for_worker);   // the decided frames at the front of the queue
  // Whether a frame at utime must still wait before its mesh can be decided (see the header
  // comment): no (every sweep that may be nearest is decoded); the sweep covering it is still to
  // come (waits at most mesh_wait_s); a sweep near it waits for its poses (the next pose decodes
  // it). A decoded sweep counts whether its mesh is finished or still in the worker: the decision
  // does not depend on the worker's progress, only on the messages so far.
  // nearest: nearestDecodedSweep(utime), which is then the frame's mesh.
  enum class MeshWait { kNo, kSweepToCome, kSweepNeedsPoses };
  MeshWait meshWait(int64_t utime, int64_t nearest) const;
  // The decoded sweep (finished, in the worker or queued) nearest to utime within max_mesh_age_s,
  // the earlier on a tie; 0: none.
  int64_t nearestDecodedSweep(int64_t utime) const;
  bool inWorker(int64_t sweep_utime) const;  // queued for or being meshed by the worker
  void project(int64_t utime, const cv::Mat& labels, const Eigen::Isometry3d& pose, int64_t mesh_utime);
  void tryPendingSweep();
  void buildMesh(const ground::SweepPoints& points);
  void workerLoop();
  void finishCloses(bool all);

  const skeleton::Skeleton& skeleton_;
  BevBuilderOptions options_;
  Projector projector_;
  RoadBevAccumulator accumulator_;
  PoseBuffer poses_;
  geo::TimeOrder pose_order_;
  std::deque<PendingFrame> pending_;
  int64_t last_frame_utime_ = 0;
  std::optional<SweepData> pending_sweep_;
  std::map<int64_t, int64_t> closing_;  // road id -> close utime
  std::vector<RoadBev> closed_;
  std::function<void(int64_t)> on_projected_;
  std::function<void(int64_t, int64_t)> on_mesh_choice_;
  int64_t newest_sweep_end_ = 0;  // last packet time of the newest sweep received
  bool finishing_ = false;

  // Taken by every public method and by the worker (to pick work and publish a mesh); the caller
  // releases it while it decodes a sweep or projects a frame (Unlocked in bev_builder.cc: the
  // public methods are called from one thread, so what the worker does not touch stays put).
  mutable std::mutex mutex_;
  std::condition_variable_any cv_;  // also waited on with mutex_ itself (drainFrames)
  BevBuilderStats stats_;
  std::deque<std::shared_ptr<const ground::SweepGround>> meshes_;  // finished, oldest first
  std::deque<ground::SweepPoints> work_;                          // waiting for the worker
  int64_t newest_decided_utime_ = std::numeric_limits<int64_t>::min();  // frame whose mesh was decided last
  int64_t working_utime_ = 0;                                     // middle of the sweep in the worker
  bool working_ = false, stop_ = false;
  std::thread worker_;
};

}  // namespace lanemap::bev
