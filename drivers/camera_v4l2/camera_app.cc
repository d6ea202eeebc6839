// CameraApp: capture loop -> CAMERA_FRONT (see camera_app.h).
#include "drivers/camera_v4l2/camera_app.h"

#include "processes/framework/stop_signals.h"
#include "lanemap/image_t.hpp"

#include <iostream>
#include <stdexcept>

namespace lanemap::drivers {

void CameraSettings::load(const config::YamlReader& config) {
  auto& c = capture;
  config.read("device", device);
  config.read("channel", channel);
  config.read("format", c.format);
  config.read("width", c.width);
  config.read("height", c.height);
  config.read("fps", c.fps);
  config.read("jpeg_quality", c.jpeg_quality);
  config.read("buffers", c.buffers);
  config.read("poll_timeout_ms", c.poll_timeout_ms);
  config.read("stall_timeout_s", c.stall_timeout_s);
  double age_ms = static_cast<double>(c.max_timestamp_age_us) * 1e-3;
  config.read("max_timestamp_age_ms", age_ms);
  c.max_timestamp_age_us = static_cast<int64_t>(age_ms * 1e3);
  config.read("reconnect", c.reconnect);
  config.read("reconnect_initial_s", c.reconnect_initial_s);
  config.read("reconnect_max_s", c.reconnect_max_s);
}

CameraApp::CameraApp(Process& process, CameraSettings settings)
    : process_(process),
      settings_(std::move(settings)),
      device_(settings_.device),
      capture_(
          device_, settings_.capture, [this](const camera::CapturedFrame& f) { publish(f); },
          [this](const std::string& state, const std::string& message) {
            process_.setState(state == "streaming" ? "streaming " + settings_.device
                                                   : state == "waiting" ? "waiting for " + settings_.device
                                                                        : state);
            std::cerr << process_.name() << ": " << message << "\n";
            updateCounters();
          }) {
  process_.setState("opening " + settings_.device);
  worker_ = std::thread([this] {
    setStopSignalsBlocked(false);  // SIGINT/SIGTERM land here, not in the main thread's LCM wait
    try {
      capture_.run([this] { return stop_.load() || Process::stopRequested(); });
    } catch (const camera::VideoDeviceError& e) {
      std::cerr << process_.name() << ": " << e.what() << "\n";
      if (e.retryable()) {
        std::cerr << process_.name() << ": giving up (reconnect: true waits for the camera)\n";
      }
      exit_code_.store(2);
      process_.setState("failed");
    } catch (const std::exception& e) {
      std::cerr << process_.name() << ": " << e.what() << "\n";
      exit_code_.store(2);
      process_.setState("failed");
    }
    updateCounters();
    Process::requestStop();
  });
}

CameraApp::~CameraApp() {
  stop_.store(true);
  if (worker_.joinable()) worker_.join();
}

void CameraApp::updateCounters() {
  const camera::CaptureStats s = capture_.stats();
  Counters& c = process_.counters();
  c.set("frames", s.frames);
  c.set("frames_dropped", s.dropped);
  c.set("frames_corrupt", s.corrupt);
  c.set("huffman_inserted", s.huffman_inserted);
  c.set("timestamp_fallbacks", s.timestamp_fallbacks);
  c.set("poll_timeouts", s.poll_timeouts);
  c.set("stalls", s.stalls);
  c.set("disconnects", s.disconnects);
  c.set("open_failures", s.open_failures);
  c.set("restarts", s.restarts);
  c.set("format_adjusted", s.format_adjusted);
  const camera::VideoFormat f = capture_.format();
  c.set("width", f.width);
  c.set("height", f.height);
}

void CameraApp::publish(const camera::CapturedFrame& frame) {
  image_t msg;
  msg.utime = frame.utime;
  msg.seq = frame.seq;
  msg.width = static_cast<int32_t>(frame.width);
  msg.height = static_cast<int32_t>(frame.height);
  msg.row_stride = 0;
  msg.pixelformat = image_t::PIXEL_FORMAT_JPEG;
  msg.size = static_cast<int32_t>(frame.jpeg.size());
  msg.data = frame.jpeg;
  process_.lcm().publish(settings_.channel, &msg);
  process_.latency().add(static_cast<double>(geo::wallUtime() - frame.utime) * 1e-3);
  updateCounters();
}

void listDevices(std::ostream& out) {
  const auto devices = camera::listVideoDevices();
  if (devices.empty()) out << "no /dev/video* device\n";
  for (const auto& path : devices) {
    camera::V4l2Device dev(path);
    try {
      dev.open();
      out << path << ": " << dev.card() << " (" << dev.driver() << ", " << dev.busInfo() << "):";
      for (uint32_t f : dev.formats()) out << " " << camera::fourccToString(f);
      out << "\n";
    } catch (const std::exception& e) {
      out << e.what() << "\n";
    }
    dev.stop();
  }
}

}  // namespace lanemap::drivers
