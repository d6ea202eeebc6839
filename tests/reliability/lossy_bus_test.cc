// The graph behind a lossy bus (issue 18): lcm-logplayer plays the drive on one multicast group,
// lanemap-fault-relay republishes it on the graph's, dropping a share of the messages of every
// channel (POSE, the truth labels, LIDAR_PACKETS; seeded), and the graph (road tracker, BEV builder
// on the truth labels, lane mapper) maps it: lossless, 10 % and 30 % lost. At each the graph keeps
// running (no restart), says in STATUS what it lost (the relay: dropped per channel; the BEV
// builder: frames_missed from the frames' seq, frames_missed_pct) and maps the driven road, and
// the relay drops exactly what its log mode drops of the same log (so the run can be replayed
// offline). The lanes' precision and recall against the truth are printed, and at 10 % they are
// within 0.05 of the lossless run's (the criterion, per run).
// Everything runs in a private network namespace; ~85 s (three 18 s drives at real time).
//
// The second test replays the loss deterministically (log mode + lanemap-offline) for ten loss
// seeds: each gives lanes within 0.05 of the lossless run's P and R (the criterion, per run).
#include "core/eval/area.h"
#include "core/eval/evaluate.h"
#include "core/io/lanelet2.h"
#include "lanemap/status_t.hpp"
#include "tests/bev/bev_replay.h"
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/sim_drive.h"
#include "tests/common/status.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;
namespace lt = lanemap::testing;

constexpr const char* kGraphUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";
constexpr const char* kPlayerUrl = "udpm://239.255.76.68:7668?ttl=0&recv_buf_size=8388608";

// The counters of every process, as their last STATUS said.
struct Statuses {
  std::map<std::string, std::map<std::string, int64_t>> counters;
  std::set<std::string> restarted;  // a process seen with two pids
  std::map<std::string, int> pid;
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const lanemap::status_t* s) {
    auto& c = counters[s->process];
    for (const auto& [name, value] : lanemap::testing::statusCounters(*s)) c[name] = value;
    if (pid.count(s->process) && pid[s->process] != s->pid) restarted.insert(s->process);
    pid[s->process] = s->pid;
  }
  int64_t get(const std::string& process, const std::string& name) const {
    const auto p = counters.find(process);
    if (p == counters.end()) return -1;
    const auto it = p->second.find(name);
    return it == p->second.end() ? -1 : it->second;
  }
};

std::string launchFile(const std::string& dir) {
  const std::string path = dir + "/lossy.yaml";
  std::ofstream f(path);
  f << "name: lossy\n"
       "lcm_url: \"" << kGraphUrl << "\"\n"
       "workdir: " << LANEMAP_SOURCE_DIR << "\n"
       "vars: {drive: \"\", store: \"\", drop: \"0\", relay: \"\"}\n"
       "defaults: {restart: on-failure, restart_delay_s: 1.0, max_restart_delay_s: 10.0, stop_timeout_s: 10.0}\n"
       "hosts:\n  car: {description: one computer}\n"
       "processes:\n"
       "  - {name: relay, host: car, command: \"lanemap-fault-relay --from '" << kPlayerUrl << "' --drop ${drop} --seed 7 ${relay}\"}\n"
       "  - {name: road_tracker, host: car, command: \"lanemap-road-tracker --osm ${drive}/roads.osm\", config: config/road_tracker.yaml}\n"
       "  - {name: bev_builder, host: car, command: \"lanemap-bev-builder --osm ${drive}/roads.osm --store ${store} --semantic-channel "
       "SEMANTIC_FRONT_TRUTH\", config: config/bev_builder.yaml}\n"
       "  - {name: lane_mapper, host: car, command: \"lanemap-lane-mapper --osm ${drive}/roads.osm --store ${store}\", config: config/lane_mapper.yaml}\n"
       "  - {name: player, host: car, command: \"lanemap-wait-ready --timeout 60 road_tracker bev_builder lane_mapper fault_relay && exec "
       "lcm-logplayer --lcm-url '" << kPlayerUrl << "' ${drive}/drive.lcmlog\", restart: never, start_delay_s: 1.0, stop_launch_after_s: 8.0}\n";
  return path;
}

// What lanemap-fault-relay's log mode drops of the drive's log with the live relay's seed and
// rate: counter name -> value ("received:POSE", "dropped:POSE", ...).
std::map<std::string, int64_t> logModeCounters(const std::string& drive, const std::string& dir, double drop) {
  std::map<std::string, int64_t> c;
  const auto r = lt::runCommand(lt::binPath("lanemap-fault-relay") + " --log-in " + drive + "/drive.lcmlog --log-out " + dir +
                                "/filtered.lcmlog --drop " + std::to_string(drop) + " --seed 7");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::istringstream in(r.output);
  std::string name;
  int64_t value = 0;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    if (ls >> name >> value && ls.eof()) c[name] = value;
  }
  fs::remove(dir + "/filtered.lcmlog");
  return c;
}

// The drive's truth on the roads it drove to their end (the one it began on from where it began,
// as lanemap-eval --driven scores it; not the one it ended on), and the truth file's ENU origin.
struct DrivenTruth {
  lanemap::geo::LatLonAlt origin;
  lanemap::map::LaneMap driven;
};
DrivenTruth drivenTruth(const std::string& drive) {
  const auto origin = lanemap::eval::lanelet2Origin(drive + "/groundtruth.osm");
  const auto truth = lanemap::io::readLanelet2(drive + "/groundtruth.osm", origin.lat, origin.lon);
  auto area = lanemap::eval::drivenAreaFromScenario(drive + "/scenario.json", lanemap::geo::LocalFrame(origin));
  area.partial.clear();
  return {origin, lanemap::eval::restrictToDriven(truth, area)};
}

Statuses runGraph(const std::string& drive, const std::string& dir, double drop) {
  Statuses st;
  fs::create_directories(dir);
  lt::ChildProcess graph({lt::binPath("lanemap-launch"), launchFile(dir), "--all-hosts", "--status-interval", "0", "--set", "drive=" + drive,
                          "--set", "store=" + dir + "/store", "--set", "drop=" + std::to_string(drop), "--log-dir", dir + "/logs"});
  EXPECT_TRUE(graph.started());
  lcm::LCM lcm(kGraphUrl);
  EXPECT_TRUE(lcm.good());
  lcm.subscribe("STATUS", &Statuses::onStatus, &st);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(150);
  while (std::chrono::steady_clock::now() < deadline) {
    lcm.handleTimeout(50);
    if (graph.waitExit(std::chrono::milliseconds(5)) != -2) break;
  }
  EXPECT_EQ(graph.waitExit(std::chrono::seconds(30)), 0) << "the launch did not end well: see " << dir << "/logs";
  return st;
}

TEST(LossyBus, TenAndThirtyPercentLostAreCountedAndTheDrivenRoadIsStillMapped) {
  if (!lt::inPrivateNetns()) {
    ASSERT_EQ(lt::rerunInPrivateNetns(), 0);
    return;
  }
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed, lt::kBevDriveArgs);
  ASSERT_FALSE(drive.empty());
  const auto [origin, driven] = drivenTruth(drive);
  ASSERT_FALSE(driven.lanelets.empty());

  lt::TempDir out("lossy-bus");
  struct Run {
    double drop;
    Statuses st;
    lanemap::eval::EvalReport report;
  };
  std::vector<Run> runs;
  for (const double drop : {0.0, 0.1, 0.3}) {
    SCOPED_TRACE("drop " + std::to_string(drop));
    const std::string dir = out.str("drop-" + std::to_string(static_cast<int>(drop * 100)));
    Run r{drop, runGraph(drive, dir, drop), {}};
    EXPECT_TRUE(r.st.restarted.empty()) << "a process was restarted: see " << dir << "/logs";
    ASSERT_TRUE(fs::exists(dir + "/store/lane_map.osm")) << "no map: see " << dir << "/logs";
    const auto map = lanemap::io::readLanelet2(dir + "/store/lane_map.osm", origin.lat, origin.lon);
    r.report = lanemap::eval::evaluate(driven, map);
    const int64_t received = r.st.get("fault_relay", "received"), dropped = r.st.get("fault_relay", "dropped");
    std::printf("drop %.0f %%: relay received %lld, dropped %lld (%.1f %%); bev_builder frames_missed %lld (%lld %%), projected %lld;"
                " lanes P %.3f R %.3f RMS %.3f m (%zu lanes)\n",
                drop * 100, static_cast<long long>(received), static_cast<long long>(dropped),
                received > 0 ? 100.0 * dropped / received : 0.0, static_cast<long long>(r.st.get("bev_builder", "frames_missed")),
                static_cast<long long>(r.st.get("bev_builder", "frames_missed_pct")),
                static_cast<long long>(r.st.get("bev_builder", "frames_projected")), r.report.lane_precision.value(),
                r.report.lane_recall.value(), r.report.lane_rms_m, r.report.built_lanes.size());
    // What was lost is counted: by the relay, and by the BEV builder from the frames' seq.
    ASSERT_GT(received, 1000);
    EXPECT_NEAR(static_cast<double>(dropped) / received, drop, 0.03);
    // The BEV builder sees the lost frames in the camera's seq: as many as the relay dropped of
    // that channel but those before the first or after the last frame it got (a gap in seq is
    // all it sees), and says which share of the frames that is.
    const int64_t labels_dropped = std::max<int64_t>(0, r.st.get("fault_relay", "dropped:SEMANTIC_FRONT_TRUTH"));
    const int64_t missed = r.st.get("bev_builder", "frames_missed");
    EXPECT_LE(missed, labels_dropped);
    EXPECT_GE(missed, labels_dropped - 4) << "frames_missed " << missed << ", the relay dropped " << labels_dropped;
    if (drop == 0.0) { EXPECT_EQ(missed, 0); }
    if (drop > 0.2) { EXPECT_GE(r.st.get("bev_builder", "frames_missed_pct"), 15); }
    EXPECT_GE(r.st.get("lane_mapper", "roads_mapped"), 1) << "the graph maps what it can";
    // The live relay drops what its log mode drops of the same log with the same seed (one random
    // stream per channel): a lossy live run can be replayed offline, deterministically
    // (lanemap-fault-relay --log-in/--log-out, then lanemap-offline). Compared for each channel the
    // live relay received whole (the bus itself lost nothing of it).
    const auto offline = logModeCounters(drive, dir, drop);
    for (const char* ch : {"POSE", "SEMANTIC_FRONT_TRUTH", "LIDAR_PACKETS"}) {
      const std::string c = ch;
      ASSERT_TRUE(offline.count("received:" + c)) << c;
      if (r.st.get("fault_relay", "received:" + c) != offline.at("received:" + c)) {
        std::printf("  %s: the live relay received %lld of %lld (lost on the bus before it): not compared\n", ch,
                    static_cast<long long>(r.st.get("fault_relay", "received:" + c)), static_cast<long long>(offline.at("received:" + c)));
        continue;
      }
      EXPECT_EQ(std::max<int64_t>(0, r.st.get("fault_relay", "dropped:" + c)), offline.count("dropped:" + c) ? offline.at("dropped:" + c) : 0) << c;
    }
    runs.push_back(r);
  }
  const auto& lossless = runs[0].report;
  ASSERT_GT(lossless.lane_recall.total, 0u);
  EXPECT_EQ(lossless.lane_recall.value(), 1.0) << "the lossless run finds every lane of the driven road";
  // The criterion at 10 % on every channel, per run: P and R within 0.05 of the lossless
  // run's. Measured 2026-12-05 on this drive (2 true lanes, relay seed 7), twice alike: lossless
  // P 1 R 1, 10 % P 1 R 1, 30 % P 0.5 R 0.5. Until 2026-12-04 seed 7 took the 120 m lane with it at
  // 10 % (P 0.333 R 0.5: the lane explorer's chain through the lane's 3.5 m shift broke on the
  // frames and poses that seed drops; docs/robustness.md); the mapping changes of that day keep it.
  // The offline replay of the same drops (lanemap-fault-relay --log-in, lanemap-offline: the test
  // below) agrees. At 30 % what is held is that the graph maps the driven road and finds a lane.
  ASSERT_EQ(runs.size(), 3u);
  const Run& ten = runs[1];
  ASSERT_DOUBLE_EQ(ten.drop, 0.1);
  EXPECT_NEAR(ten.report.lane_precision.value(), lossless.lane_precision.value(), 0.05) << "10 % lost";
  EXPECT_NEAR(ten.report.lane_recall.value(), lossless.lane_recall.value(), 0.05) << "10 % lost";
  for (const Run& r : runs) {
    EXPECT_GE(r.report.lane_recall.value(), 0.5) << "drop " << r.drop;
    EXPECT_GT(r.report.lane_precision.hits, 0u) << "drop " << r.drop;
  }
}

}  // namespace

namespace {

// The drive's lanes mapped offline from `log` (lanemap-offline --oracle, as the live graph maps on
// the truth labels), scored on the driven roads.
lanemap::eval::EvalReport mapOffline(const std::string& drive, const std::string& log, const std::string& out,
                                     const lanemap::map::LaneMap& driven, const lanemap::geo::LatLonAlt& origin) {
  const auto r = lt::runCommand(lt::binPath("lanemap-offline") + " -q --oracle --log " + log + " --osm " + drive + "/roads.osm --out " + out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  if (r.exit_code != 0) return {};
  return lanemap::eval::evaluate(driven, lanemap::io::readLanelet2(out + "/map.osm", origin.lat, origin.lon));
}

// The loss replayed deterministically (the relay's log mode, then lanemap-offline) for ten loss
// seeds: what 10 % on every channel costs on this drive, not what one seed happens to cost.
TEST(LossyBus, TenPercentLostOverTenLossSeedsGivesTheLosslessLanes) {
  const std::string drive = lt::sharedSimDrive("osm/west-oakland.osm", lt::kBevDriveSeconds, lt::kBevDriveSeed, lt::kBevDriveArgs);
  ASSERT_FALSE(drive.empty());
  const auto [origin, driven] = drivenTruth(drive);
  ASSERT_FALSE(driven.lanelets.empty());
  lt::TempDir out("lossy-offline");
  const auto lossless = mapOffline(drive, drive + "/drive.lcmlog", out.str("lossless"), driven, origin);
  ASSERT_GT(lossless.lane_recall.total, 0u);
  std::printf("lossless: lanes P %.3f R %.3f (%zu built)\n", lossless.lane_precision.value(), lossless.lane_recall.value(),
              lossless.built_lanes.size());
  size_t p_hits = 0, built = 0, r_hits = 0, truth_lanes = 0, same = 0;
  for (int seed = 1; seed <= 10; ++seed) {
    const std::string log = out.str("lossy-" + std::to_string(seed) + ".lcmlog");
    const auto f = lt::runCommand(lt::binPath("lanemap-fault-relay") + " --log-in " + drive + "/drive.lcmlog --log-out " + log +
                                  " --drop 0.1 --seed " + std::to_string(seed));
    ASSERT_EQ(f.exit_code, 0) << f.output;
    const auto r = mapOffline(drive, log, out.str("map-" + std::to_string(seed)), driven, origin);
    std::printf("10 %% lost, loss seed %2d: lanes P %.3f R %.3f (%zu built)\n", seed, r.lane_precision.value(), r.lane_recall.value(),
                r.built_lanes.size());
    p_hits += r.lane_precision.hits;
    built += r.lane_precision.total;
    r_hits += r.lane_recall.hits;
    truth_lanes += r.lane_recall.total;
    same += std::abs(r.lane_precision.value() - lossless.lane_precision.value()) <= 0.05 &&
            std::abs(r.lane_recall.value() - lossless.lane_recall.value()) <= 0.05;
    // Whatever a seed costs, the road is mapped and one lane of it at least found.
    EXPECT_GE(r.lane_recall.value(), 0.5) << "loss seed " << seed;
  }
  std::printf("10 %% lost, pooled over 10 loss seeds: lanes P %.3f R %.3f (lossless P %.3f R %.3f); %zu of 10 seeds within 0.05 of them\n",
              built ? static_cast<double>(p_hits) / built : 0.0, static_cast<double>(r_hits) / truth_lanes,
              lossless.lane_precision.value(), lossless.lane_recall.value(), same);
  // The criterion, per run: every loss seed's P and R within 0.05 of the lossless run's.
  // Measured 2026-12-05: all 10 give the lossless lanes (P 0.667 R 1). Before the mapping changes of
  // 2026-12-04 (lanes on nothing dropped, lanes carried through short roads, centre lines recentred
  // between their bounds; which of them did it was not isolated) seed 7, the live test's, lost the
  // 120 m lane to the explorer at the lane's 3.5 m shift (docs/robustness.md): 9 of 10 then. A graph
  // that handled a lost pose or frame worse (skipped the frame, closed the road early or late)
  // costs seeds.
  EXPECT_EQ(same, 10u);
}

}  // namespace
