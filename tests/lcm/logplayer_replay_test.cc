// A simulated drive's LCM log replays with Debian's lcm-logplayer over udpm:// inside a private
// network namespace, and a subscriber receives every channel, every message, at its rate.
#include "processes/framework/channels.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace {

using namespace lanemap::testing;

nlohmann::json readJson(const std::string& path) {
  std::ifstream f(path);
  nlohmann::json j;
  f >> j;
  return j;
}

TEST(LogPlayer, ReplayDeliversEveryChannelAtItsRate) {
  if (!inPrivateNetns()) {
    ASSERT_EQ(rerunInPrivateNetns(), 0);
    return;
  }
  TempDir dir("replay");
  const std::string log = sharedSimDrive("osm/west-oakland.osm", 8.0, 5) + "/drive.lcmlog";
  ASSERT_EQ(runCommand(binPath("lanemap-lcm-stats") + " --log " + log + " --json " + dir.str("log.json")).exit_code, 0);

  const std::string url = testUdpmUrl(7668);
  const std::string cmd = binPath("lanemap-lcm-stats") + " --lcm-url '" + url +
                          "' --seconds 40 --idle-exit 2 --json " + dir.str("live.json") + " & sleep 0.5; " +
                          "lcm-logplayer -l '" + url + "' " + log + "; wait";
  const auto replay = runCommand(cmd);
  ASSERT_EQ(replay.exit_code, 0) << replay.output;

  const auto in_log = readJson(dir.str("log.json"));
  const auto live = readJson(dir.str("live.json"));
  for (const char* ch : {lanemap::channels::kPose, lanemap::channels::kCameraFront,
                         lanemap::channels::kSemanticFrontTruth, lanemap::channels::kLidarPackets}) {
    ASSERT_TRUE(in_log.contains(ch)) << ch << " missing from the log";
    ASSERT_TRUE(live.contains(ch)) << ch << " not received\n" << replay.output;
    EXPECT_EQ(live[ch]["count"].get<int64_t>(), in_log[ch]["count"].get<int64_t>()) << ch << " lost messages";
    // Received at the nominal rate of the registry (+-5 %: replay timing on a loaded machine).
    const double nominal = lanemap::channels::find(ch)->rate_hz;
    EXPECT_NEAR(live[ch]["rate_hz"].get<double>(), nominal, 0.05 * nominal) << ch;
  }
}

}  // namespace
