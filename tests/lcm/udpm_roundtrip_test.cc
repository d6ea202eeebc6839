// Every lanemap message type, published on its registry channel over udpm:// inside a private
// network namespace, is received byte-identical (and an image-sized message is not dropped).
#include "lanemap/bev_preview_t.hpp"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/lidar_points_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "lanemap/status_t.hpp"
#include "processes/framework/channels.h"
#include "tests/common/netns.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

using namespace lanemap;

template <typename T>
std::vector<uint8_t> encode(const T& msg) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// A message of every type, filled with non-trivial values, keyed by channel.
std::map<std::string, std::pair<std::string, std::vector<uint8_t>>> sampleMessages() {
  std::map<std::string, std::pair<std::string, std::vector<uint8_t>>> out;
  image_t img;
  img.utime = 1767225600123456;
  img.seq = 42;
  img.width = 640;
  img.height = 360;
  img.row_stride = 640 * 3;
  img.pixelformat = image_t::PIXEL_FORMAT_BGR;
  img.data.resize(640 * 360 * 3);  // 691 kB: needs a large receive buffer and fragmentation
  for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = static_cast<uint8_t>(i * 7);
  img.size = static_cast<int32_t>(img.data.size());
  out[channels::kCameraFront] = {"lanemap.image_t", encode(img)};

  label_image_t lab;
  lab.utime = img.utime;
  lab.seq = 42;
  lab.width = 4;
  lab.height = 2;
  lab.encoding = label_image_t::ENCODING_RAW;
  lab.data = {0, 1, 2, 3, 6, 7, 8, 10};
  lab.size = 8;
  lab.source = "sim-truth";
  out[channels::kSemanticFront] = {"lanemap.label_image_t", encode(lab)};
  lab.seq = 43;
  out[channels::kSemanticFrontTruth] = {"lanemap.label_image_t", encode(lab)};

  pose_t pose{};
  pose.utime = 1767225600000000;
  pose.latitude = 37.8075123456;
  pose.longitude = -122.3001234567;
  pose.altitude = 12.5;
  pose.orientation[0] = 1.0;
  pose.velocity_enu[0] = 3.0;
  pose.position_covariance[0] = 0.01;
  pose.status = pose_t::STATUS_SIMULATED;
  out[channels::kPose] = {"lanemap.pose_t", encode(pose)};

  lidar_packets_t pk;
  pk.utime = pose.utime;
  pk.model = "VLP-16";
  pk.num_packets = 75;
  pk.packet_size = 1206;
  for (int i = 0; i < pk.num_packets; ++i) {
    pk.packet_utime.push_back(pose.utime + i * 1327);
    pk.data.emplace_back(1206, static_cast<uint8_t>(i));
  }
  out[channels::kLidarPackets] = {"lanemap.lidar_packets_t", encode(pk)};

  lidar_points_t pts;
  pts.utime = pose.utime;
  pts.num_points = 3;
  pts.x = {1.f, 2.f, 3.f};
  pts.y = {0.f, -1.f, 1.f};
  pts.z = {-1.5f, -1.4f, 0.2f};
  pts.intensity = {10.f, 200.f, 30.f};
  pts.ring = {0, 1, 15};
  pts.time_offset = {0.f, 0.001f, 0.002f};
  out[channels::kLidarPoints] = {"lanemap.lidar_points_t", encode(pts)};

  road_event_t ev;
  ev.utime = pose.utime;
  ev.type = road_event_t::TYPE_REACHED_INTERSECTION;
  ev.road_id = 12;
  ev.from_node = 65300000;
  ev.to_node = 65300001;
  ev.previous_road_id = 11;
  ev.intersection_id = 65300001;
  ev.distance_m = 0.8;
  ev.detail = "test";
  out[channels::kRoadEvent] = {"lanemap.road_event_t", encode(ev)};

  bev_road_t bev;
  bev.utime = pose.utime;
  bev.road_id = 12;
  bev.from_node = 1;
  bev.to_node = 2;
  bev.path = "/tmp/store/road_12.bev";
  bev.origin_east = -10.0;
  bev.origin_north = 5.0;
  bev.resolution_m = 0.1;
  bev.width = 200;
  bev.height = 1000;
  bev.num_frames = 87;
  out[channels::kBevRoad] = {"lanemap.bev_road_t", encode(bev)};

  bev_preview_t preview;
  preview.utime = pose.utime;
  preview.road_id = 12;
  preview.num_frames = 40;
  preview.west = -10.0;
  preview.south = 5.0;
  preview.east = 10.0;
  preview.north = 105.0;
  preview.png = {0x89, 'P', 'N', 'G', 1, 2, 3};
  preview.size = static_cast<int32_t>(preview.png.size());
  out[channels::kBevOpen] = {"lanemap.bev_preview_t", encode(preview)};

  lane_map_t lm;
  lm.utime = pose.utime;
  lm.kind = lane_map_t::KIND_ROAD;
  lm.id = 12;
  lm.origin_latitude = 37.8;
  lm.origin_longitude = -122.3;
  lm.origin_altitude = 0.0;
  lane_t lane;
  lane.lane_id = 1;
  lane.index_from_left = 0;
  for (auto* pl : {&lane.centre, &lane.left_boundary, &lane.right_boundary}) {
    pl->num_points = 2;
    pl->east = {0.0, 10.0};
    pl->north = {0.0, 0.5};
    pl->up = {0.0, 0.1};
    pl->type = polyline_t::TYPE_DASHED;
  }
  lane.num_successors = 1;
  lane.successors = {7};
  lane.confidence = 0.8;
  lm.lanes = {lane};
  lm.num_lanes = 1;
  lm.map_path = "/tmp/map.osm";
  lm.partial_station_m = lm.partial_road_length_m = -1.0;
  out[channels::kLaneMap] = {"lanemap.lane_map_t", encode(lm)};

  status_t st;
  st.utime = pose.utime;
  st.process = "test";
  st.host = "h";
  st.pid = 1;
  st.state = "running";
  st.num_counters = 2;
  st.counter_names = {"received", "dropped"};
  st.counter_values = {10, 0};
  st.latency_p50_ms = 1.0;
  st.latency_p99_ms = 2.0;
  st.cpu_fraction = 0.1;
  out[channels::kStatus] = {"lanemap.status_t", encode(st)};
  return out;
}

struct Collector {
  std::map<std::string, std::vector<uint8_t>> got;
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    got[channel].assign(p, p + rbuf->data_size);
  }
};

TEST(Udpm, EveryRegistryChannelHasASampleOfItsType) {
  const auto samples = sampleMessages();
  for (const auto& c : channels::kRegistry) {
    auto it = samples.find(c.name);
    ASSERT_NE(it, samples.end()) << c.name;
    EXPECT_EQ(it->second.first, c.type) << c.name;
  }
  EXPECT_EQ(samples.size(), std::size(channels::kRegistry));
}

TEST(Udpm, EveryMessageTypeRoundTripsInPrivateNetns) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  lcm::LCM lcm(lanemap::testing::testUdpmUrl());
  ASSERT_TRUE(lcm.good());
  Collector collector;
  auto* sub = lcm.subscribe(".*", &Collector::onMessage, &collector);
  sub->setQueueCapacity(100);
  const auto samples = sampleMessages();
  for (const auto& [channel, msg] : samples) {
    ASSERT_EQ(lcm.publish(channel, msg.second.data(), static_cast<unsigned>(msg.second.size())), 0);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (collector.got.size() < samples.size() && std::chrono::steady_clock::now() < deadline) {
    lcm.handleTimeout(100);
  }
  ASSERT_EQ(collector.got.size(), samples.size());
  for (const auto& [channel, msg] : samples) {
    EXPECT_EQ(collector.got[channel], msg.second) << channel;
  }
}

}  // namespace
