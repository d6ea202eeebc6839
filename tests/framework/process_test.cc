// The process framework: command line, config, LCM URL resolution, counters and STATUS, shutdown.
#include "lanemap/status_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/process.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>
#include <thread>

namespace {

using namespace lanemap;

struct StatusCatcher {
  std::vector<status_t> got;
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const status_t* msg) { got.push_back(*msg); }
};

std::vector<char*> argvOf(std::vector<std::string>& args) {
  std::vector<char*> v;
  for (auto& a : args) v.push_back(a.data());
  return v;
}

TEST(Channels, RegistryNamesAreUniqueUpperSnakeAndTyped) {
  std::set<std::string> names;
  for (const auto& c : channels::kRegistry) {
    const std::string n = c.name;
    EXPECT_TRUE(names.insert(n).second) << "duplicate " << n;
    for (char ch : n) EXPECT_TRUE((ch >= 'A' && ch <= 'Z') || ch == '_' || (ch >= '0' && ch <= '9')) << n;
    EXPECT_EQ(std::string(c.type).rfind("lanemap.", 0), 0u) << n;
    EXPECT_GE(c.rate_hz, 0.0);
  }
  EXPECT_EQ(channels::find("POSE")->rate_hz, 100.0);
  EXPECT_EQ(channels::find("NOT_A_CHANNEL"), nullptr);
}

TEST(ProcessFramework, LcmUrlComesFromFlagThenConfigThenEnvironment) {
  YAML::Node config = YAML::Load("lcm_url: memq://config");
  setenv("LCM_DEFAULT_URL", "memq://env", 1);
  EXPECT_EQ(resolveLcmUrl("memq://flag", config), "memq://flag");
  EXPECT_EQ(resolveLcmUrl("", config), "memq://config");
  EXPECT_EQ(resolveLcmUrl("", YAML::Node()), "memq://env");
  unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(resolveLcmUrl("", YAML::Node()), "");
}

TEST(ProcessFramework, BadConfigFilesGiveClearErrors) {
  lanemap::testing::TempDir dir("cfg");
  try {
    loadYamlFile(dir.str("missing.yaml"));
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.yaml"), std::string::npos) << e.what();
  }
  std::ofstream(dir.str("bad.yaml")) << "a: [1, 2\n";
  EXPECT_THROW(loadYamlFile(dir.str("bad.yaml")), std::runtime_error);

  Process p("test_process");
  std::vector<std::string> args{"test_process", "--config", dir.str("missing.yaml"), "--lcm-url", "memq://"};
  auto argv = argvOf(args);
  EXPECT_EQ(p.init(static_cast<int>(argv.size()), argv.data()), 2);
}

TEST(ProcessFramework, HelpExitsZeroAndUnknownFlagsFail) {
  {
    Process p("test_process");
    std::vector<std::string> args{"test_process", "--help"};
    auto argv = argvOf(args);
    EXPECT_EQ(p.init(static_cast<int>(argv.size()), argv.data()), 0);
  }
  {
    Process p("test_process");
    std::vector<std::string> args{"test_process", "--no-such-flag"};
    auto argv = argvOf(args);
    EXPECT_GT(p.init(static_cast<int>(argv.size()), argv.data()), 0);
  }
}

TEST(ProcessFramework, StatusCarriesCountersLatencyAndState) {
  Process p("test_process");
  std::vector<std::string> args{"test_process", "--lcm-url", "memq://"};
  auto argv = argvOf(args);
  ASSERT_EQ(p.init(static_cast<int>(argv.size()), argv.data()), -1);
  StatusCatcher catcher;
  p.lcm().subscribe(channels::kStatus, &StatusCatcher::onStatus, &catcher);
  p.counters().add("received", 5);
  p.counters().add("received");
  p.counters().add("dropped", 2);
  for (int i = 1; i <= 100; ++i) p.latency().add(i);
  p.publishStatus();
  p.lcm().handleTimeout(100);
  ASSERT_EQ(catcher.got.size(), 1u);
  const status_t& s = catcher.got[0];
  EXPECT_EQ(s.process, "test_process");
  EXPECT_EQ(s.state, "running");
  ASSERT_EQ(s.num_counters, 2);
  EXPECT_EQ(s.counter_names[0], "dropped");
  EXPECT_EQ(s.counter_values[0], 2);
  EXPECT_EQ(s.counter_names[1], "received");
  EXPECT_EQ(s.counter_values[1], 6);
  EXPECT_NEAR(s.latency_p50_ms, 50.5, 0.6);
  EXPECT_NEAR(s.latency_p99_ms, 99.0, 1.01);
}

TEST(ProcessFramework, SpinPublishesStatusAtOneHertzAndStopsOnRequest) {
  Process p("test_process");
  std::vector<std::string> args{"test_process", "--lcm-url", "memq://"};
  auto argv = argvOf(args);
  ASSERT_EQ(p.init(static_cast<int>(argv.size()), argv.data()), -1);
  StatusCatcher catcher;
  p.lcm().subscribe(channels::kStatus, &StatusCatcher::onStatus, &catcher);
  std::thread stopper([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(2300));
    Process::requestStop();
  });
  EXPECT_EQ(p.spin(), 0);
  stopper.join();
  // memq delivers from within handle(): drain what spin published last.
  p.lcm().handleTimeout(50);
  // Published at t = 0, 1, 2 s and once more on stopping.
  ASSERT_GE(catcher.got.size(), 3u);
  ASSERT_LE(catcher.got.size(), 4u);
  EXPECT_EQ(catcher.got.back().state, "stopped");
  const double dt = (catcher.got[2].utime - catcher.got[1].utime) * 1e-6;
  EXPECT_NEAR(dt, 1.0, 0.15);
}

}  // namespace
