// Live UDP reception and capture replay for the LIDAR driver (see packet_source.h).
#include "drivers/lidar_vlp16/packet_source.h"

#include "core/geo/wall_clock.h"
#include "core/lidar/pcap.h"
#include "core/lidar/velodyne.h"

#include <algorithm>
#include <chrono>
#include <optional>
#include <thread>
#include <vector>

namespace lanemap::drivers {
namespace {


// Sleeps until `capture_us` (relative to the first record) is due at the rate scale.
class Pacer {
 public:
  explicit Pacer(double rate_scale) : rate_scale_(rate_scale) {}
  void wait(int64_t capture_us, const StopFlag& stop) {
    if (rate_scale_ <= 0.0) return;
    if (!has_first_) {
      first_ = capture_us;
      has_first_ = true;
    }
    const auto due = start_ + std::chrono::microseconds(static_cast<int64_t>(
                                  static_cast<double>(capture_us - first_) / rate_scale_));
    while (!stop() && std::chrono::steady_clock::now() < due) {
      std::this_thread::sleep_until(
          std::min(due, std::chrono::steady_clock::now() + std::chrono::milliseconds(100)));
    }
  }

 private:
  double rate_scale_;
  bool has_first_ = false;
  int64_t first_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// Raw payloads carry no capture time: the packet's own timestamp (us past the hour) unwrapped.
class RawPayloadClock {
 public:
  int64_t next(const std::vector<uint8_t>& payload) {
    if (payload.size() == lidar::kDataPacketSize) {
      const uint8_t* p = payload.data() + lidar::kTimestampOffset;
      const int64_t t = p[0] | (p[1] << 8) | (p[2] << 16) | (static_cast<int64_t>(p[3]) << 24);
      if (last_ && t < *last_ - 1800LL * 1000000) hour_offset_ += 3600LL * 1000000;  // hour wrap
      last_ = t;
      now_ = t + hour_offset_;
    }
    return now_;
  }

 private:
  std::optional<int64_t> last_;
  int64_t hour_offset_ = 0, now_ = 0;
};

}  // namespace

void receiveLoop(lidar::UdpReceiver& data, lidar::UdpReceiver* position, const DatagramSink& sink,
                 const StopFlag& stop) {
  std::vector<lidar::UdpReceiver*> receivers{&data};
  if (position) receivers.push_back(position);
  lidar::Datagram d;
  while (!stop()) {
    for (std::size_t i : lidar::waitReadable(receivers, 100)) {
      while (receivers[i]->receive(d)) sink(d, i == 0 ? PortKind::kData : PortKind::kPosition);
    }
  }
}

ReplayStats replayCapture(const std::string& path, const ReplayOptions& options,
                          const DatagramSink& sink, const StopFlag& stop) {
  ReplayStats stats;
  Pacer pacer(options.rate_scale);
  lidar::Datagram d;
  auto deliver = [&](int64_t capture_us, PortKind kind) {
    pacer.wait(capture_us, stop);
    d.size = d.data.size();
    d.truncated = false;
    d.receive_utime = options.keep_capture_time ? capture_us : geo::wallUtime();
    sink(d, kind);
    ++stats.datagrams;
  };
  if (lidar::looksLikePcap(path)) {
    lidar::PcapReader reader(path);
    lidar::UdpPayload u;
    while (!stop() && reader.next(u)) {
      const PortKind kind = u.dst_port == options.data_port       ? PortKind::kData
                            : u.dst_port == options.position_port ? PortKind::kPosition
                                                                  : PortKind::kOther;
      if (kind == PortKind::kOther) {
        ++stats.skipped;
        continue;
      }
      d.data = std::move(u.data);
      d.src_ip = u.src_ip;
      d.src_port = u.src_port;
      deliver(static_cast<int64_t>(u.timestamp_ns / 1000), kind);
    }
    stats.skipped += reader.stats().not_ipv4_udp + reader.stats().fragments;
  } else {
    RawPayloadClock clock;
    for (auto& payload : lidar::readRawPayloadFile(path, lidar::kDataPacketSize)) {
      if (stop()) break;
      const int64_t t = clock.next(payload);
      d.data = std::move(payload);
      d.src_ip = 0;
      d.src_port = 0;
      deliver(t, PortKind::kData);
    }
  }
  return stats;
}

}  // namespace lanemap::drivers
