// Helpers for process tests: start a binary in the background (posix_spawn) and stop it
// with SIGTERM, and collect the LCM messages a driver publishes (decoded), all inside the private
// network namespace of tests/common/netns.h.
#pragma once

#include "lanemap/lidar_packets_t.hpp"
#include "lanemap/lidar_points_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/status_t.hpp"
#include "tests/common/status.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <map>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace lanemap::testing {

// A child process started with posix_spawn; SIGTERM + wait at stop() or destruction.
class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, argv[0], nullptr, nullptr, argv.data(), environ) != 0) pid_ = -1;
  }
  ~ChildProcess() { stop(); }
  bool started() const { return pid_ > 0; }
  pid_t pid() const { return pid_; }
  // Exit code after SIGTERM (or after it exited by itself); -1 if it died of a signal.
  int stop() {
    if (pid_ <= 0) return exit_code_;
    kill(pid_, SIGTERM);
    return wait();
  }
  // Waits for the child to exit by itself (up to timeout); -2 on timeout.
  int waitExit(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (pid_ > 0 && std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        return exit_code_;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return pid_ > 0 ? -2 : exit_code_;
  }

 private:
  int wait() {
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return exit_code_;
  }
  pid_t pid_ = -1;
  int exit_code_ = -1;
};

// Decodes what drivers publish. Subscribes LIDAR_PACKETS, LIDAR_POINTS, POSE and STATUS.
class DriverMessages {
 public:
  explicit DriverMessages(lcm::LCM& lcm) : lcm_(lcm) {
    for (const char* ch : {"LIDAR_PACKETS", "LIDAR_POINTS", "POSE", "STATUS"}) {
      lcm.subscribe(ch, &DriverMessages::onMessage, this)->setQueueCapacity(1000);
    }
  }
  std::vector<lanemap::lidar_packets_t> packets;
  std::vector<lanemap::lidar_points_t> points;
  std::vector<lanemap::pose_t> poses;
  std::map<std::string, lanemap::status_t> last_status;  // by process name

  // Counter of the last STATUS of `process` (-1 if absent).
  int64_t counter(const std::string& process, const std::string& name) const {
    auto it = last_status.find(process);
    return it == last_status.end() ? -1 : statusCounter(it->second, name);
  }
  // Handles messages until `done()` or the timeout; returns done().
  bool waitFor(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!done() && std::chrono::steady_clock::now() < deadline) lcm_.handleTimeout(20);
    return done();
  }

 private:
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto n = static_cast<int>(rbuf->data_size);
    if (channel == "LIDAR_PACKETS") {
      packets.emplace_back();
      if (packets.back().decode(rbuf->data, 0, n) < 0) packets.pop_back();
    } else if (channel == "LIDAR_POINTS") {
      points.emplace_back();
      if (points.back().decode(rbuf->data, 0, n) < 0) points.pop_back();
    } else if (channel == "POSE") {
      poses.emplace_back();
      if (poses.back().decode(rbuf->data, 0, n) < 0) poses.pop_back();
    } else if (channel == "STATUS") {
      lanemap::status_t s;
      if (s.decode(rbuf->data, 0, n) >= 0) last_status[s.process] = s;
    }
  }
  lcm::LCM& lcm_;
};

}  // namespace lanemap::testing
