// Writes the seed corpus of the lcm_decode harness: one file per message type, as the harness
// reads it (a selector byte, then the encoded message without its 8-byte hash), with realistic
// contents: a 32x16 JPEG and a YUYV frame, raw and PNG labels, a lidar_packets_t of two real
// VLP-16 packets (data/lidar), a pose, a lane map of two lanes ... Run by fuzz/make_seeds.py:
//   build-fuzz/fuzz_lcm_seeds fuzz/corpus/lcm_decode
#include "lanemap/bev_road_t.hpp"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/lidar_points_t.hpp"
#include "lanemap/polyline_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "lanemap/status_t.hpp"

#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

using namespace lanemap;

namespace {
std::string g_dir;

template <typename T>
void write(uint8_t selector, const std::string& name, const T& msg) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  if (msg.encode(buf.data(), 0, static_cast<int>(buf.size())) != static_cast<int>(buf.size())) {
    std::cerr << name << ": encode failed\n";
    std::exit(1);
  }
  std::ofstream out(g_dir + "/" + name, std::ios::binary);
  out.put(static_cast<char>(selector));
  out.write(reinterpret_cast<const char*>(buf.data()) + 8, static_cast<std::streamsize>(buf.size() - 8));
}

polyline_t line(double y, int8_t type) {
  polyline_t p;
  for (int i = 0; i < 4; ++i) {
    p.east.push_back(i * 5.0);
    p.north.push_back(y);
    p.up.push_back(0.1);
  }
  p.num_points = 4;
  p.type = type;
  return p;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_lcm_seeds OUT_DIR\n";
    return 2;
  }
  g_dir = argv[1];
  cv::Mat bgr(16, 32, CV_8UC3);
  for (int r = 0; r < bgr.rows; ++r)
    for (int c = 0; c < bgr.cols; ++c) bgr.at<cv::Vec3b>(r, c) = cv::Vec3b(r * 8, c * 4, (r + c) * 3);
  {
    image_t m{};
    m.utime = 1700000000000000;
    m.seq = 7;
    m.width = 32;
    m.height = 16;
    m.row_stride = 0;
    m.pixelformat = image_t::PIXEL_FORMAT_JPEG;
    cv::imencode(".jpg", bgr, m.data);
    m.size = static_cast<int32_t>(m.data.size());
    write(0, "image_jpeg", m);
    m.pixelformat = image_t::PIXEL_FORMAT_YUYV;
    m.row_stride = 64;
    m.data.assign(64 * 16, 0x80);
    m.size = static_cast<int32_t>(m.data.size());
    write(0, "image_yuyv", m);
    m.pixelformat = image_t::PIXEL_FORMAT_GRAY;
    m.row_stride = 0;
    m.data.assign(32 * 16, 0x40);
    m.size = static_cast<int32_t>(m.data.size());
    write(0, "image_gray", m);
  }
  {
    label_image_t m{};
    m.utime = 1700000000000000;
    m.seq = 7;
    m.width = 32;
    m.height = 16;
    cv::Mat labels(16, 32, CV_8UC1);
    for (int r = 0; r < 16; ++r)
      for (int c = 0; c < 32; ++c) labels.at<uint8_t>(r, c) = static_cast<uint8_t>((c / 3) % 11);
    m.encoding = label_image_t::ENCODING_RAW;
    m.data.assign(labels.data, labels.data + labels.total());
    m.size = static_cast<int32_t>(m.data.size());
    m.source = "sim-truth";
    write(1, "labels_raw", m);
    m.encoding = label_image_t::ENCODING_PNG;
    cv::imencode(".png", labels, m.data);
    m.size = static_cast<int32_t>(m.data.size());
    write(1, "labels_png", m);
  }
  {
    std::ifstream in(std::string(LANEMAP_SOURCE_DIR) + "/data/lidar/vlp16_einride_recording.bin", std::ios::binary);
    std::vector<uint8_t> rec((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (rec.size() < 2 * 1206) {
      std::cerr << "cannot read data/lidar/vlp16_einride_recording.bin\n";
      return 1;
    }
    lidar_packets_t m{};
    m.utime = 1700000000000000;
    m.model = "VLP-16";
    m.num_packets = 2;
    m.packet_size = 1206;
    m.packet_utime = {m.utime, m.utime + 1327};
    m.data = {std::vector<uint8_t>(rec.begin(), rec.begin() + 1206),
              std::vector<uint8_t>(rec.begin() + 1206, rec.begin() + 2412)};
    write(2, "lidar_packets_2", m);
  }
  {
    pose_t m{};
    m.utime = 1700000000000000;
    m.latitude = 43.7384;
    m.longitude = 7.4246;
    m.altitude = 52.0;
    m.orientation[0] = 0.7071;
    m.orientation[3] = 0.7071;
    m.velocity_enu[0] = 10.0;
    m.position_covariance[0] = m.position_covariance[4] = m.position_covariance[8] = 0.01;
    m.status = pose_t::STATUS_RTK_FIXED;
    write(3, "pose", m);
  }
  {
    lidar_points_t m{};
    m.utime = 1700000000000000;
    m.num_points = 3;
    m.x = {1, 2, 3};
    m.y = {0, 1, -1};
    m.z = {-1.5f, -1.4f, 0.2f};
    m.intensity = {10, 20, 30};
    m.ring = {0, 1, 15};
    m.time_offset = {0, 0.001f, 0.002f};
    write(4, "lidar_points", m);
  }
  {
    lane_map_t m{};
    m.utime = 1700000000000000;
    m.kind = lane_map_t::KIND_ROAD;
    m.id = 42;
    m.origin_latitude = 43.7384;
    m.origin_longitude = 7.4246;
    for (int i = 0; i < 2; ++i) {
      lane_t l{};
      l.lane_id = 100 + i;
      l.index_from_left = i;
      l.centre = line(-1.75 - 3.5 * i, polyline_t::TYPE_VIRTUAL);
      l.left_boundary = line(-3.5 * i, i ? polyline_t::TYPE_DASHED : polyline_t::TYPE_SOLID);
      l.right_boundary = line(-3.5 * (i + 1), i ? polyline_t::TYPE_CURB : polyline_t::TYPE_DASHED);
      l.successors = {200 + i};
      l.num_successors = 1;
      m.lanes.push_back(l);
    }
    m.num_lanes = 2;
    m.map_path = "/tmp/store/map.osm";
    write(5, "lane_map_2lanes", m);
    write(6, "lane", m.lanes[0]);
    write(7, "polyline", m.lanes[0].centre);
  }
  {
    road_event_t m{};
    m.utime = 1700000000000000;
    m.type = road_event_t::TYPE_REACHED_INTERSECTION;
    m.road_id = 42;
    m.from_node = 1001;
    m.to_node = 1002;
    m.previous_road_id = -1;
    m.intersection_id = 1002;
    m.distance_m = 0.4;
    m.detail = "reached";
    write(8, "road_event", m);
  }
  {
    bev_road_t m{};
    m.utime = 1700000000000000;
    m.road_id = 42;
    m.path = "/tmp/store/bev/road_42.bev";
    m.resolution_m = 0.05;
    m.width = 800;
    m.height = 300;
    m.num_frames = 120;
    write(9, "bev_road", m);
  }
  {
    status_t m{};
    m.utime = 1700000000000000;
    m.process = "bev_builder";
    m.host = "mapping";
    m.pid = 1234;
    m.state = "running";
    m.counter_names = {"frames_received", "frames_projected"};
    m.counter_values = {120, 118};
    m.num_counters = 2;
    m.latency_p50_ms = 12.5;
    write(10, "status", m);
  }
  return 0;
}
