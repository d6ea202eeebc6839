// lanemap-wait-ready: waits until every named process has published a STATUS on the bus, then
// exits 0 (1 after --timeout seconds, naming the missing ones). A lanemap process publishes its
// first STATUS when it enters its LCM loop, after it subscribed: from then on it misses nothing.
// Launch files start a log player with it, so the first seconds of a drive are not lost to a
// process still loading its map on a busy machine (config/launch/demo.yaml):
//
//   lanemap-wait-ready --timeout 60 segmenter road_tracker bev_builder && exec lanemap-logplayer ...
#include "lanemap/status_t.hpp"
#include "processes/framework/channels.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <iostream>
#include <set>
#include <string>
#include <vector>

namespace {

struct Waiter {
  std::set<std::string> missing;
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const lanemap::status_t* s) { missing.erase(s->process); }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Wait until the named lanemap processes publish STATUS (they are subscribed and running)"};
  std::vector<std::string> names;
  std::string url;
  double timeout_s = 60.0;
  app.add_option("process", names, "process names, as in their STATUS (segmenter, road_tracker, ...)")->required();
  app.add_option("--timeout", timeout_s, "give up after this many seconds (exit 1)")->capture_default_str();
  app.add_option("--lcm-url", url, "LCM URL (default $LCM_DEFAULT_URL)");
  CLI11_PARSE(app, argc, argv);

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::cerr << "lanemap-wait-ready: cannot open LCM\n";
    return 2;
  }
  Waiter w;
  w.missing.insert(names.begin(), names.end());
  lcm.subscribe(lanemap::channels::kStatus, &Waiter::onStatus, &w);
  const auto t0 = std::chrono::steady_clock::now();
  const auto deadline = t0 + std::chrono::duration<double>(timeout_s);
  while (!w.missing.empty() && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(100);
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!w.missing.empty()) {
    std::cerr << "lanemap-wait-ready: no STATUS after " << waited << " s from:";
    for (const auto& n : w.missing) std::cerr << " " << n;
    std::cerr << "\n";
    return 1;
  }
  std::cerr << "lanemap-wait-ready: " << names.size() << " processes ready after " << waited << " s\n";
  return 0;
}
