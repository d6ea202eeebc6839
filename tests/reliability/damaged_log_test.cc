// A truncated or corrupt LCM log (issue 18, docs/robustness.md): LogReader
// (processes/framework/log_reader.h) reads every whole event and counts what it could not read;
// lanemap-offline maps what is readable and says so (stderr, summary.json "log_read"), and a file
// with no whole event in it is a clear error (exit 2) that leaves no map behind. lanemap-logplayer
// plays such a log onto the bus past the damage, at its pace (lcm-logplayer stops at it).
#include "processes/framework/lcm_log_writer.h"
#include "processes/framework/log_reader.h"
#include "tests/bev/bev_replay.h"
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace lanemap;
namespace fs = std::filesystem;
namespace lt = lanemap::testing;
using lanemap::testing::readFile;

constexpr int kEvents = 20, kData = 1000;
constexpr int64_t kEventBytes = 4 + 8 + 8 + 4 + 4 + 1 + kData;  // sync, number, time, lengths, channel "X", data

void writeBytes(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

struct ReadResult {
  int64_t events, skipped, unread;
  std::vector<int64_t> times;
};
ReadResult readAll(const std::string& path) {
  LogReader r(path);
  ReadResult out{};
  while (const lcm::LogEvent* ev = r.next()) out.times.push_back(ev->timestamp);
  out.events = r.events();
  out.skipped = r.bytesSkipped();
  out.unread = r.bytesUnread();
  return out;
}

TEST(LogReader, CountsTheEventsItReadAndTheBytesItCouldNot) {
  lt::TempDir dir("damaged-log");
  const std::string good = dir.str("good.lcmlog");
  {
    LcmLogWriter w(good);
    const std::vector<uint8_t> data(kData, 0x55);
    for (int i = 0; i < kEvents; ++i) w.write("X", 1000 * i, data.data(), data.size());
  }
  const std::string bytes = readFile(good);
  ASSERT_EQ(static_cast<int64_t>(bytes.size()), kEvents * kEventBytes);
  const ReadResult whole = readAll(good);
  EXPECT_EQ(whole.events, kEvents);
  EXPECT_EQ(whole.skipped, 0);
  EXPECT_EQ(whole.unread, 0);

  // Cut in the middle of event 15 (a logger killed, a full disk): 15 whole events, the rest unread.
  const int64_t cut = 15 * kEventBytes + 300;
  writeBytes(dir.str("cut.lcmlog"), bytes.substr(0, cut));
  const ReadResult c = readAll(dir.str("cut.lcmlog"));
  EXPECT_EQ(c.events, 15);
  EXPECT_EQ(c.skipped, 0);
  EXPECT_EQ(c.unread, 300);
  {
    LogReader r(dir.str("cut.lcmlog"));
    while (r.next()) {
    }
    EXPECT_TRUE(r.damaged());
    EXPECT_NE(r.damageReport().find("the last 300 bytes (from byte " + std::to_string(15 * kEventBytes)), std::string::npos) << r.damageReport();
  }

  // 777 bytes of garbage between events 5 and 6: passed over to event 6's sync word. lcm trusts an
  // event only when a sync word (or the end of the file) follows it, so event 5 goes too.
  writeBytes(dir.str("garbage.lcmlog"), bytes.substr(0, 6 * kEventBytes) + std::string(777, '\0') + bytes.substr(6 * kEventBytes));
  const ReadResult g = readAll(dir.str("garbage.lcmlog"));
  EXPECT_EQ(g.events, kEvents - 1);
  EXPECT_EQ(g.skipped, 777 + kEventBytes);
  EXPECT_EQ(g.unread, 0);
  std::vector<int64_t> without5 = whole.times;
  without5.erase(without5.begin() + 5);
  EXPECT_EQ(g.times, without5);

  // Event 8's sync word overwritten: events 7 and 8 are lost (passed over), the others read.
  std::string hit = bytes;
  hit[8 * kEventBytes] = 0;
  writeBytes(dir.str("hit.lcmlog"), hit);
  const ReadResult h = readAll(dir.str("hit.lcmlog"));
  EXPECT_EQ(h.events, kEvents - 2);
  EXPECT_EQ(h.skipped, 2 * kEventBytes);
  EXPECT_EQ(h.times.back(), 19000);

  // Not a log at all.
  std::mt19937 rng(3);
  std::string noise(50000, '\0');
  for (auto& ch : noise) ch = static_cast<char>(rng() & 0x7f);  // no 0xED: no sync word
  writeBytes(dir.str("noise.lcmlog"), noise);
  const ReadResult n = readAll(dir.str("noise.lcmlog"));
  EXPECT_EQ(n.events, 0);
  EXPECT_EQ(n.unread, 50000);
  EXPECT_THROW(LogReader(dir.str("missing.lcmlog")), std::runtime_error);
}

// lanemap-logplayer over a private network namespace's bus: 40 events 20 ms apart, event 30's
// timestamp 1000 s in the future (a damaged clock), event 10's sync word overwritten (events 9 and
// 10 lost, as LogReader reads it). Every other event arrives, in order; the replay keeps the log's
// pace (at least the 0.6 s the readable timestamps span before the jump) and does not wait out
// the jump; stderr says the log is damaged. A file that is not a log: exit 2 and why.
TEST(LogPlayer, PlaysEveryReadableEventOfADamagedLogAtItsPaceAndPassesOverABadTimestamp) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  lt::TempDir dir("logplayer");
  constexpr int kN = 40, kBytes = 100;
  constexpr int64_t kOne = 4 + 8 + 8 + 4 + 4 + 1 + kBytes;
  const std::string good = dir.str("good.lcmlog");
  {
    LcmLogWriter w(good);
    for (int i = 0; i < kN; ++i) {
      const std::vector<uint8_t> data(kBytes, static_cast<uint8_t>(i));
      const int64_t t = i == 30 ? 1'000'000'000 : 20'000 * i;
      w.write("X", 1'700'000'000'000'000 + t, data.data(), data.size());
    }
  }
  std::string bytes = readFile(good);
  ASSERT_EQ(static_cast<int64_t>(bytes.size()), kN * kOne);
  bytes[10 * kOne] = 0;
  const std::string hit = dir.str("hit.lcmlog");
  writeBytes(hit, bytes);

  const std::string url = lt::testUdpmUrl(7671);
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  struct Got {
    std::vector<int> ids;
    void on(const lcm::ReceiveBuffer* b, const std::string&) { ids.push_back(b->data_size > 0 ? static_cast<const uint8_t*>(b->data)[0] : -1); }
  } got;
  lcm.subscribe("X", &Got::on, &got);
  const auto play = [&](const std::string& log, const std::string& err) {
    return lt::ChildProcess({"/bin/sh", "-c", "exec " + lt::binPath("lanemap-logplayer") + " -l '" + url + "' " + log + " 2> " + err});
  };
  const auto t0 = std::chrono::steady_clock::now();
  lt::ChildProcess player = play(hit, dir.str("hit.err"));
  ASSERT_TRUE(player.started());
  int rc = -2;
  while (rc == -2 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    lcm.handleTimeout(10);
    rc = player.waitExit(std::chrono::milliseconds(1));  // (0 would not look)
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (int i = 0; i < 20; ++i) lcm.handleTimeout(10);  // what is still in flight
  EXPECT_EQ(rc, 0);
  std::vector<int> want;
  for (int i = 0; i < kN; ++i) {
    if (i != 9 && i != 10) want.push_back(i);
  }
  EXPECT_EQ(got.ids, want);
  EXPECT_GE(wall_s, 0.6) << "played faster than the log";
  EXPECT_LT(wall_s, 30.0) << "waited for the bad timestamp";
  const std::string err = readFile(dir.str("hit.err"));
  EXPECT_NE(err.find("is damaged, played what could be read: 38 events read"), std::string::npos) << err;
  EXPECT_NE(err.find("2 timestamp jumps"), std::string::npos) << err;  // forward to event 30, back after it

  // Not a log: exit 2, and why.
  writeBytes(dir.str("noise.lcmlog"), std::string(5000, 'x'));
  lt::ChildProcess noise = play(dir.str("noise.lcmlog"), dir.str("noise.err"));
  EXPECT_EQ(noise.waitExit(std::chrono::seconds(30)), 2);
  EXPECT_NE(readFile(dir.str("noise.err")).find("not an LCM log, or no whole event in it"), std::string::npos);
}

TEST(DamagedLog, OfflineMapsWhatIsReadableSaysSoAndRefusesANonLog) {
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed, lt::kBevDriveArgs);
  ASSERT_FALSE(drive.empty());
  lt::TempDir dir("damaged-offline");
  const std::string bytes = readFile(drive + "/drive.lcmlog");
  const auto offline = [&](const std::string& log, const std::string& out) {
    return lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --log " + log + " --osm " + drive + "/roads.osm --out " + out);
  };
  const auto summary = [](const std::string& out) { return nlohmann::json::parse(readFile(out + "/summary.json")); };

  int64_t events = 0, middle = 0;  // the whole log's events; where the event nearest its middle starts
  {
    LogReader whole(drive + "/drive.lcmlog");
    while (whole.next()) {
      if (whole.lastEventEnd() <= static_cast<int64_t>(bytes.size()) / 2) middle = whole.lastEventEnd();
    }
    ASSERT_FALSE(whole.damaged());
    events = whole.events();
  }

  // Cut at 97 % of its bytes, inside an event, and with 4 KiB overwritten by noise from the start
  // of the event in its middle.
  std::string damaged = bytes.substr(0, bytes.size() * 97 / 100);
  std::mt19937 rng(11);
  for (size_t i = 0; i < 4096; ++i) damaged[middle + i] = static_cast<char>(rng());
  writeBytes(dir.str("damaged.lcmlog"), damaged);
  const auto d = offline(dir.str("damaged.lcmlog"), dir.str("damaged"));
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NE(d.output.find("warning: the log is damaged, mapping what could be read"), std::string::npos) << d.output;
  EXPECT_NE(d.output.find("are not a whole event"), std::string::npos) << d.output;
  const auto sd = summary(dir.str("damaged"));
  EXPECT_TRUE(sd["log_read"]["damaged"].get<bool>());
  EXPECT_GT(sd["log_read"]["bytes_unread"].get<int64_t>(), 0);
  EXPECT_GE(sd["log_read"]["bytes_skipped"].get<int64_t>(), 4096) << "the noise and the events it hit";
  EXPECT_LT(sd["log_read"]["events"].get<int64_t>(), events);
  EXPECT_GT(sd["log_read"]["events"].get<int64_t>(), events * 9 / 10);
  EXPECT_GT(sd["lanelets"].get<int>(), 0) << "the readable part of the drive is mapped";
  EXPECT_TRUE(fs::exists(dir.str("damaged/map.osm")));

  // Not an LCM log: exit 2, a message that says so, no map written.
  std::string noise(200000, '\0');
  for (auto& ch : noise) ch = static_cast<char>(rng() & 0x7f);
  writeBytes(dir.str("noise.lcmlog"), noise);
  const auto n = offline(dir.str("noise.lcmlog"), dir.str("noise"));
  EXPECT_EQ(n.exit_code, 2) << n.output;
  EXPECT_NE(n.output.find("not an LCM log, or no whole event in it"), std::string::npos) << n.output;
  EXPECT_FALSE(fs::exists(dir.str("noise/map.osm")));
  EXPECT_FALSE(fs::exists(dir.str("noise/summary.json")));

  // The segmenter's log mode on the same non-log: exit 2, says why, and leaves no output behind
  // (neither the output nor its .partial), where it used to leave an empty log. A log file already
  // at the output path is not replaced by a failed run.
  const auto segment = [&](const std::string& out) {
    return lt::runCommand(lt::binPath("lanemap-segmenter") + " --config config/segmenter.yaml" +
                          " --lcm-url memq:// --log-in " + dir.str("noise.lcmlog") + " --log-out " + out);
  };
  const auto sn = segment(dir.str("noise-seg.lcmlog"));
  EXPECT_EQ(sn.exit_code, 2) << sn.output;
  EXPECT_NE(sn.output.find("not an LCM log, or no whole event in it"), std::string::npos) << sn.output;
  EXPECT_FALSE(fs::exists(dir.str("noise-seg.lcmlog")));
  EXPECT_FALSE(fs::exists(dir.str("noise-seg.lcmlog.partial")));
  writeBytes(dir.str("earlier-seg.lcmlog"), "an earlier output");
  const auto se = segment(dir.str("earlier-seg.lcmlog"));
  EXPECT_EQ(se.exit_code, 2) << se.output;
  EXPECT_EQ(readFile(dir.str("earlier-seg.lcmlog")), "an earlier output");
  EXPECT_FALSE(fs::exists(dir.str("earlier-seg.lcmlog.partial")));
}

}  // namespace
