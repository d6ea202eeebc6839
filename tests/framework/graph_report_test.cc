// processes/framework/graph_report.h on constructed recordings: the drive window from POSE, CPU
// share over the drive only, latency of the last STATUS with samples, restarts, drop counters and
// hand-over losses against the drive log, and when the map was complete.
#include "lanemap/lane_map_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "lanemap/status_t.hpp"
#include "processes/framework/graph_report.h"
#include "processes/framework/lcm_log_writer.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace lanemap;

constexpr int64_t kT0 = 1767225600000000;  // the drive's first POSE
constexpr int64_t kS = 1000000;

class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : log_(path) {}
  void raw(const std::string& channel, int64_t t, std::vector<uint8_t> data = {0}) {
    log_.write(channel, t, data.data(), data.size());
  }
  template <typename T>
  void message(const std::string& channel, int64_t t, const T& msg) {
    log_.message(channel, t, msg);
  }
  void reached(int64_t t, int64_t road) {
    road_event_t e{};
    e.utime = t;
    e.type = road_event_t::TYPE_REACHED_INTERSECTION;
    e.road_id = road;
    message("ROAD_EVENT", t, e);
  }
  void laneMap(int64_t t, int64_t road) {
    lane_map_t m{};
    m.utime = t;
    m.kind = lane_map_t::KIND_ROAD;
    m.id = road;
    message("LANE_MAP", t, m);
  }
  void status(int64_t t, const std::string& process, int32_t pid, double cpu, double p50, double p99,
              const std::map<std::string, int64_t>& counters, const std::string& state = "running") {
    status_t s;
    s.utime = t;
    s.process = process;
    s.host = "car";
    s.pid = pid;
    s.state = state;
    for (const auto& [k, v] : counters) {
      s.counter_names.push_back(k);
      s.counter_values.push_back(v);
    }
    s.num_counters = static_cast<int32_t>(counters.size());
    s.latency_p50_ms = p50;
    s.latency_p99_ms = p99;
    s.cpu_fraction = cpu;
    message("STATUS", t, s);
  }

 private:
  LcmLogWriter log_;
};

TEST(GraphReport, FiguresFromTheRecording) {
  lanemap::testing::TempDir dir("graph-report");
  {
    // The played drive: 101 poses, 10 truth frames, 20 sweeps.
    LogWriter drive(dir.str("drive.lcmlog"));
    for (int i = 0; i <= 100; ++i) drive.raw("POSE", kT0 + i * 100000);
    for (int i = 0; i < 10; ++i) drive.raw("SEMANTIC_FRONT_TRUTH", kT0 + i * kS);
    for (int i = 0; i < 20; ++i) drive.raw("LIDAR_PACKETS", kT0 + i * kS / 2);
  }
  {
    LogWriter rec(dir.str("graph.lcmlog"));
    const double nan = std::nan("");
    // Before the drive: start-up CPU that must not count, no latency yet.
    rec.status(kT0 - kS / 2, "bev_builder", 10, 0.95, nan, nan, {{"frames_received", 0}});
    for (int i = 0; i <= 100; ++i) rec.raw("POSE", kT0 + i * 100000);  // drive: 10 s
    // During the drive (STATUS at +2 s .. +10 s cover it).
    for (int s = 2; s <= 10; s += 2) {
      rec.status(kT0 + s * kS, "bev_builder", 10, s == 4 ? 0.50 : 0.20, 20.0 + s, s == 6 ? 90.0 : 40.0, {{"frames_received", s}});
      rec.status(kT0 + s * kS, "segmenter", s < 6 ? 20 : 21, 0.01, 0.2, 1.0, {{"truth_received", s}});
    }
    rec.reached(kT0 + 5 * kS, 7);
    rec.laneMap(kT0 + 6 * kS, 7);
    rec.reached(kT0 + 8 * kS + kS / 2, 5);
    rec.raw("BEV_ROAD", kT0 + 9 * kS);
    rec.reached(kT0 + 9 * kS + kS / 2, 9);  // never mapped
    rec.laneMap(kT0 + 12 * kS + kS / 2, 5);  // 2.5 s after the last POSE (kT0 + 10 s)
    // After the drive: the final counters; idle CPU that must not count either.
    rec.status(kT0 + 14 * kS, "bev_builder", 10, 0.0, 21.0, 41.0,
               {{"frames_received", 9}, {"frames_projected", 8}, {"frames_late", 1}, {"frames_queue_full", 0},
                {"poses_received", 101}, {"sweeps_received", 19}, {"sweeps_replaced", 3}, {"roads_written", 1}});
    rec.status(kT0 + 14 * kS, "segmenter", 21, 0.0, 0.3, 2.0, {{"truth_received", 10}, {"labels_published", 10}});
    rec.status(kT0 + 14 * kS, "lane_mapper", 30, 0.0, 150.0, 150.0, {{"bev_roads_received", 1}, {"roads_mapped", 1}});
  }
  const GraphReport r = readGraphReport(dir.str("graph.lcmlog"), dir.str("drive.lcmlog"), "SEMANTIC_FRONT");
  EXPECT_EQ(r.poses_recorded, 101);
  EXPECT_NEAR(r.driveSeconds(), 10.0, 1e-9);
  EXPECT_NEAR(r.mapCompleteAfterS(), 2.5, 1e-9);
  EXPECT_EQ(r.published.at("POSE"), 101);
  EXPECT_EQ(r.lane_maps, 2);
  ASSERT_EQ(r.road_to_map_s.size(), 3u);
  EXPECT_EQ(r.road_to_map_s[0].first, 7);
  EXPECT_NEAR(r.road_to_map_s[0].second, 1.0, 1e-9);
  EXPECT_EQ(r.road_to_map_s[1].first, 5);
  EXPECT_NEAR(r.road_to_map_s[1].second, 4.0, 1e-9);
  EXPECT_EQ(r.road_to_map_s[2].first, 9);
  EXPECT_TRUE(std::isnan(r.road_to_map_s[2].second));

  const ProcessHealth* bev = r.process("bev_builder");
  ASSERT_NE(bev, nullptr);
  EXPECT_NEAR(bev->cpu_mean, (0.2 + 0.5 + 0.2 + 0.2 + 0.2) / 5, 1e-9);  // drive STATUS only
  EXPECT_NEAR(bev->cpu_max, 0.5, 1e-9);
  EXPECT_NEAR(bev->latency_p50_ms, 21.0, 1e-9);  // the last STATUS with samples
  EXPECT_NEAR(bev->latency_p99_ms, 41.0, 1e-9);
  EXPECT_NEAR(bev->latency_p99_worst_ms, 90.0, 1e-9);
  EXPECT_EQ(bev->counter("frames_projected"), 8);
  EXPECT_EQ(bev->counter("no_such_counter"), -1);
  EXPECT_EQ(bev->pids.size(), 1u);
  EXPECT_EQ(r.process("segmenter")->pids.size(), 2u);  // restarted once

  std::map<std::string, int64_t> frame;
  for (const auto& l : r.frameLosses()) frame[l.what] = l.count;
  EXPECT_EQ(frame.at("bev_builder frames_late"), 1);
  EXPECT_EQ(frame.at("bev_builder frames_queue_full"), 0);
  EXPECT_EQ(frame.at("SEMANTIC_FRONT_TRUTH player -> segmenter"), 0);
  EXPECT_EQ(frame.at("SEMANTIC_FRONT segmenter -> bev_builder"), 1);  // 10 published, 9 received
  EXPECT_EQ(frame.count("segmenter frames_dropped"), 0u) << "the oracle has no frame queue";
  EXPECT_EQ(r.framesLost(), 2);
  std::map<std::string, int64_t> other;
  for (const auto& l : r.otherLosses()) other[l.what] = l.count;
  EXPECT_EQ(other.at("POSE player -> bev_builder"), 0);
  EXPECT_EQ(other.at("LIDAR_PACKETS player -> bev_builder"), 1);
  EXPECT_EQ(other.at("bev_builder sweeps_replaced"), 3);
  EXPECT_EQ(other.at("BEV_ROAD bev_builder -> lane_mapper"), 0);

  std::ostringstream text;
  printGraphReport(r, text);
  EXPECT_NE(text.str().find("2 frame(s) dropped or lost"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("map complete 2.5 s after the drive's end"), std::string::npos) << text.str();
}

TEST(GraphReport, NoFrameDroppedAndNoMap) {
  lanemap::testing::TempDir dir("graph-report");
  {
    LogWriter rec(dir.str("graph.lcmlog"));
    rec.status(kT0, "segmenter", 1, 0.3, 50.0, 90.0,
               {{"frames_received", 5}, {"frames_dropped", 0}, {"frames_segmented", 5}, {"labels_published", 5}});
    rec.status(kT0, "bev_builder", 2, 0.2, 20.0, 30.0, {{"frames_received", 5}, {"frames_projected", 5}});
  }
  const GraphReport r = readGraphReport(dir.str("graph.lcmlog"));
  EXPECT_EQ(r.framesLost(), 0);
  EXPECT_TRUE(std::isnan(r.mapCompleteAfterS()));
  EXPECT_NEAR(r.process("segmenter")->cpu_mean, 0.3, 1e-9);  // no POSE: every STATUS counts
  std::ostringstream text;
  printGraphReport(r, text);
  EXPECT_NE(text.str().find("no frame dropped"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("camera-to-BEV (segmenter + bev_builder, percentiles added): p50 70.0 ms, p99 120.0 ms"),
            std::string::npos)
      << text.str();
  EXPECT_THROW(readGraphReport(dir.str("missing.lcmlog")), std::runtime_error);
}

}  // namespace
