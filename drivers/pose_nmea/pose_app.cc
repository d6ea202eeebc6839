// PoseApp: NMEA bytes -> lines -> sentences -> epochs -> POSE (see pose_app.h).
#include "drivers/pose_nmea/pose_app.h"

#include "lanemap/pose_t.hpp"

#include <signal.h>

#include <pthread.h>

#include <iostream>
#include <stdexcept>

namespace lanemap::drivers {
namespace {

// SIGINT/SIGTERM go to the worker, never to the main thread's LCM wait (see lidar_vlp16's
// processes/framework/stop_signals.h: Process::spin() treats an interrupted wait as a failure).
void unblockStopSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
}

}  // namespace

void PoseSettings::load(const config::YamlReader& config) {
  config.read("source", source);
  config.read("serial_device", serial_device);
  config.read("baud", baud);
  config.read("udp_address", udp_address);
  config.read("udp_port", udp_port);
  config.read("file", file);
  config.read("realtime", realtime);
  config.read("channel", channel);
  config.read("talkers", talkers);
  {
    const config::YamlReader c = config.section("combiner");
    auto& o = combiner;
    c.read("uere_single_m", o.uere_single_m);
    c.read("uere_dgnss_m", o.uere_dgnss_m);
    c.read("uere_rtk_float_m", o.uere_rtk_float_m);
    c.read("uere_rtk_fixed_m", o.uere_rtk_fixed_m);
    c.read("uere_dead_reckoning_m", o.uere_dead_reckoning_m);
    c.read("vertical_factor", o.vertical_factor);
    c.read("heading_sigma_deg", o.heading_sigma_deg);
    c.read("course_heading_sigma_deg", o.course_heading_sigma_deg);
    c.read("roll_pitch_sigma_deg", o.roll_pitch_sigma_deg);
    c.read("min_speed_for_course_mps", o.min_speed_for_course_mps);
    c.read("use_course_as_heading", o.use_course_as_heading);
    c.read("publish_invalid", o.publish_invalid);
  }
}

void PoseSettings::validate() const {
  if (source != "serial" && source != "udp" && source != "file") {
    throw std::runtime_error("pose_nmea: source '" + source + "' unknown (serial, udp or file)");
  }
  if (source == "file" && file.empty())
    throw std::runtime_error("pose_nmea: source file needs --file");
  if (source == "serial") baudConstant(baud);
  if (udp_port < 1 || udp_port > 65535) {
    throw std::runtime_error("pose_nmea: udp_port " + std::to_string(udp_port) +
                             " not in 1..65535");
  }
  combiner.validate();
}

PoseApp::PoseApp(Process& process, PoseSettings settings)
    : process_(process),
      settings_(std::move(settings)),
      parser_(settings_.talkers.empty() ? gnss::NmeaParser()
                                        : gnss::NmeaParser(std::set<std::string>(
                                              settings_.talkers.begin(), settings_.talkers.end()))),
      combiner_(settings_.combiner) {
  if (settings_.source == "file") {
    source_ = std::make_unique<FileSource>(settings_.file);
  } else if (settings_.source == "udp") {
    source_ = std::make_unique<UdpSource>(settings_.udp_address, settings_.udp_port);
  } else {
    source_ = std::make_unique<SerialSource>(settings_.serial_device, settings_.baud);
  }
  process_.setState("reading " + source_->describe());
  worker_ = std::thread([this] {
    unblockStopSignals();
    run();
  });
}

PoseApp::~PoseApp() {
  stop_.store(true);
  if (worker_.joinable()) worker_.join();
}

void PoseApp::run() {
  std::string chunk, line;
  int64_t receive_utime = geo::wallUtime();
  try {
    while (!stop_.load() && !Process::stopRequested()) {
      chunk.clear();
      const bool more = source_->read(chunk, receive_utime, 100);
      splitter_.feed(chunk);
      while (splitter_.next(line)) handleLine(line, receive_utime);
      if (!more) break;  // end of file
    }
  } catch (const std::exception& e) {
    std::cerr << process_.name() << ": " << e.what() << "\n";
    process_.counters().add("source_errors");
    process_.setState(std::string("source failed: ") + e.what());
  }
  if (const std::string rest = splitter_.flush(); !rest.empty()) handleLine(rest, receive_utime);
  for (const auto& pose : combiner_.flush()) publish(pose);
  updateCounters();
  if (settings_.source == "file" || process_.counters().get("source_errors") > 0) {
    Process::requestStop();  // the stream ended: spin() sends the final STATUS and returns
  }
}

void PoseApp::handleLine(const std::string& line, int64_t receive_utime) {
  const gnss::ParseResult r = parser_.parse(line);
  if (r.sentence) {
    if (settings_.realtime) pace(*r.sentence);
    for (const auto& pose : combiner_.add(*r.sentence, receive_utime)) publish(pose);
  }
  updateCounters();
}

void PoseApp::pace(const gnss::Sentence& s) {
  std::optional<double> t;
  if (const auto* g = std::get_if<gnss::GgaData>(&s.data)) t = g->utc_seconds;
  if (const auto* r = std::get_if<gnss::RmcData>(&s.data)) t = r->utc_seconds;
  if (!t) return;
  if (!pace_t0_) {
    pace_t0_ = t;
    pace_start_ = std::chrono::steady_clock::now();
    return;
  }
  double dt = *t - *pace_t0_;
  if (dt < -43200.0) dt += 86400.0;  // past midnight
  const auto due = pace_start_ + std::chrono::microseconds(static_cast<int64_t>(dt * 1e6));
  while (!stop_.load() && !Process::stopRequested() && std::chrono::steady_clock::now() < due) {
    std::this_thread::sleep_until(
        std::min(due, std::chrono::steady_clock::now() + std::chrono::milliseconds(100)));
  }
}

void PoseApp::publish(const gnss::GnssPose& p) {
  pose_t msg{};
  msg.utime = p.utime;
  msg.latitude = p.latitude_deg;
  msg.longitude = p.longitude_deg;
  msg.altitude = p.altitude_m;
  for (int i = 0; i < 4; ++i) msg.orientation[i] = p.orientation[i];
  for (int i = 0; i < 3; ++i) msg.velocity_enu[i] = p.velocity_enu[i];
  for (int i = 0; i < 9; ++i) {
    msg.position_covariance[i] = p.position_covariance[i];
    msg.orientation_covariance[i] = p.orientation_covariance[i];
  }
  msg.status = static_cast<int8_t>(p.status);
  process_.lcm().publish(settings_.channel, &msg);
  process_.counters().add("poses_published");
  process_.latency().add(static_cast<double>(geo::wallUtime() - p.utime) * 1e-3);
}

void PoseApp::updateCounters() {
  Counters& c = process_.counters();
  for (const auto& [status, n] : parser_.statusCounts()) {
    if (status == "ok") {
      c.set("sentences", static_cast<int64_t>(n));
    } else if (status == "ignored") {
      c.set("ignored", static_cast<int64_t>(n));
    } else {
      c.set("rejected_" + status, static_cast<int64_t>(n));
    }
  }
  for (const auto& [type, n] : parser_.sentenceCounts())
    c.set("sentences_" + type, static_cast<int64_t>(n));
  c.set("rejected_too_long_lines", static_cast<int64_t>(splitter_.oversize()));
  c.set("rejected", static_cast<int64_t>(parser_.rejected() + splitter_.oversize()));
  c.set("epochs_without_fix", static_cast<int64_t>(combiner_.epochsWithoutFix()));
}

}  // namespace lanemap::drivers
