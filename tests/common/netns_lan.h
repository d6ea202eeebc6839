// Several "machines" on one Ethernet segment, for multi-host tests, built inside the test's own
// private network namespace (tests/common/netns.h: `unshare -rn`, where the test is root of a user
// namespace and owns the network namespace; no privilege on the real machine is used).
//
// NetnsLan::init() makes a bridge in the test's namespace (multicast snooping off, so multicast
// floods to every port); addHost(name) starts a holder process in a new network + UTS namespace
// (hostname = name), joins it to the bridge by a veth pair (eth0, 10.77.0.N/24, 224.0.0.0/4 routed to
// eth0, so LCM udpm with ttl=1 reaches the other hosts); addLoopbackHost(name) makes a namespace with
// only lo (224.0.0.0/4 on lo), the one-machine reference. run() gives the argv prefix that runs a
// command in a host's namespaces (nsenter). Everything stays inside the test's namespace: there is
// no route or link to the real network.
#pragma once

#include "tests/common/sim_drive.h"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <map>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace lanemap::testing {

class NetnsLan {
 public:
  NetnsLan() = default;
  NetnsLan(const NetnsLan&) = delete;
  NetnsLan& operator=(const NetnsLan&) = delete;
  ~NetnsLan() {
    for (auto& [name, pid] : holders_) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
  }

  // The bridge. False (and `error`) when this kernel or sandbox cannot make one.
  bool init(std::string& error) {
    const auto r = runCommand("ip link add " + bridge_ + " type bridge mcast_snooping 0 && ip link set " + bridge_ + " up");
    if (r.exit_code != 0) error = "cannot create a bridge in the test namespace: " + r.output;
    return r.exit_code == 0;
  }

  bool addHost(const std::string& name, std::string& error) {
    pid_t pid;
    if (!startHolder(name, pid, error)) return false;
    const int n = ++hosts_on_bridge_;
    const std::string outer = "lm-" + name.substr(0, 8), inner = "lmi-" + name.substr(0, 8);
    const std::string p = std::to_string(pid);
    const auto r = runCommand("ip link add " + outer + " type veth peer name " + inner + " && ip link set " + inner +
                              " netns " + p + " && ip link set " + outer + " master " + bridge_ + " && ip link set " +
                              outer + " up && nsenter -t " + p + " -n -u sh -c 'hostname " + name +
                              " && ip link set lo up && ip link set " + inner + " name eth0 && ip addr add 10.77.0." +
                              std::to_string(n) + "/24 dev eth0 && ip link set eth0 up && ip route add 224.0.0.0/4 dev eth0'");
    if (r.exit_code != 0) error = "cannot join host " + name + " to the bridge: " + r.output;
    return r.exit_code == 0;
  }

  bool addLoopbackHost(const std::string& name, std::string& error) {
    pid_t pid;
    if (!startHolder(name, pid, error)) return false;
    const auto r = runCommand("nsenter -t " + std::to_string(pid) + " -n -u sh -c 'hostname " + name +
                              " && ip link set lo up && ip route add 224.0.0.0/4 dev lo'");
    if (r.exit_code != 0) error = "cannot set up host " + name + ": " + r.output;
    return r.exit_code == 0;
  }

  // argv prefix running a command in `host`'s network and UTS namespaces.
  std::vector<std::string> run(const std::string& host) const {
    return {nsenter_, "-t", std::to_string(holders_.at(host)), "-n", "-u", "--"};
  }
  // The same as a shell prefix.
  std::string shell(const std::string& host) const {
    return nsenter_ + " -t " + std::to_string(holders_.at(host)) + " -n -u -- ";
  }

 private:
  bool startHolder(const std::string& name, pid_t& pid, std::string& error) {
    if (nsenter_.empty()) {
      nsenter_ = trim(runCommand("command -v nsenter").output);
      unshare_ = trim(runCommand("command -v unshare").output);
    }
    const std::vector<std::string> args = {unshare_, "-nu", "sleep", "3600"};
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
      error = "cannot start unshare for host " + name;
      return false;
    }
    holders_[name] = pid;
    // Wait until unshare has made the namespace (its net namespace differs from ours).
    const std::string self = nsLink("/proc/self/ns/net");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (std::chrono::steady_clock::now() < deadline) {
      const std::string ns = nsLink("/proc/" + std::to_string(pid) + "/ns/net");
      if (!ns.empty() && ns != self && nsLink("/proc/" + std::to_string(pid) + "/exe").find("sleep") != std::string::npos) {
        return true;
      }
      int status = 0;
      if (waitpid(pid, &status, WNOHANG) == pid) {
        holders_.erase(name);
        error = "unshare -nu failed for host " + name;
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    error = "host " + name + ": namespace not ready after 5 s";
    return false;
  }

  static std::string nsLink(const std::string& path) {
    char buf[256] = {0};
    const ssize_t n = readlink(path.c_str(), buf, sizeof(buf) - 1);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
  }
  static std::string trim(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    return s;
  }

  std::string bridge_ = "lm-br0";
  std::string nsenter_, unshare_;
  int hosts_on_bridge_ = 0;
  std::map<std::string, pid_t> holders_;
};

}  // namespace lanemap::testing
