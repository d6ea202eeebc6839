// The NMEA pose driver's application object: settings (config/pose_nmea.yaml, overridable on the
// command line) and PoseApp, which reads bytes from the source on a worker thread, cuts lines,
// parses and combines them (core/gnss/nmea.h) and publishes one POSE per fix epoch, with the line
// counts by reason in STATUS. In file mode it exits at the end of the file.
#pragma once

#include "core/gnss/nmea.h"
#include "drivers/pose_nmea/nmea_source.h"
#include "processes/framework/channels.h"
#include "processes/framework/process.h"

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace lanemap::drivers {

struct PoseSettings {
  std::string source = "serial";  // serial | udp | file
  std::string serial_device = "/dev/ttyUSB0";
  int baud = 115200;
  std::string udp_address = "0.0.0.0";
  int udp_port = 10110;  // the usual NMEA-over-UDP port
  std::string file;
  bool realtime = false;  // file: pace the epochs by their NMEA time
  std::string channel = channels::kPose;
  std::vector<std::string> talkers;  // empty: NmeaParser's default set
  gnss::CombinerOptions combiner;

  // Reads the keys present (unknown keys are an error); throws std::runtime_error naming the key.
  // The driver's config (strict: the caller's finish() refuses unknown keys).
  void load(const config::YamlReader& config);
  void validate() const;
};

class PoseApp {
 public:
  // Opens the source (throws SourceError / lidar::UdpError with a clear message) and starts the
  // worker thread.
  PoseApp(Process& process, PoseSettings settings);
  ~PoseApp();

 private:
  void run();
  void handleLine(const std::string& line, int64_t receive_utime);
  void pace(const gnss::Sentence& sentence);
  void publish(const gnss::GnssPose& pose);
  void updateCounters();

  Process& process_;
  PoseSettings settings_;
  std::unique_ptr<NmeaSource> source_;
  gnss::NmeaParser parser_;
  gnss::NmeaLineSplitter splitter_;
  gnss::PoseCombiner combiner_;
  std::optional<double> pace_t0_;
  std::chrono::steady_clock::time_point pace_start_;
  std::atomic<bool> stop_{false};
  std::thread worker_;
};

}  // namespace lanemap::drivers
