// Every LCM message type of lcmtypes/ and the process code behind its decode. Input: one selector
// byte (which type, modulo the number of types) and the message body after the 8-byte type hash
// (the harness puts the right hash in front, so the fuzzer explores the fields, not the hash).
// Sizes that disagree with the data, negative or huge num_points / size / string lengths must make
// decode() return < 0 (lcm's typed subscribe then skips the message) -- never throw, allocate
// gigabytes or read past the buffer. A message that decodes re-encodes to bytes that decode again.
// Behind the decode, what the processes do with it:
//   image_t       -> seg::decodeFrame (the segmenter; only seg::FrameError may escape)
//   label_image_t -> seg::decodeLabels (FrameError only)
//   lidar_packets_t -> lidar::PacketDecoder on every packet (the BEV builder's sweep ground)
//   pose_t        -> toEnuPose, toPoseInput, PoseBuffer add/lookup (road tracker, BEV builder)
#include "core/bev/pose_buffer.h"
#include "core/io/image_header.h"
#include "core/lidar/velodyne.h"
#include "core/seg/segmenter.h"
#include "fuzz/fuzz_util.h"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/image_t.hpp"
#include "lanemap/label_image_t.hpp"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/lane_t.hpp"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/lidar_points_t.hpp"
#include "lanemap/polyline_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "lanemap/status_t.hpp"
#include "processes/framework/pose_conversion.h"

#include <cstring>
#include <vector>

namespace {

using namespace lanemap;

// Decodes hash + body as T; on success re-encodes and decodes that again, and returns true.
template <typename T>
bool decodeChecked(const uint8_t* body, size_t n, T& msg) {
  std::vector<uint8_t> buf(8 + n);
  int64_t hash = T::getHash();
  __int64_t_encode_array(buf.data(), 0, 8, &hash, 1);
  if (n) std::memcpy(buf.data() + 8, body, n);
  const int r = msg.decode(buf.data(), 0, static_cast<int>(buf.size()));
  if (r < 0) return false;
  FUZZ_CHECK(static_cast<size_t>(r) <= buf.size());
  const int es = msg.getEncodedSize();
  FUZZ_CHECK(es >= 8);
  std::vector<uint8_t> enc(static_cast<size_t>(es));
  const int w = msg.encode(enc.data(), 0, es);
  FUZZ_CHECK(w >= 8 && w <= es);  // < es when a string holds a NUL (lcm encodes up to it)
  T again;
  FUZZ_CHECK(again.decode(enc.data(), 0, w) == w);
  std::vector<uint8_t> enc2(static_cast<size_t>(again.getEncodedSize()));
  FUZZ_CHECK(again.encode(enc2.data(), 0, static_cast<int>(enc2.size())) == w);
  FUZZ_CHECK(std::memcmp(enc.data(), enc2.data(), static_cast<size_t>(w)) == 0);
  return true;
}

void onImage(const image_t& m) {
  FUZZ_CHECK(m.data.size() == static_cast<size_t>(m.size));
  try {
    const cv::Mat bgr = seg::decodeFrame(m.pixelformat, m.width, m.height, m.row_stride, m.data.data(), m.data.size());
    FUZZ_CHECK(bgr.cols == m.width && bgr.rows == m.height && bgr.type() == CV_8UC3);
  } catch (const seg::FrameError&) {
  }
}

void onLabels(const label_image_t& m) {
  FUZZ_CHECK(m.data.size() == static_cast<size_t>(m.size));
  try {
    const cv::Mat labels = seg::decodeLabels(m.encoding, m.width, m.height, m.data);
    FUZZ_CHECK(labels.cols == m.width && labels.rows == m.height && labels.type() == CV_8UC1);
  } catch (const seg::FrameError&) {
  }
}

void onLidarPackets(const lidar_packets_t& m) {
  FUZZ_CHECK(m.packet_utime.size() == static_cast<size_t>(m.num_packets));
  FUZZ_CHECK(m.data.size() == static_cast<size_t>(m.num_packets));
  lidar::PacketDecoder decoder;
  std::vector<lidar::LidarPoint> points;
  for (const auto& p : m.data) {
    FUZZ_CHECK(p.size() == static_cast<size_t>(m.packet_size));
    decoder.decode(p.data(), p.size(), points);
  }
  FUZZ_CHECK(decoder.stats().packets == m.data.size());
  FUZZ_CHECK(points.size() <= m.data.size() * lidar::kBlocksPerPacket * lidar::kChannelsPerBlock);
}

void onPose(const pose_t& m) {
  static const geo::LocalFrame frame(geo::LatLonAlt{43.7384, 7.4246, 0.0});
  const EnuPose p = toEnuPose(m, frame);
  const tracking::PoseInput in = toPoseInput(p);
  FUZZ_CHECK(in.valid == p.valid);
  bev::PoseBuffer buffer(10.0, 0.25);
  bev::TimedPose t = toTimedPose(p);
  const bool ok = buffer.add(t);
  FUZZ_CHECK(!ok || (t.position.allFinite() && buffer.size() == 1));
  Eigen::Isometry3d out;
  (void)buffer.lookup(m.utime, &out);
  (void)buffer.lookup(m.utime / 2, &out);
  t.utime = m.utime / 2 + 1000000;  // a second pose: the interpolation between the two
  t.position = Eigen::Vector3d(1, 2, 3);
  buffer.add(t);
  (void)buffer.lookup(m.utime / 4 + 500000, &out);
}

template <typename T>
void decodeOnly(const uint8_t* body, size_t n) {
  T m;
  decodeChecked(body, n, m);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t* body = data + 1;
  const size_t n = size - 1;
  switch (data[0] % 11) {
    case 0: { image_t m; if (decodeChecked(body, n, m)) onImage(m); break; }
    case 1: { label_image_t m; if (decodeChecked(body, n, m)) onLabels(m); break; }
    case 2: { lidar_packets_t m; if (decodeChecked(body, n, m)) onLidarPackets(m); break; }
    case 3: { pose_t m; if (decodeChecked(body, n, m)) onPose(m); break; }
    case 4: decodeOnly<lidar_points_t>(body, n); break;
    case 5: decodeOnly<lane_map_t>(body, n); break;
    case 6: decodeOnly<lane_t>(body, n); break;
    case 7: decodeOnly<polyline_t>(body, n); break;
    case 8: decodeOnly<road_event_t>(body, n); break;
    case 9: decodeOnly<bev_road_t>(body, n); break;
    case 10: decodeOnly<status_t>(body, n); break;
  }
  return 0;
}
