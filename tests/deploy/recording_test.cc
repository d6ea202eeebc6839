// The recording workflow of docs/recording.md, inside a private network namespace: a simulated
// drive is published with Debian's lcm-logplayer (as the drivers would publish it), recorded with
// lcm-logger, and the recording holds the same messages: the same channels, the same count per
// channel, every payload byte-equal and in order; the logger's timestamps keep the order of
// arrival (within a channel, and among messages sent in one datagram) and span the drive's
// duration. Then the recording itself replays (lcm-logplayer) into a second logger and
// comes out the same again: a recording is as good as the original drive.
#include "processes/framework/channels.h"
#include "tests/common/child_process.h"
#include "tests/common/lcm_log.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <map>

namespace {

using namespace lanemap::testing;
using namespace std::chrono_literals;

constexpr const char* kProbe = "LANEMAP_TEST_PROBE";

std::string which(const std::string& tool) {
  auto r = runCommand("command -v " + tool);
  while (!r.output.empty() && r.output.back() == '\n') r.output.pop_back();
  return r.output;
}

// Starts lcm-logger on `url` writing `path` and returns once it records (a probe message seen in
// the file). The probe channel is left out of the comparisons.
std::unique_ptr<ChildProcess> startLogger(const std::string& url, const std::string& path) {
  auto logger = std::make_unique<ChildProcess>(
      std::vector<std::string>{which("lcm-logger"), "--force", "--quiet", "--flush-interval=20", "--lcm-url=" + url, path});
  // (Debian's lcm-logger 1.3.1 does not know the short -l: only --lcm-url=URL works)
  if (!logger->started()) return nullptr;
  lcm::LCM lcm(url);
  const uint8_t probe[1] = {1};
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    lcm.publish(kProbe, probe, 1);
    std::this_thread::sleep_for(50ms);
    if (countChannel(readLcmLog(path), kProbe) > 0) return logger;
  }
  ADD_FAILURE() << "lcm-logger did not record within 10 s";
  return nullptr;
}

std::vector<LogMessage> withoutProbe(std::vector<LogMessage> log) {
  log.erase(std::remove_if(log.begin(), log.end(), [](const LogMessage& m) { return m.channel == kProbe; }), log.end());
  return log;
}

// Plays `log` with lcm-logplayer while lcm-logger records it to `out`; returns the recording.
std::vector<LogMessage> playAndRecord(const std::string& log, const std::string& out, const std::string& url,
                                      std::size_t expected_messages, const std::string& speed) {
  auto logger = startLogger(url, out);
  if (!logger) return {};
  const auto play = runCommand(which("lcm-logplayer") + " -s " + speed + " -l '" + url + "' " + log);
  EXPECT_EQ(play.exit_code, 0) << play.output;
  // lcm-logger flushes when a message arrives after its flush interval: probes push the last
  // messages of the drive to the file.
  lcm::LCM lcm(url);
  const uint8_t probe[1] = {2};
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (withoutProbe(readLcmLog(out)).size() < expected_messages && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(50ms);
    lcm.publish(kProbe, probe, 1);
  }
  std::this_thread::sleep_for(200ms);  // anything extra would show up now
  EXPECT_EQ(logger->stop(), 0);        // SIGTERM: lcm-logger closes its file and exits 0
  return withoutProbe(readLcmLog(out));
}

void expectSameMessages(const std::vector<LogMessage>& original, const std::vector<LogMessage>& recorded) {
  const auto a = byChannel(original), b = byChannel(recorded);
  std::vector<std::string> ca, cb;
  for (const auto& kv : a) ca.push_back(kv.first);
  for (const auto& kv : b) cb.push_back(kv.first);
  ASSERT_EQ(cb, ca);
  for (const auto& [channel, msgs] : a) {
    const auto& got = b.at(channel);
    ASSERT_EQ(got.size(), msgs.size()) << channel;
    for (std::size_t i = 0; i < msgs.size(); ++i) {
      ASSERT_EQ(got[i].size(), msgs[i].size()) << channel << " message " << i;
      ASSERT_TRUE(got[i] == msgs[i]) << channel << " message " << i << " payload differs";
    }
  }
}

TEST(Recording, LoggerRecordsAReplayedDriveByteForByteAndItReplaysAgain) {
  if (!inPrivateNetns()) {
    ASSERT_EQ(rerunInPrivateNetns(), 0);
    return;
  }
  // 8 s with every sensor (shared with tests/lcm/logplayer_replay_test.cc): CAMERA_FRONT JPEGs and
  // LIDAR_PACKETS sweeps of ~90 kB are fragmented by LCM, POSE at 100 Hz.
  const std::string drive = sharedSimDrive("osm/west-oakland.osm", 8.0, 5);
  ASSERT_FALSE(drive.empty());
  const auto original = readLcmLog(drive + "/drive.lcmlog");
  const auto channels = byChannel(original);
  for (const char* ch : {lanemap::channels::kPose, lanemap::channels::kCameraFront, lanemap::channels::kLidarPackets,
                         lanemap::channels::kSemanticFrontTruth}) {
    ASSERT_TRUE(channels.count(ch)) << ch;
  }
  ASSERT_GT(countChannel(original, lanemap::channels::kPose), 700u);

  TempDir dir("recording");
  const std::string url = testUdpmUrl(7671);
  const auto first = playAndRecord(drive + "/drive.lcmlog", dir.str("first.lcmlog"), url, original.size(), "1");
  ASSERT_FALSE(first.empty());
  expectSameMessages(original, first);
  // The logger's own timestamps span the drive (played at real time) and never go back among the
  // messages that travel in one datagram, nor within one channel. LCM stamps a fragmented message
  // (camera, LIDAR) when its first fragment arrives, so small messages received while its
  // fragments trickle in are written before it with later stamps: by 36 us on an idle machine, by
  // 39 ms in CI with the multi-host test running beside this one. A message under 1400 bytes (POSE,
  // ROAD_EVENT, ...) is one datagram: no LCM version fragments below that.
  std::size_t small_messages = 0;
  int64_t last_small = 0;
  std::map<std::string, int64_t> last_in_channel;
  for (std::size_t i = 0; i < first.size(); ++i) {
    const auto& m = first[i];
    if (m.channel.size() + 1 + m.data.size() + 8 < 1400) {
      ASSERT_GE(m.timestamp, last_small) << i << " " << m.channel;
      last_small = m.timestamp;
      ++small_messages;
    }
    auto it = last_in_channel.find(m.channel);
    if (it != last_in_channel.end()) ASSERT_GE(m.timestamp, it->second) << i << " " << m.channel;
    last_in_channel[m.channel] = m.timestamp;
  }
  EXPECT_GE(small_messages, countChannel(original, lanemap::channels::kPose));  // the check covered POSE
  const double span_s = (first.back().timestamp - first.front().timestamp) * 1e-6;
  const double drive_s = (original.back().timestamp - original.front().timestamp) * 1e-6;
  EXPECT_NEAR(span_s, drive_s, 0.05 * drive_s + 0.2);

  // The recording is a drive log like any other: replay it (twice as fast) and record again.
  const auto second = playAndRecord(dir.str("first.lcmlog"), dir.str("second.lcmlog"), url, original.size(), "2");
  // (the first recording also holds the probe messages: played again, they are left out)
  expectSameMessages(original, second);
}

}  // namespace
