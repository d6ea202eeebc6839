// lanemap-lcm-stats: listens on an LCM URL (or reads an LCM log file) and reports, per channel,
// how many messages arrived, their rate, size, and whether the channel is in the registry.
// A text-mode lcm-spy for scripts and tests.
#include "processes/framework/channels.h"
#include "processes/framework/process.h"
#include "tools/cli_checks.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>

namespace {

struct ChannelStats {
  int64_t count = 0;
  int64_t bytes = 0;
  int64_t first_utime = 0;  // receive time (live) or log timestamp
  int64_t last_utime = 0;
};

struct Listener {
  std::map<std::string, ChannelStats> stats;
  void add(const std::string& channel, int64_t bytes, int64_t t) {
    auto& s = stats[channel];
    if (s.count == 0) s.first_utime = t;
    s.last_utime = t;
    ++s.count;
    s.bytes += bytes;
  }
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    add(channel, rbuf->data_size, rbuf->recv_utime);
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("lanemap-lcm-stats: per-channel message counts and rates, live or from a log");
  std::string url, log_path, json_path;
  double seconds = 10.0, idle_exit = 0.0;
  app.add_option("--lcm-url", url, "LCM URL to listen on (default $LCM_DEFAULT_URL)");
  app.add_option("--log", log_path, "read this LCM log file instead of listening");
  app.add_option("--seconds", seconds, "listen this long")->check(lanemap::cli::kPositive);
  app.add_option("--idle-exit", idle_exit, "stop after this many seconds without a message, once one came");
  app.add_option("--json", json_path, "also write the figures as JSON");
  CLI11_PARSE(app, argc, argv);

  Listener listener;
  if (!log_path.empty()) {
    lcm::LogFile log(log_path, "r");
    if (!log.good()) {
      std::cerr << "lanemap-lcm-stats: cannot read LCM log '" << log_path << "'\n";
      return 2;
    }
    while (const lcm::LogEvent* ev = log.readNextEvent()) listener.add(ev->channel, ev->datalen, ev->timestamp);
  } else {
    lcm::LCM lcm(url);
    if (!lcm.good()) {
      std::cerr << "lanemap-lcm-stats: cannot open LCM '" << url << "'\n";
      return 2;
    }
    auto* sub = lcm.subscribe(".*", &Listener::onMessage, &listener);
    sub->setQueueCapacity(10000);
    const auto start = std::chrono::steady_clock::now();
    auto last_msg = start;
    int64_t seen = 0;
    while (std::chrono::steady_clock::now() - start < std::chrono::duration<double>(seconds)) {
      lcm.handleTimeout(50);
      int64_t total = 0;
      for (const auto& [c, s] : listener.stats) total += s.count;
      const auto now = std::chrono::steady_clock::now();
      if (total != seen) {
        seen = total;
        last_msg = now;
      } else if (idle_exit > 0 && seen > 0 && now - last_msg > std::chrono::duration<double>(idle_exit)) {
        break;
      }
    }
  }

  nlohmann::json out = nlohmann::json::object();
  std::printf("%-22s %8s %9s %12s  %s\n", "CHANNEL", "COUNT", "RATE_HZ", "BYTES", "REGISTRY");
  for (const auto& [channel, s] : listener.stats) {
    const double span = (s.last_utime - s.first_utime) * 1e-6;
    const double rate = s.count > 1 && span > 0 ? (s.count - 1) / span : 0.0;
    const auto* spec = lanemap::channels::find(channel);
    std::printf("%-22s %8lld %9.2f %12lld  %s\n", channel.c_str(), static_cast<long long>(s.count), rate,
                static_cast<long long>(s.bytes), spec ? spec->type : "(not in registry)");
    out[channel] = {{"count", s.count}, {"rate_hz", rate}, {"bytes", s.bytes}, {"registered", spec != nullptr},
                    {"first_utime", s.first_utime}, {"last_utime", s.last_utime}};
  }
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    f << out.dump(2) << "\n";
    if (!f) {
      std::cerr << "lanemap-lcm-stats: cannot write '" << json_path << "'\n";
      return 2;
    }
  }
  return 0;
}
