// The small process framework every lanemap process and driver uses:
// command line (--config, --lcm-url, --help), YAML config, the LCM instance, clean shutdown on
// SIGINT/SIGTERM, and a 1 Hz STATUS message with the process's counters.
//
//   int main(int argc, char** argv) {
//     lanemap::Process process("road_tracker");
//     if (int rc = process.init(argc, argv); rc >= 0) return rc;
//     RoadTrackerApp app(process);      // subscribes in its constructor
//     return process.spin();            // until SIGINT/SIGTERM
//   }
#pragma once

#include "core/geo/wall_clock.h"
#include "core/config/yaml_reader.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace lanemap {

// Named monotonic counters, reported in STATUS. Thread-safe.
class Counters {
 public:
  void add(const std::string& name, int64_t n = 1);
  void set(const std::string& name, int64_t value);
  int64_t get(const std::string& name) const;
  std::map<std::string, int64_t> snapshot() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> values_;
};

// Latencies (ms) of the last 500 events, for p50/p99 in STATUS. lanemap's convention: from when
// the input entered the process (lcm::ReceiveBuffer::recv_utime, the wall-clock time LCM's receive
// thread got the message) to when its output is done, so queue waits count; never now - msg.utime,
// which is meaningless on a replayed log. Each process's header says what its input and output are.
class LatencyWindow {
 public:
  void add(double ms);
  double percentile(double p) const;  // NaN when empty

 private:
  mutable std::mutex mutex_;
  std::deque<double> samples_;
};

// Resolves the LCM URL: explicit flag, else the config's `lcm_url`, else $LCM_DEFAULT_URL,
// else "" (LCM's own default).
std::string resolveLcmUrl(const std::string& flag, const YAML::Node& config);

// Loads a YAML file; throws std::runtime_error naming the file and the problem.
YAML::Node loadYamlFile(const std::string& path);

class Process {
 public:
  explicit Process(std::string name);
  ~Process();

  // Command line of this process: add options before init().
  CLI::App& cli() { return cli_; }

  // Parses the command line, loads the config, creates the LCM instance and installs the signal
  // handlers. Returns -1 to go on, or an exit code (0 after --help, non-zero on an error, which it
  // has printed).
  int init(int argc, char** argv);

  const std::string& name() const { return name_; }
  const YAML::Node& config() const { return config_; }
  // The same config through the strict reader (knows the file; `lcm_url` is already known): read
  // every key through it, then call its finish() so that an unknown key is an error naming it.
  const config::YamlReader& settings() const { return settings_; }
  lcm::LCM& lcm() { return *lcm_; }
  Counters& counters() { return counters_; }
  LatencyWindow& latency() { return latency_; }
  void setState(const std::string& state);

  // Handles LCM messages until SIGINT/SIGTERM (or requestStop()), publishing STATUS every second.
  // Returns the exit code. With --replay: runs the process replay instead (below).
  int spin();

  // Process replay (openpilot's, tests/replay): `--replay IN.lcmlog --replay-out OUT.lcmlog` puts
  // the process on an in-process bus (memq://); spin() publishes IN's events one at a time in log
  // order (STATUS aside), handles each to the end before the next, and writes what the process
  // publishes (STATUS aside) to OUT, each stamped with the time of the input event it answered.
  // Whatever the app publishes after spin() (a finish() at the end of the drive) is collected when
  // the Process is destroyed. A process with a worker thread says when it is idle (setIdleCheck):
  // the replay waits for it after every input, so the output does not depend on the machine.
  //
  // `--replay-out OUT.lcmlog` alone is the replay of a process that reads its own input (a driver's
  // --file or --pcap): it runs as usual on an in-process bus and OUT records what it publishes
  // (STATUS aside), each stamped 0 (there is no input event to answer).
  bool replaying() const { return !replay_in_.empty(); }
  bool recording() const { return !replay_out_.empty(); }
  void setIdleCheck(std::function<bool()> idle) { idle_ = std::move(idle); }

  // Publishes one STATUS message now (spin() calls it at 1 Hz).
  void publishStatus();

  static void requestStop();
  static bool stopRequested();

 private:
  std::string name_;
  CLI::App cli_;
  std::string config_path_;
  std::string lcm_url_flag_;
  YAML::Node config_;
  config::YamlReader settings_{YAML::Node()};
  std::unique_ptr<lcm::LCM> lcm_;
  Counters counters_;
  LatencyWindow latency_;
  std::mutex state_mutex_;
  std::string state_ = "starting";
  double last_cpu_s_ = 0.0;
  std::chrono::steady_clock::time_point last_status_wall_;

  int replay();
  void drainReplay(bool wait_idle);
  void onReplayMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  std::string replay_in_, replay_out_;
  std::unique_ptr<lcm::LogFile> replay_log_;
  std::deque<std::pair<std::string, std::string>> replay_inputs_;  // published, not yet seen back
  int64_t replay_utime_ = 0, replay_events_ = 0;
  std::function<bool()> idle_;
};

}  // namespace lanemap
