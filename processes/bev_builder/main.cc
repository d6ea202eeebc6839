// lanemap-bev-builder: SEMANTIC_FRONT (or SEMANTIC_FRONT_TRUTH), LIDAR_PACKETS, POSE and ROAD_EVENT
// in; one BEV grid per closed atomic road out, written atomically to <store>/bev/road_<id>.bev and
// announced on BEV_ROAD (METHOD.md section 3). A thin wrapper over core/bev/bev_builder.h; the mesh
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
#include "core/bev/bev_builder.h"
#include "core/bev/bev_store.h"
#include "core/camera/camera_model.h"
#include "core/config/vehicle_config.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"

#include <chrono>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <string>

namespace {

using namespace lanemap;

class BevBuilderApp {
 public:
  BevBuilderApp(Process& process, std::unique_ptr<skeleton::Skeleton> skeleton, const camera::CameraModel& camera,
                const bev::BevBuilderOptions& options, std::string store)
      : process_(process), skeleton_(std::move(skeleton)), builder_(*skeleton_, camera, options), store_(std::move(store)) {
    builder_.setProjectedCallback([this](int64_t utime) { onProjected(utime); });
  }

  void subscribe(const std::string& semantic_channel, const BevBuilderSettings& s) {
    const int q_pose = s.pose_queue, q_sem = s.semantic_queue, q_lidar = s.lidar_queue, q_event = s.road_event_queue;
    auto& lcm = process_.lcm();
    lcm.subscribe(channels::kPose, &BevBuilderApp::onPose, this)->setQueueCapacity(q_pose);
    lcm.subscribe(semantic_channel, &BevBuilderApp::onLabels, this)->setQueueCapacity(q_sem);
    lcm.subscribe(channels::kLidarPackets, &BevBuilderApp::onLidar, this)->setQueueCapacity(q_lidar);
    lcm.subscribe(channels::kRoadEvent, &BevBuilderApp::onRoadEvent, this)->setQueueCapacity(q_event);
  }

  // After spin(): roads that were closing are handed over too.
  void finish() {
    builder_.finish();
    writeClosed();
    updateCounters();
  }

 private:
  void onPose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* m) {
    builder_.addPose(toTimedPose(toEnuPose(*m, skeleton_->frame())));
    afterMessage();
  }

  void onLabels(const lcm::ReceiveBuffer* rbuf, const std::string&, const label_image_t* m) {
    // Projection may happen now or on a later pose: onProjected() finds the receive time here.
    // Frames are projected in utime order, so older entries left here were skipped frames.
    received_.emplace(m->utime, rbuf->recv_utime);
    while (received_.size() > 200) received_.erase(received_.begin());
    builder_.addEncodedFrame(m->utime, static_cast<bev::LabelEncoding>(m->encoding), m->data, m->width, m->height);
    afterMessage();
  }

  // Called by the builder (LCM thread, inside addPose/addEncodedFrame/finish) when a frame's
  // projection has finished.
  void onProjected(int64_t frame_utime) {
    const auto it = received_.find(frame_utime);
    if (it == received_.end()) return;
    process_.latency().add(static_cast<double>(nowUtime() - it->second) * 1e-3);
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
    updateCounters();  // a struct copy and ~30 map writes: cheap at ~250 messages/s
  }

  void writeClosed() {
    for (auto& road : builder_.takeClosed()) {
      try {
        const auto stored = bev::storeRoad(store_, road);
        publish(road, stored);
        process_.counters().add("roads_written");
      } catch (const std::exception& e) {
        std::cerr << "bev_builder: road " << road.road_id << ": " << e.what() << "\n";
        process_.counters().add("roads_write_failed");
      }
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
};

}  // namespace

int main(int argc, char** argv) {
  Process process("bev_builder");
  std::string osm_flag, store_flag, channel_flag, vehicle_flag;
  bool no_lidar = false;
  process.cli().add_option("--osm", osm_flag, "OSM file of the skeleton (default: the osm of the config's map: file)");
  process.cli().add_option("--store", store_flag, "map store folder (default: config store)");
  process.cli().add_option("--semantic-channel", channel_flag, "semantic channel (default: config semantic_channel)");
  process.cli().add_option("--vehicle", vehicle_flag, "vehicle YAML: camera, lidar mount (default: config vehicle)");
  process.cli().add_flag("--no-lidar", no_lidar, "flat ground only");
  if (int rc = process.init(argc, argv); rc >= 0) return rc;
  try {
    const auto settings = BevBuilderSettings::fromYaml(process.settings());
    process.settings().finish();
    const std::string osm = osm_flag.empty() ? settings.map.osm : osm_flag;
    const std::string store = store_flag.empty() ? settings.store : store_flag;
    const std::string channel = channel_flag.empty() ? settings.semantic_channel : channel_flag;
    const std::string vehicle = vehicle_flag.empty() ? resolveConfigFile(settings.vehicle) : vehicle_flag;
    if (osm.empty()) throw std::runtime_error("no OSM file: give --osm or `osm:` in the map config");
    if (store.empty()) throw std::runtime_error("no map store: give --store or `store:` in the config");
    auto sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(osm::readOsm(osm), settings.map.skeleton));
    const auto vehicle_config = config::VehicleConfig::fromYamlFile(vehicle);
    const camera::CameraModel& camera = vehicle_config.camera;
    bev::BevBuilderOptions options = settings.options;
    if (no_lidar) options.use_lidar = false;
    if (options.use_lidar) options.lidar_to_vehicle = vehicle_config.lidarToVehicle();
    std::cerr << "bev_builder: " << sk->roads().size() << " atomic roads from " << osm << ", " << channel
              << (options.use_lidar ? " + LIDAR mesh" : " (flat ground)") << ", store " << store << "\n";
    BevBuilderApp app(process, std::move(sk), camera, options, store);
    app.subscribe(channel, settings);
    const int rc = process.spin();
    app.finish();
    return rc;
  } catch (const std::exception& e) {
    std::cerr << "bev_builder: " << e.what() << "\n";
    return 2;
  }
}
