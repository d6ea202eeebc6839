// The VLP-16 driver's application object: its settings (config/lidar_vlp16.yaml, overridable on
// the command line), and LidarApp, which takes every datagram (live UDP or a replayed capture, see
// packet_source.h), bundles sweeps, publishes LIDAR_PACKETS (and LIDAR_POINTS when enabled) and
// keeps the STATUS counters.
#pragma once

#include "drivers/lidar_vlp16/packet_source.h"
#include "drivers/lidar_vlp16/sweep_bundler.h"
#include "processes/framework/channels.h"
#include "processes/framework/process.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace lanemap::drivers {

struct LidarSettings {
  std::string model = "vlp16";      // vlp16 | vlp32c | hdl32e | auto (product-id byte)
  std::string address = "0.0.0.0";  // where to bind
  int data_port = 2368;
  int position_port = 8308;  // 0: do not listen for position packets
  int receive_buffer_bytes = 8 << 20;
  bool publish_points = false;
  std::string packets_channel = channels::kLidarPackets;
  std::string points_channel = channels::kLidarPoints;
  // Replay (--pcap): file, rate scale (0 = as fast as possible), keep the capture timestamps.
  std::string pcap;
  double rate_scale = 1.0;
  bool keep_capture_time = false;

  // Reads the keys present in `config` (unknown keys are an error naming them). Throws
  // std::runtime_error naming the key on a wrong type or value.
  // The driver's config (strict: the caller's finish() refuses unknown keys).
  void load(const config::YamlReader& config);
  void validate() const;
  std::optional<lidar::Model> forcedModel() const;  // nullopt for "auto"
};

class LidarApp {
 public:
  // Binds the sockets (throws lidar::UdpError with a clear message) or checks the capture file,
  // then starts the receive/replay thread.
  LidarApp(Process& process, LidarSettings settings);
  ~LidarApp();

 private:
  void onDatagram(const lidar::Datagram& d, PortKind kind);
  void publish(const PacketSweep& sweep);
  void runReplay();

  Process& process_;
  LidarSettings settings_;
  SweepBundler bundler_;
  std::unique_ptr<lidar::UdpReceiver> data_rx_, position_rx_;
  std::atomic<bool> stop_{false};
  std::thread worker_;
};

}  // namespace lanemap::drivers
