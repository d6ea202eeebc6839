// Where the LIDAR driver's datagrams come from: live UDP sockets (data port + position port), or a
// recorded capture (classic pcap, or a raw file of 1206-byte payloads) replayed at a rate scale.
// Both hand every datagram to the same sink, so a replay exercises the live path.
#pragma once

#include "core/lidar/udp_receiver.h"

#include <cstdint>
#include <functional>
#include <string>

namespace lanemap::drivers {

enum class PortKind { kData, kPosition, kOther };

using DatagramSink = std::function<void(const lidar::Datagram&, PortKind)>;
using StopFlag = std::function<bool()>;

// Reads both sockets until stop() (checked every 100 ms). `position` may be null.
void receiveLoop(lidar::UdpReceiver& data, lidar::UdpReceiver* position, const DatagramSink& sink,
                 const StopFlag& stop);

struct ReplayOptions {
  double rate_scale = 1.0;  // 1 = real time, 2 = twice as fast, 0 = as fast as possible
  // Stamp packets with the capture time instead of "now" (raw payload files have none: there it
  // is the sensor's own time past the hour, useful only for relative timing).
  bool keep_capture_time = false;
  uint16_t data_port = 2368;  // pcap: UDP destination ports that are data / position packets
  uint16_t position_port = 8308;
};

struct ReplayStats {
  std::size_t datagrams = 0;  // handed to the sink
  std::size_t skipped = 0;    // pcap records that are not UDP to one of the two ports
};

// Replays a pcap or raw payload file (throws lidar::PcapError on an unreadable file).
ReplayStats replayCapture(const std::string& path, const ReplayOptions& options,
                          const DatagramSink& sink, const StopFlag& stop);

}  // namespace lanemap::drivers
