// LidarApp: datagrams -> sweeps -> LIDAR_PACKETS / LIDAR_POINTS (see lidar_app.h).
#include "drivers/lidar_vlp16/lidar_app.h"

#include "core/lidar/pcap.h"
#include "processes/framework/stop_signals.h"
#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/lidar_points_t.hpp"

#include <cstring>
#include <fstream>
#include <iostream>
#include <stdexcept>

namespace lanemap::drivers {
namespace {

constexpr int kPositionPacketSize = 512;  // VLP-16 position (GPS/PPS) packet payload

}  // namespace

void LidarSettings::load(const config::YamlReader& config) {
  config.read("model", model);
  config.read("address", address);
  config.read("data_port", data_port);
  config.read("position_port", position_port);
  config.read("receive_buffer_bytes", receive_buffer_bytes);
  config.read("publish_points", publish_points);
  config.read("packets_channel", packets_channel);
  config.read("points_channel", points_channel);
  config.read("rate_scale", rate_scale);
  config.read("keep_capture_time", keep_capture_time);
}

void LidarSettings::validate() const {
  if (data_port < 1 || data_port > 65535) {
    throw std::runtime_error("lidar_vlp16: data_port " + std::to_string(data_port) +
                             " not in 1..65535");
  }
  if (position_port < 0 || position_port > 65535 || position_port == data_port) {
    throw std::runtime_error("lidar_vlp16: position_port " + std::to_string(position_port) +
                             " not in 0..65535 or equal to data_port");
  }
  if (!(rate_scale >= 0.0)) throw std::runtime_error("lidar_vlp16: rate_scale must be >= 0");
  forcedModel();  // throws on an unknown model name
}

std::optional<lidar::Model> LidarSettings::forcedModel() const {
  if (model == "auto") return std::nullopt;
  try {
    return lidar::parseModel(model);
  } catch (const std::exception& e) {
    throw std::runtime_error("lidar_vlp16: model '" + model +
                             "' unknown (vlp16, vlp32c, hdl32e or auto): " + e.what());
  }
}

LidarApp::LidarApp(Process& process, LidarSettings settings)
    : process_(process),
      settings_(std::move(settings)),
      bundler_(settings_.forcedModel(), settings_.publish_points) {
  auto stop = [this] { return stop_.load() || Process::stopRequested(); };
  auto sink = [this](const lidar::Datagram& d, PortKind kind) { onDatagram(d, kind); };
  if (!settings_.pcap.empty()) {
    std::ifstream in(settings_.pcap, std::ios::binary | std::ios::ate);
    if (!in) throw std::runtime_error("cannot read capture file '" + settings_.pcap + "'");
    const auto bytes = static_cast<long long>(in.tellg());
    if (!lidar::looksLikePcap(settings_.pcap) &&
        (bytes == 0 || bytes % lidar::kDataPacketSize != 0)) {
      throw std::runtime_error("capture file '" + settings_.pcap +
                               "' is neither a classic pcap nor " + "raw 1206-byte payloads (" +
                               std::to_string(bytes) + " bytes)");
    }
    process_.setState("replaying " + settings_.pcap);
    worker_ = std::thread([this] {
      setStopSignalsBlocked(false);
      runReplay();
    });
    return;
  }
  data_rx_ = std::make_unique<lidar::UdpReceiver>(settings_.address, settings_.data_port,
                                                  settings_.receive_buffer_bytes);
  if (settings_.position_port > 0) {
    position_rx_ = std::make_unique<lidar::UdpReceiver>(settings_.address, settings_.position_port);
  }
  process_.counters().set("receive_buffer_bytes", data_rx_->receiveBufferBytes());
  worker_ = std::thread([this, sink, stop] {
    setStopSignalsBlocked(false);  // SIGINT/SIGTERM land here, not in the main thread's LCM wait
    receiveLoop(*data_rx_, position_rx_.get(), sink, stop);
  });
}

LidarApp::~LidarApp() {
  stop_.store(true);
  if (worker_.joinable()) worker_.join();
}

void LidarApp::runReplay() {
  ReplayOptions o;
  o.rate_scale = settings_.rate_scale;
  o.keep_capture_time = settings_.keep_capture_time;
  o.data_port = static_cast<uint16_t>(settings_.data_port);
  o.position_port = static_cast<uint16_t>(settings_.position_port);
  try {
    const ReplayStats s = replayCapture(
        settings_.pcap, o, [this](const lidar::Datagram& d, PortKind k) { onDatagram(d, k); },
        [this] { return stop_.load() || Process::stopRequested(); });
    process_.counters().set("replay_skipped_records", static_cast<int64_t>(s.skipped));
  } catch (const std::exception& e) {
    std::cerr << process_.name() << ": " << e.what() << "\n";
    process_.counters().add("replay_errors");
  }
  bundler_.finish();
  process_.counters().set("sweeps_partial", static_cast<int64_t>(bundler_.partialSweeps()));
  Process::requestStop();  // replay done: spin() publishes the final STATUS and returns
}

void LidarApp::onDatagram(const lidar::Datagram& d, PortKind kind) {
  Counters& c = process_.counters();
  if (kind == PortKind::kPosition) {
    c.add(d.size == kPositionPacketSize ? "position_packets" : "position_rejected_size");
    return;
  }
  c.add("datagrams");
  std::vector<PacketSweep> done;
  // A datagram longer than the receiver's buffer arrives cut but still longer than 1206 bytes, so
  // the decoder rejects it as oversize.
  const lidar::DecodeStatus status =
      bundler_.add(d.data.data(), d.data.size(), d.receive_utime, done);
  c.add(rejectionCounterName(status));
  for (const auto& sweep : done) publish(sweep);
  c.set("sweeps_partial", static_cast<int64_t>(bundler_.partialSweeps()));
  if (bundler_.overlongSweeps() > 0)
    c.set("sweeps_overlong", static_cast<int64_t>(bundler_.overlongSweeps()));
}

void LidarApp::publish(const PacketSweep& sweep) {
  lidar_packets_t msg;
  msg.utime = sweep.packet_utime.front();
  msg.model = modelDisplayName(sweep.model);
  msg.num_packets = static_cast<int32_t>(sweep.packets.size());
  msg.packet_size = lidar::kDataPacketSize;
  msg.packet_utime = sweep.packet_utime;
  msg.data.reserve(sweep.packets.size());
  for (const auto& p : sweep.packets) msg.data.emplace_back(p.begin(), p.end());
  process_.lcm().publish(settings_.packets_channel, &msg);
  process_.counters().add("sweeps_published");
  process_.latency().add(static_cast<double>(geo::wallUtime() - sweep.packet_utime.back()) * 1e-3);

  if (!settings_.publish_points || sweep.points.empty()) return;
  lidar_points_t pts;
  pts.utime = sweep.point_utime.front();
  pts.num_points = static_cast<int32_t>(sweep.points.size());
  for (std::size_t i = 0; i < sweep.points.size(); ++i) {
    const auto& p = sweep.points[i];
    pts.x.push_back(p.x);
    pts.y.push_back(p.y);
    pts.z.push_back(p.z);
    pts.intensity.push_back(p.intensity);
    pts.ring.push_back(static_cast<int8_t>(p.ring));
    pts.time_offset.push_back(static_cast<float>((sweep.point_utime[i] - pts.utime) * 1e-6));
  }
  process_.lcm().publish(settings_.points_channel, &pts);
  process_.counters().add("points_published", pts.num_points);
}

}  // namespace lanemap::drivers
