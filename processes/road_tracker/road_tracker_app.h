// lanemap-road-tracker: map-matches POSE messages to the OSM skeleton M0 and publishes ROAD_EVENT
// (entered road / reached intersection / left map / wrong way / pose lost). A thin wrapper over
// core/tracking/road_tracker.h; counters in STATUS. STATUS latency (last 500 poses, ~5 s): from a
// POSE's receive time (lcm::ReceiveBuffer::recv_utime) to the end of its handling, its events
// published: LCM queue wait + map matching.
//
//   lanemap-road-tracker --config config/road_tracker.yaml [--osm data/osm/west-oakland.osm]
#pragma once

#include "core/skeleton/skeleton.h"
#include "core/tracking/road_tracker.h"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"
#include "processes/framework/process_configs.h"
#include <cmath>
#include <iostream>
#include <memory>
#include <string>

namespace lanemap::road_tracker_app {


using lanemap::tracking::RoadTrackerConfig;

class RoadTrackerApp {
 public:
  RoadTrackerApp(lanemap::Process& process, std::unique_ptr<lanemap::skeleton::Skeleton> skeleton,
                 const RoadTrackerConfig& config, const std::string& pose_channel, int queue)
      : process_(process), skeleton_(std::move(skeleton)), tracker_(*skeleton_, config) {
    auto* sub = process_.lcm().subscribe(pose_channel, &RoadTrackerApp::onPose, this);
    sub->setQueueCapacity(queue);
  }

 private:
  void onPose(const lcm::ReceiveBuffer* rbuf, const std::string&, const lanemap::pose_t* msg) {
    auto& counters = process_.counters();
    counters.add("poses_received");
    const lanemap::tracking::PoseInput pose = lanemap::toPoseInput(lanemap::toEnuPose(*msg, skeleton_->frame()));
    for (const auto& e : tracker_.update(pose)) publish(e);
    const auto& stats = tracker_.stats();
    counters.set("poses_invalid", stats.invalid);
    counters.set("poses_out_of_order", stats.out_of_order);
    counters.set("poses_duplicate", stats.duplicates);
    counters.set("pose_time_jumps", stats.time_jumps);
    counters.set("filter_resets", stats.filter_resets);
    counters.set("rematches", stats.rematches);
    counters.set("current_road", tracker_.currentRoad());
    process_.latency().add(static_cast<double>(lanemap::geo::wallUtime() - rbuf->recv_utime) * 1e-3);
  }

  void publish(const lanemap::tracking::RoadEvent& e) {
    lanemap::road_event_t msg;
    msg.utime = e.utime;
    msg.type = static_cast<int8_t>(e.type);
    msg.road_id = e.road_id;
    msg.from_node = e.from_node;
    msg.to_node = e.to_node;
    msg.previous_road_id = e.previous_road_id;
    msg.intersection_id = e.intersection_id;
    msg.distance_m = e.distance_m;
    msg.detail = e.detail;
    if (e.crossing_utime != e.utime) {
      msg.detail += (msg.detail.empty() ? "" : "; ") + std::string("crossing_utime=") +
                    std::to_string(e.crossing_utime);
    }
    process_.lcm().publish(lanemap::channels::kRoadEvent, &msg);
    process_.counters().add(std::string("events_") + lanemap::tracking::toString(e.type));
    // Found on a road rather than entering it from a junction: at the start, after a lost pose, or
    // after this process restarted mid-drive (what it recovered: where the car is).
    if (e.type == lanemap::tracking::RoadEventType::kEnteredRoad && e.previous_road_id < 0) process_.counters().add("roads_found_mid_road");
  }

  lanemap::Process& process_;
  std::unique_ptr<lanemap::skeleton::Skeleton> skeleton_;
  lanemap::tracking::RoadTracker tracker_;
};

}  // namespace lanemap::road_tracker_app
