// Bundles a stream of Velodyne data packets into sweeps (one rotation each) for the LIDAR driver:
// every packet is decoded (so bad ones are rejected by reason), its points go through the
// SweepSplitter, and when the azimuth wraps the packets so far become one sweep. The packet in
// which the wrap happens ENDS its sweep (a sweep's packets therefore cover the whole rotation, plus
// the few degrees of that last packet past 0). Every packet belongs to exactly one sweep. The
// decoded points of a sweep are exactly the splitter's rotation (wrap to wrap), each with the host
// time of its firing: the sensor's own clock (packet timestamp + firing offset) gives the exact
// spacing, shifted onto the host clock by the receive time of the sweep's first packet.
//
// The first sweep after start starts mid-rotation: it is counted as partial and not returned; so
// is the unfinished one at the end of a stream, and a "sweep" that never wraps within
// kMaxPacketsPerSweep packets (a stuck azimuth): it is dropped and bundling starts over.
#pragma once

#include "core/lidar/velodyne.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lanemap::drivers {

struct PacketSweep {
  std::vector<lidar::Packet> packets;     // in arrival order
  std::vector<int64_t> packet_utime;      // host receive time of each packet
  std::vector<lidar::LidarPoint> points;  // decoded (when points are kept): wrap to wrap
  std::vector<int64_t> point_utime;       // host time of each point's firing
  lidar::Model model = lidar::Model::kVlp16;
};

// "VLP-16", "VLP-32C", "HDL-32E": the model names of lidar_packets_t.
const char* modelDisplayName(lidar::Model model);
// Counter name of a rejection: "rejected_short", "rejected_bad_flag", ...
std::string rejectionCounterName(lidar::DecodeStatus status);

class SweepBundler {
 public:
  // 10x a VLP-16 rotation at its slowest (300 rpm, dual return: ~302 packets).
  static constexpr std::size_t kMaxPacketsPerSweep = 3000;

  SweepBundler(std::optional<lidar::Model> forced_model, bool keep_points);

  // Adds one datagram received at `receive_utime`. A completed sweep is appended to `done`.
  // Returns the decode status (anything but kOk: the packet was rejected and is not bundled).
  lidar::DecodeStatus add(const uint8_t* data, std::size_t size, int64_t receive_utime,
                          std::vector<PacketSweep>& done);

  const lidar::DecodeStats& stats() const { return decoder_.stats(); }
  std::size_t partialSweeps() const { return partial_; }  // dropped: started mid-rotation
  std::size_t pendingPackets() const { return current_.packets.size(); }
  // End of stream: the unfinished sweep is counted as partial and dropped.
  void finish();
  std::size_t overlongSweeps() const { return overlong_; }  // dropped: no wrap in time

 private:
  lidar::PacketDecoder decoder_;
  lidar::SweepSplitter splitter_;
  bool keep_points_;
  bool seen_wrap_ = false;
  PacketSweep current_;
  std::vector<lidar::LidarPoint> scratch_;
  std::vector<lidar::LidarPoint> pending_points_;  // points not yet in a completed rotation
  std::vector<int64_t> pending_point_sensor_us_;   // sensor time of each pending point
  std::vector<int64_t> pending_point_anchor_us_;   // host minus sensor clock, per point's packet
  std::optional<uint32_t> last_usec_past_hour_;
  int64_t hour_offset_us_ = 0;  // unwraps the sensor's top-of-hour reset
  std::size_t partial_ = 0, overlong_ = 0;
};

}  // namespace lanemap::drivers
