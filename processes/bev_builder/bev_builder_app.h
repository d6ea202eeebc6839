// lanemap-bev-builder: SEMANTIC_FRONT (or SEMANTIC_FRONT_TRUTH), LIDAR_PACKETS, POSE and ROAD_EVENT
// in; one BEV grid per closed atomic road out, written atomically to <store>/bev/road_<id>.bev and
// announced on BEV_ROAD (METHOD.md section 3); about once a second a picture of the open road's grid
// on BEV_OPEN for the viewer (config `preview`). Crash recovery: the open road's grid is
// checkpointed every checkpoint.period_s to <store>/bev/open/ (core/bev/bev_store.h), written by
// core/bev/checkpoint_writer.h's thread so that frames never wait for the disk; a builder
// that starts and finds checkpoints carries those roads on (STATUS roads_recovered,
// frames_recovered, and recovered_gap_ms: the time between the checkpoint's newest frame and the
// first frame after the restart, what the crash cost). End of the drive (the process stops: the log
// player ended, or a shutdown): the road being driven never closed, so it is stored partial
// (bev_store.h storePartialRoad: bev/partial/road_<id>.bev, with the station the last pose reached)
// and announced on BEV_ROAD with that path; its checkpoint is removed (a crash, SIGKILL, skips this
// and leaves the checkpoint for the next start). STATUS roads_partial. A store other drives filled:
// the roads this drive merges onto stored evidence measure its offset (bev::LiveDriveOffset, config
// `drive_offset`), and once min_roads agree the later roads are stored moved by it (STATUS
// drive_offset_cm, roads_corrected). A thin wrapper over core/bev/bev_builder.h; the mesh
// of each LIDAR sweep is built in core's worker thread so LCM handling never waits for it, a frame
// projection runs inline (tools/bench/bev_bench.cc: ~10-20 ms). Counters in STATUS.
//
// STATUS latency (p50/p99 of the last 500 frames) is this process's share of frame-to-BEV: from the
// label message's receive time (lcm::ReceiveBuffer::recv_utime, wall clock, taken by LCM's receive
// thread) to the end of the frame's projection into its road's grid. It includes the wait in LCM's
// queue behind other messages, the PNG decode, the wait for a pose newer than the frame (poses come
// at 100 Hz: up to ~10 ms) and the projection. Frames that are never projected (late, no pose,
// queue full: their counters) have no latency. Camera-to-BEV is the segmenter's latency (camera
// frame received -> labels published) plus this one; lanemap-graph-report prints both and their sum.
//
//   lanemap-bev-builder --config config/bev_builder.yaml [--osm FILE] [--store DIR] [--vehicle FILE]
//                       [--semantic-channel SEMANTIC_FRONT_TRUTH] [--no-lidar]
#pragma once

#include "core/bev/bev_builder.h"
#include "core/bev/bev_render.h"
#include "core/bev/bev_store.h"
#include "core/bev/checkpoint_writer.h"
#include "core/bev/drive_offsets.h"
#include "core/camera/camera_model.h"
#include "core/config/vehicle_config.h"
#include "core/io/store_lock.h"
#include "core/mapping/partial_road.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "lanemap/bev_preview_t.hpp"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace lanemap::bev_builder_app {


using namespace lanemap;

class BevBuilderApp {
 public:
  BevBuilderApp(Process& process, std::unique_ptr<skeleton::Skeleton> skeleton, const camera::CameraModel& camera,
                const bev::BevBuilderOptions& options, std::string store)
      : process_(process), skeleton_(std::move(skeleton)), builder_(*skeleton_, camera, options), store_(std::move(store)),
        checkpoints_(store_) {
    builder_.setProjectedCallback([this](int64_t utime) { onProjected(utime); });
  }

  // BEV_OPEN: a picture at most every period_s seconds (wall clock; 0: never) while a road is open
  // and has new frames, at most max_px on its longest side.
  void setPreview(double period_s, int max_px) {
    preview_period_s_ = period_s;
    preview_max_px_ = max_px;
  }
  void setCheckpointPeriod(double period_s) { checkpoint_period_s_ = period_s; }
  void setDriveOffset(const bev::DriveOffsetOptions& options, double resolution_m) {
    drive_offset_ = bev::LiveDriveOffset(options, resolution_m);
  }
  // The road frame a partial road's station is measured in (the map block's road_frame: the lane
  // mapper explores up to the station in the same frame).
  void setRoadFrame(const lanes::ExplorerOptions& frame) { road_frame_ = frame; }

  // Roads whose checkpoints are in the store (a crash or kill of an earlier run) are active again.
  void recover() {
    std::vector<std::string> errors;
    std::vector<int64_t> already_stored;
    for (auto& c : bev::loadCheckpoints(store_, &errors, &already_stored)) {
      const int frames = c.grid.frames();
      if (builder_.restoreRoad(c.road_id, std::move(c.grid), c.last_frame_utime)) {
        process_.counters().add("roads_recovered");
        process_.counters().add("frames_recovered", frames);
        checkpointed_[c.road_id] = frames;
        recovered_frame_utime_ = std::max(recovered_frame_utime_, c.last_frame_utime);
        std::cerr << "bev_builder: recovered road " << c.road_id << " (" << frames << " frames) from " << c.path << "\n";
      } else {
        process_.counters().add("checkpoints_unusable");
        std::cerr << "bev_builder: checkpoint of road " << c.road_id << " does not fit this skeleton or grid: " << c.path << "\n";
      }
    }
    for (const int64_t id : already_stored) {  // killed between storing the road and removing its checkpoint
      process_.counters().add("checkpoints_already_stored");
      std::cerr << "bev_builder: checkpoint of road " << id << " was stored before the restart: removed, not carried on\n";
    }
    for (const auto& e : errors) {
      process_.counters().add("checkpoints_unreadable");
      std::cerr << "bev_builder: unreadable checkpoint " << e << "\n";
    }
  }

  // Subscribes for the app `*app` will hold, before it exists: main calls this before the slow part
  // of its start (reading the OSM, building the skeleton, loading the checkpoints), so what comes
  // on the bus meanwhile waits in LCM's queues (queue_capacity: 6 s of frames, 10 s of poses) and
  // is handled once the app is there, in spin(). A builder restarted after a crash so loses only
  // what came before these subscriptions (the restart delay and the exec), not its whole start.
  static void subscribe(lcm::LCM& lcm, const std::string& semantic_channel, const BevBuilderSettings& s,
                        const std::unique_ptr<BevBuilderApp>* app) {
    lcm.subscribeFunction(channels::kPose, &forward<pose_t, &BevBuilderApp::onPose>, app)->setQueueCapacity(s.pose_queue);
    lcm.subscribeFunction(semantic_channel, &forward<label_image_t, &BevBuilderApp::onLabels>, app)->setQueueCapacity(s.semantic_queue);
    lcm.subscribeFunction(channels::kLidarPackets, &forward<lidar_packets_t, &BevBuilderApp::onLidar>, app)->setQueueCapacity(s.lidar_queue);
    lcm.subscribeFunction(channels::kRoadEvent, &forward<road_event_t, &BevBuilderApp::onRoadEvent>, app)->setQueueCapacity(s.road_event_queue);
  }

  // After spin(): roads that were closing are handed over too, and the road being driven is
  // stored partial.
  void finish() {
    builder_.finish();
    writeClosed();
    writePartial();
    updateCounters();
  }

 private:
  template <class M, void (BevBuilderApp::*Handle)(const lcm::ReceiveBuffer*, const std::string&, const M*)>
  static void forward(const lcm::ReceiveBuffer* rbuf, const std::string& channel, const M* m, const std::unique_ptr<BevBuilderApp>* app) {
    if (*app) ((**app).*Handle)(rbuf, channel, m);  // spin() runs after the app is made: always there
  }

  void onPose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* m) {
    const EnuPose p = toEnuPose(*m, skeleton_->frame());
    if (p.position.allFinite()) last_position_ = p.position.head<2>();
    builder_.addPose(toTimedPose(p));
    afterMessage();
  }

  void onLabels(const lcm::ReceiveBuffer* rbuf, const std::string&, const label_image_t* m) {
    // Projection may happen now or on a later pose: onProjected() finds the receive time here.
    // Frames are projected in utime order, so older entries left here were skipped frames.
    received_.emplace(m->utime, rbuf->recv_utime);
    while (received_.size() > 200) received_.erase(received_.begin());
    // Frames lost on the bus (a gap in the camera's seq; a seq that goes back is a restarted
    // source): STATUS frames_missed and the share of the frames sent, frames_missed_pct.
    const bool gap = last_label_seq_ >= 0 && m->seq > last_label_seq_ + 1 && m->seq - last_label_seq_ < 100000;
    process_.counters().add("frames_missed", gap ? m->seq - last_label_seq_ - 1 : 0);
    if (m->seq > last_label_seq_ || m->seq < last_label_seq_ - 100) last_label_seq_ = m->seq;
    ++labels_received_;
    const int64_t missed = process_.counters().get("frames_missed");
    process_.counters().set("frames_missed_pct", 100 * missed / (missed + labels_received_));
    builder_.addEncodedFrame(m->utime, static_cast<bev::LabelEncoding>(m->encoding), m->data, m->width, m->height);
    afterMessage();
  }

  // Called by the builder (LCM thread, inside addPose/addEncodedFrame/finish) when a frame's
  // projection has finished.
  void onProjected(int64_t frame_utime) {
    last_projected_utime_ = std::max(last_projected_utime_, frame_utime);
    if (recovered_frame_utime_ > 0) {
      process_.counters().set("recovered_gap_ms", (frame_utime - recovered_frame_utime_) / 1000);
      recovered_frame_utime_ = 0;
    }
    const auto it = received_.find(frame_utime);
    if (it == received_.end()) return;
    process_.latency().add(static_cast<double>(geo::wallUtime() - it->second) * 1e-3);
    received_.erase(received_.begin(), std::next(it));
  }

  void onLidar(const lcm::ReceiveBuffer*, const std::string&, const lidar_packets_t* m) {
    bev::SweepData s;
    s.utime = m->utime;
    s.packet_utime = m->packet_utime;
    s.packets = m->data;
    builder_.addSweep(std::move(s));
    afterMessage();
  }

  void onRoadEvent(const lcm::ReceiveBuffer*, const std::string&, const road_event_t* m) {
    switch (m->type) {
      case road_event_t::TYPE_ENTERED_ROAD: builder_.roadEntered(m->road_id, m->utime); break;
      case road_event_t::TYPE_REACHED_INTERSECTION: builder_.roadClosed(m->road_id, m->utime); break;
      case road_event_t::TYPE_LEFT_MAP:
      case road_event_t::TYPE_POSE_LOST: builder_.roadsAbandoned(m->utime); break;
      default: break;
    }
    afterMessage();
  }

  void afterMessage() {
    writeClosed();
    checkpoint();
    publishPreview();
    updateCounters();  // a struct copy and ~30 map writes: cheap at ~250 messages/s
  }

  // The open road's grid to <store>/bev/open/ every checkpoint_period_s (wall clock) when it has
  // new frames; checkpoints of roads no longer active are removed.
  void checkpoint() {
    if (checkpoint_period_s_ <= 0.0) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_checkpoint_ < std::chrono::duration<double>(checkpoint_period_s_)) return;
    last_checkpoint_ = now;
    std::optional<bev::RoadBev> open;
    builder_.withOpenRoad([&](const bev::RoadBev& road) {
      const auto it = checkpointed_.find(road.road_id);
      if (road.grid.frames() > 0 && (it == checkpointed_.end() || it->second != road.grid.frames())) open = road;  // a copy
    });
    const auto active = builder_.accumulator().activeRoads();
    for (auto it = checkpointed_.begin(); it != checkpointed_.end();) {
      if (std::find(active.begin(), active.end(), it->first) == active.end()) {
        checkpoints_.cancel(it->first);
        bev::removeCheckpoint(store_, it->first);
        it = checkpointed_.erase(it);
      } else {
        ++it;
      }
    }
    if (!open) return;
    checkpointed_[open->road_id] = open->grid.frames();
    checkpoints_.write(std::move(*open), last_projected_utime_);  // written in the writer's thread
  }

  // The checkpoint writer's figures and errors, into STATUS and stderr.
  void checkpointCounters() {
    for (const auto& e : checkpoints_.takeErrors()) std::cerr << "bev_builder: checkpoint of " << e << "\n";
    const auto s = checkpoints_.stats();
    auto& c = process_.counters();
    c.set("checkpoints_written", s.written);
    c.set("checkpoints_failed", s.failed);
    c.set("checkpoints_replaced", s.replaced);
    c.set("checkpoint_us_total", s.us_total);
    c.set("checkpoint_us_max", s.us_max);
    c.set("checkpoint_kb", s.kb);
  }

  void publishPreview() {
    if (preview_period_s_ <= 0.0) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_preview_ < std::chrono::duration<double>(preview_period_s_)) return;
    last_preview_ = now;
    bev_preview_t msg;
    bool drawn = false;
    try {
      builder_.withOpenRoad([&](const bev::RoadBev& road) {
        if (road.grid.frames() == 0 || (road.road_id == preview_road_ && road.grid.frames() == preview_frames_)) return;
        const bev::BevPicture pic = bev::bevPicture(road.grid, preview_max_px_);
        preview_road_ = road.road_id;
        preview_frames_ = road.grid.frames();
        msg.road_id = road.road_id;
        msg.num_frames = road.grid.frames();
        msg.west = pic.enu.min().x();
        msg.south = pic.enu.min().y();
        msg.east = pic.enu.max().x();
        msg.north = pic.enu.max().y();
        msg.png = pic.png;
        msg.size = static_cast<int32_t>(msg.png.size());
        drawn = true;
      });
    } catch (const std::exception& e) {
      process_.counters().add("previews_failed");
      std::cerr << "bev_builder: preview: " << e.what() << "\n";
      return;
    }
    if (!drawn) return;
    msg.utime = geo::wallUtime();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - now).count();
    process_.lcm().publish(channels::kBevOpen, &msg);
    process_.counters().add("previews_published");
    process_.counters().set("preview_us_max", std::max<int64_t>(process_.counters().get("preview_us_max"), static_cast<int64_t>(ms * 1e3)));
  }

  void writeClosed() {
    for (auto& road : builder_.takeClosed()) {
      try {
        checkpoints_.cancel(road.road_id);  // no older checkpoint may land after the road is stored
        const Eigen::Vector2i correction = drive_offset_.correction();
        const auto stored = bev::storeRoad(store_, road, true, correction);
        publish(road, stored);
        bev::removeCheckpoint(store_, road.road_id);  // after the road is stored: a crash between keeps both
        checkpointed_.erase(road.road_id);
        process_.counters().add("roads_written");
        if (correction != Eigen::Vector2i::Zero()) process_.counters().add("roads_corrected");
        drive_offset_.addStored(road.road_id, stored.merged, correction, stored.alignment, road.grid.frames());
        if (stored.merged) {  // driven before: merged onto the stored evidence, aligned when it could be
          process_.counters().add(stored.alignment.ok ? "roads_merged_aligned" : "roads_merged_unaligned");
          process_.counters().set("drive_offset_cm", std::lround(drive_offset_.correction().cast<double>().norm() *
                                                                 road.grid.resolution() * 100.0));
          const auto cm = static_cast<int64_t>(std::lround(stored.alignment.shift_m.norm() * 100));
          if (stored.alignment.ok) process_.counters().set("align_shift_cm_max", std::max(process_.counters().get("align_shift_cm_max"), cm));
          std::cerr << "bev_builder: road " << road.road_id << " merged onto its stored BEV, "
                    << (stored.alignment.ok ? "shifted " + std::to_string(cm) + " cm" : "unaligned: " + stored.alignment.why) << "\n";
        }
      } catch (const std::exception& e) {
        std::cerr << "bev_builder: road " << road.road_id << ": " << e.what() << "\n";
        process_.counters().add("roads_write_failed");
      }
    }
  }

  // The open road at the end of the drive, driven as far as the last pose.
  void writePartial() {
    std::optional<bev::RoadBev> open;
    builder_.withOpenRoad([&](const bev::RoadBev& road) {
      if (road.grid.frames() > 0) open = road;  // a copy
    });
    if (!open || !last_position_) return;
    const auto* road = skeleton_->road(open->road_id);
    if (!road) return;
    try {
      checkpoints_.cancel(open->road_id);
      const lanes::ExplorerOptions& frame = road_frame_;  // the station in the explorer's frame of the road
      const auto stored = bev::storePartialRoad(store_, *open, mapping::roadStation(*road, *last_position_, frame),
                                                mapping::roadFrameLength(*road, frame), true, drive_offset_.correction());
      open->closed_utime = last_projected_utime_;
      publish(*open, stored);
      bev::removeCheckpoint(store_, open->road_id);
      checkpointed_.erase(open->road_id);
      process_.counters().add(stored.partial ? "roads_partial" : "roads_written");
      std::cerr << "bev_builder: road " << open->road_id << (stored.partial ? " stored partial, to " : " (complete already) driven to ")
                << static_cast<int>(stored.station_m) << " m of " << static_cast<int>(stored.road_length_m) << " m\n";
    } catch (const std::exception& e) {
      std::cerr << "bev_builder: partial road " << open->road_id << ": " << e.what() << "\n";
      process_.counters().add("roads_write_failed");
    }
  }

  void publish(const bev::RoadBev& road, const bev::StoredRoad& stored) {
    bev_road_t msg;
    msg.utime = road.closed_utime;
    msg.road_id = road.road_id;
    msg.from_node = road.from_node;
    msg.to_node = road.to_node;
    msg.path = stored.path;
    msg.origin_east = stored.origin.x();
    msg.origin_north = stored.origin.y();
    msg.resolution_m = stored.resolution;
    msg.width = stored.width;
    msg.height = stored.height;
    msg.num_frames = stored.frames;
    process_.lcm().publish(channels::kBevRoad, &msg);
  }

  void updateCounters() {
    checkpointCounters();
    const auto s = builder_.stats();
    auto& c = process_.counters();
    c.set("frames_received", s.frames_received);
    c.set("frames_projected", s.frames_projected);
    c.set("frames_mesh", s.frames_mesh);
    c.set("frames_flat", s.frames_flat);
    c.set("frames_decode_error", s.frames_decode_error);
    c.set("frames_wrong_size", s.frames_wrong_size);
    c.set("frames_unknown_class", s.frames_unknown_class);
    c.set("frames_out_of_order", s.frames_out_of_order);
    c.set("frames_late", s.frames_late);
    c.set("frames_no_pose", s.frames_no_pose);
    c.set("frames_queue_full", s.frames_queue_full);
    c.set("frames_pending", static_cast<int64_t>(builder_.pendingFrames()));
    c.set("poses_received", s.poses_received);
    c.set("poses_invalid", s.poses_invalid);
    c.set("poses_out_of_order", s.poses_out_of_order);
    c.set("poses_duplicate", s.poses_duplicate);
    c.set("pose_time_jumps", s.pose_time_jumps);
    c.set("frames_time_jump", s.frames_time_jump);
    c.set("sweeps_received", s.sweeps_received);
    c.set("sweeps_meshed", s.sweeps_meshed);
    c.set("sweeps_no_pose", s.sweeps_no_pose);
    c.set("sweeps_replaced", s.sweeps_replaced);
    c.set("roads_opened", s.roads_opened);
    c.set("roads_closed", s.roads_closed);
    c.set("roads_discarded", s.roads_discarded);
    c.set("events_unknown_road", s.events_unknown_road);
    c.set("project_us_max", static_cast<int64_t>(s.project_ms_max * 1e3));
    c.set("project_us_mean", s.frames_projected ? static_cast<int64_t>(s.project_ms_sum * 1e3 / s.frames_projected) : 0);
    c.set("mesh_us_max", static_cast<int64_t>(s.mesh_ms_max * 1e3));
    c.set("mesh_us_mean", s.sweeps_meshed ? static_cast<int64_t>(s.mesh_ms_sum * 1e3 / s.sweeps_meshed) : 0);
    c.set("active_roads", static_cast<int64_t>(builder_.accumulator().activeRoads().size()));
  }

  Process& process_;
  std::unique_ptr<skeleton::Skeleton> skeleton_;
  bev::BevBuilder builder_;
  std::string store_;
  std::map<int64_t, int64_t> received_;  // label utime -> recv_utime, frames not yet projected
  double preview_period_s_ = 1.0;
  int preview_max_px_ = 512;
  std::chrono::steady_clock::time_point last_preview_{};
  int64_t preview_road_ = -1;
  int preview_frames_ = 0;
  double checkpoint_period_s_ = 2.0;
  lanes::ExplorerOptions road_frame_;  // only its frame_spacing_m / frame_smoothing_m are used
  std::chrono::steady_clock::time_point last_checkpoint_{};
  std::map<int64_t, int> checkpointed_;   // road -> frames in its checkpoint (on disk or queued)
  int64_t last_projected_utime_ = 0;
  int64_t last_label_seq_ = -1, labels_received_ = 0;
  int64_t recovered_frame_utime_ = 0;     // newest frame of the recovered checkpoints, until a frame comes
  std::optional<Eigen::Vector2d> last_position_;  // the newest pose (ENU), where a partial road stops
  bev::LiveDriveOffset drive_offset_;     // this drive's correction onto the store's drives (this run's)
  bev::CheckpointWriter checkpoints_;     // after store_ (it takes it); its thread ends first
};

}  // namespace lanemap::bev_builder_app
