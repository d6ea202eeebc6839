// The channel registry: every LCM channel of lanemap, declared once, with its type and rate.
// Processes take channel names from here; `lanemap-channels` prints it for scripts and people.
#pragma once

#include <string_view>

namespace lanemap::channels {

struct ChannelSpec {
  const char* name;
  const char* type;       // LCM type, package-qualified
  double rate_hz;         // nominal rate; 0 = on event
  const char* publisher;  // who publishes it
  const char* summary;
};

inline constexpr const char* kCameraFront = "CAMERA_FRONT";
inline constexpr const char* kLidarPackets = "LIDAR_PACKETS";
inline constexpr const char* kLidarPoints = "LIDAR_POINTS";
inline constexpr const char* kPose = "POSE";
inline constexpr const char* kSemanticFront = "SEMANTIC_FRONT";
inline constexpr const char* kSemanticFrontTruth = "SEMANTIC_FRONT_TRUTH";
inline constexpr const char* kRoadEvent = "ROAD_EVENT";
inline constexpr const char* kBevRoad = "BEV_ROAD";
inline constexpr const char* kBevOpen = "BEV_OPEN";
inline constexpr const char* kLaneMap = "LANE_MAP";
inline constexpr const char* kStatus = "STATUS";

inline constexpr ChannelSpec kRegistry[] = {
    {kCameraFront, "lanemap.image_t", 10.0, "camera_v4l2, sim", "front camera frame (JPEG or raw)"},
    {kLidarPackets, "lanemap.lidar_packets_t", 10.0, "lidar_vlp16, sim", "one sweep of raw Velodyne packets"},
    {kLidarPoints, "lanemap.lidar_points_t", 10.0, "lidar_vlp16", "one sweep decoded to points"},
    {kPose, "lanemap.pose_t", 100.0, "pose driver, sim", "vehicle pose, WGS84 + orientation"},
    {kSemanticFront, "lanemap.label_image_t", 10.0, "segmenter", "class image of a camera frame"},
    {kSemanticFrontTruth, "lanemap.label_image_t", 10.0, "sim", "ground-truth class image of a camera frame"},
    {kRoadEvent, "lanemap.road_event_t", 0.0, "road_tracker", "entered an atomic road / reached an intersection"},
    {kBevRoad, "lanemap.bev_road_t", 0.0, "bev_builder", "a closed road's BEV grid in the map store"},
    {kBevOpen, "lanemap.bev_preview_t", 1.0, "bev_builder", "a picture of the open road's BEV grid, for the viewer"},
    {kLaneMap, "lanemap.lane_map_t", 0.0, "lane_mapper", "lanes of a road or intersection as built"},
    {kStatus, "lanemap.status_t", 1.0, "every process", "counters and health, 1 Hz per process"},
};

// The spec of a channel, or nullptr for a name that is not in the registry.
inline const ChannelSpec* find(std::string_view name) {
  for (const auto& c : kRegistry) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

}  // namespace lanemap::channels
