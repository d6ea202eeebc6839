// Test helper: replays a simulated drive's LCM log through the core road tracker and the core
// BevBuilder, in log order, the way lanemap-road-tracker + lanemap-bev-builder see it on the bus.
#pragma once

#include "core/bev/bev_builder.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/road_tracker.h"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/pose_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/pose_conversion.h"
#include "processes/framework/process.h"

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace lanemap::testing {

inline const std::string kBevDriveArgs = "--camera-hz 5";
constexpr double kBevDriveSeconds = 18.0;
constexpr uint64_t kBevDriveSeed = 7;

inline bev::BevBuilderOptions replayOptions(bool lidar) {
  const std::string src = LANEMAP_SOURCE_DIR;
  bev::BevBuilderOptions o = bev::BevBuilderOptions::fromYaml(loadYamlFile(src + "/config/bev_builder.yaml"));
  o.use_lidar = lidar;
  o.async_mesh = false;  // deterministic
  o.lidar_to_vehicle = camera::mountFromYaml(loadYamlFile(src + "/config/vehicle.yaml")["lidar"]["mount"], "lidar.mount");
  return o;
}

struct Replay {
  std::unique_ptr<skeleton::Skeleton> sk;
  std::unique_ptr<bev::BevBuilder> builder;
  std::vector<bev::RoadBev> closed;
  std::vector<tracking::RoadEvent> events;
};

inline void feedPose(const pose_t& m, Replay& r, tracking::RoadTracker& tracker) {
  const EnuPose p = toEnuPose(m, r.sk->frame());
  r.builder->addPose(toTimedPose(p));
  for (const auto& e : tracker.update(toPoseInput(p))) {
    r.events.push_back(e);
    if (e.type == tracking::RoadEventType::kEnteredRoad) r.builder->roadEntered(e.road_id, e.utime);
    if (e.type == tracking::RoadEventType::kReachedIntersection) r.builder->roadClosed(e.road_id, e.utime);
  }
}

// Replays `log` (SEMANTIC_FRONT_TRUTH, LIDAR_PACKETS, POSE) into a fresh builder.
inline std::unique_ptr<Replay> replayLog(const std::string& log_path, const bev::BevBuilderOptions& options) {
  auto r = std::make_unique<Replay>();
  const std::string src = LANEMAP_SOURCE_DIR;
  r->sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(osm::readOsm(src + "/data/osm/west-oakland.osm")));
  const auto camera = camera::CameraModel::fromYaml(loadYamlFile(src + "/config/vehicle.yaml")["camera"]);
  r->builder = std::make_unique<bev::BevBuilder>(*r->sk, camera, options);
  tracking::RoadTracker tracker(*r->sk);
  lcm::LogFile log(log_path, "r");
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const std::string ch = ev->channel;
    if (ch == channels::kPose) {
      pose_t m;
      if (m.decode(ev->data, 0, ev->datalen) > 0) feedPose(m, *r, tracker);
    } else if (ch == channels::kSemanticFrontTruth) {
      label_image_t m;
      if (m.decode(ev->data, 0, ev->datalen) > 0) {
        r->builder->addEncodedFrame(m.utime, static_cast<bev::LabelEncoding>(m.encoding), m.data, m.width, m.height);
      }
    } else if (ch == channels::kLidarPackets) {
      lidar_packets_t m;
      if (m.decode(ev->data, 0, ev->datalen) > 0) {
        r->builder->addSweep(bev::SweepData{m.utime, m.packet_utime, m.data});
      }
    }
    for (auto& c : r->builder->takeClosed()) r->closed.push_back(std::move(c));
  }
  r->builder->finish();
  for (auto& c : r->builder->takeClosed()) r->closed.push_back(std::move(c));
  return r;
}

}  // namespace lanemap::testing
