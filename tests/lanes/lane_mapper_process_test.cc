// lanemap-lane-mapper over LCM inside a private network namespace (tests/common/netns.h): a saved
// BEV grid of a real West Oakland road (painted with two lanes per direction) goes in on BEV_ROAD;
// LANE_MAP must carry our direction's two lanes at the painted centre lines, the store must hold
// the road's Lanelet2 file and the whole map; a bad grid is counted and the process goes on; a
// restarted process republishes the stored road without any input.
#include "core/bev/bev_grid.h"
#include "core/bev/bev_store.h"
#include "core/io/lanelet2.h"
#include "core/lanes/explorer.h"
#include "core/lanes/frenet.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "lanemap/bev_road_t.hpp"
#include "lanemap/lane_map_t.hpp"
#include "lanemap/pose_t.hpp"
#include "lanemap/road_event_t.hpp"
#include "lanemap/status_t.hpp"
#include "tests/common/child_process.h"
#include "tests/common/netns.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"
#include "tests/lanes/synthetic_bev.h"
#include "tests/common/status.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace {

using namespace lanemap;
namespace fs = std::filesystem;

const std::string kOsm = std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm";
const std::string kBinary = std::string(LANEMAP_BIN_DIR) + "/lanemap-lane-mapper";
const std::string kConfig = std::string(LANEMAP_SOURCE_DIR) + "/config/lane_mapper.yaml";

// LANE_MAP and the lane mapper's STATUS, as they arrive on `lcm`.
struct Collector {
  explicit Collector(lcm::LCM& lcm) {
    lcm.subscribe("LANE_MAP", &Collector::onMap, this)->setQueueCapacity(100);
    lcm.subscribe("STATUS", &Collector::onStatus, this)->setQueueCapacity(100);
  }
  Collector(const Collector&) = delete;
  Collector& operator=(const Collector&) = delete;
  std::vector<lane_map_t> maps;
  std::vector<status_t> status;
  void onMap(const lcm::ReceiveBuffer*, const std::string&, const lane_map_t* m) { maps.push_back(*m); }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const status_t* m) {
    if (m->process == "lane_mapper") status.push_back(*m);
  }
};

using lanemap::testing::statusCounter;

// The longest nearly straight two-way road (its polyline within 0.3 m of the chord).
const skeleton::AtomicRoad* straightRoad(const skeleton::Skeleton& sk) {
  const skeleton::AtomicRoad* best = nullptr;
  for (const auto& r : sk.roads()) {
    if (r.reverse_id < 0 || r.s_end - r.s_begin < 60.0) continue;
    const Eigen::Vector2d a = r.polyline.front(), u = (r.polyline.back() - a).normalized();
    double dev = 0;
    for (const auto& p : r.polyline) dev = std::max(dev, std::abs(u.x() * (p - a).y() - u.y() * (p - a).x()));
    if (dev < 0.3 && (!best || r.length > best->length)) best = &r;
  }
  return best;
}

// Two lanes per direction, 3.5 m, double solid line on the road's centre line.
lanes::testing::Layout twoByTwo(const skeleton::AtomicRoad& r) {
  using namespace lanes::testing;
  Layout L;
  L.ref.origin = r.polyline.front();
  const Eigen::Vector2d u = r.polyline.back() - r.polyline.front();
  L.ref.heading = std::atan2(u.y(), u.x());
  L.ref.length = u.norm();
  for (double side : {1.0, -1.0}) {
    L.lines.push_back({constant(side * 0.1), -1e9, 1e9, Line::kSolid, false});
    L.lines.push_back({constant(side * 3.6), -1e9, 1e9, Line::kDashed, true});
    L.lines.push_back({constant(side * 7.1), -1e9, 1e9, Line::kSolid, false});
    L.lines.push_back({constant(side * 7.6), -1e9, 1e9, Line::kCurb, false});
  }
  L.areas.push_back({constant(-7.6), constant(7.6)});
  return L;
}

// The BEV_ROAD the BEV builder sends when it closes `r` with its grid at `path`.
bev_road_t bevRoad(const skeleton::AtomicRoad& r, const std::string& path) {
  bev_road_t msg{};
  msg.road_id = r.id;
  msg.from_node = r.from;
  msg.to_node = r.to;
  msg.path = path;
  msg.resolution_m = 0.1;
  return msg;
}

bool waitFor(lcm::LCM& lcm, const std::function<bool()>& done, int seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (!done() && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(100);
  return done();
}

TEST(LaneMapperProcess, MapsARoadStoresItAndReloadsAfterRestart) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(kOsm));
  const skeleton::AtomicRoad* road = straightRoad(sk);
  ASSERT_NE(road, nullptr);
  const auto layout = twoByTwo(*road);
  lanemap::testing::TempDir tmp("lane-mapper");
  const std::string grid_path = tmp.str("bev_road.bin");
  lanes::testing::paint(layout).save(grid_path);
  const std::string store = tmp.str("store");
  const std::string url = lanemap::testing::testUdpmUrl(7683);

  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  Collector c(lcm);
  {
    lanemap::testing::ChildProcess proc({kBinary, "--config", kConfig, "--osm", kOsm, "--store", store, "--lcm-url", url});
    ASSERT_TRUE(proc.started());
    ASSERT_TRUE(waitFor(lcm, [&] { return !c.status.empty(); }, 20)) << "no STATUS from lanemap-lane-mapper";
    EXPECT_TRUE(c.maps.empty());  // an empty store: nothing to republish

    bev_road_t bad{};
    bad.road_id = road->id;
    bad.path = tmp.str("missing.bin");
    lcm.publish("BEV_ROAD", &bad);
    bev_road_t msg = bevRoad(*road, grid_path);
    msg.utime = 42;
    lcm.publish("BEV_ROAD", &msg);
    ASSERT_TRUE(waitFor(lcm, [&] { return !c.maps.empty(); }, 30)) << "no LANE_MAP";
    ASSERT_TRUE(waitFor(lcm, [&] { return statusCounter(c.status.back(), "roads_mapped") == 1; }, 5));
    EXPECT_EQ(statusCounter(c.status.back(), "roads_failed"), 1);
    EXPECT_EQ(statusCounter(c.status.back(), "bev_roads_received"), 2);
    EXPECT_GE(proc.stop(), 0);
  }
  ASSERT_EQ(c.maps.size(), 1u);
  const lane_map_t first = c.maps[0];
  EXPECT_EQ(first.kind, +lane_map_t::KIND_ROAD);
  EXPECT_EQ(first.id, road->id);
  EXPECT_EQ(first.utime, 42);
  ASSERT_EQ(first.num_lanes, 2);
  // Our direction (right of the centre line): lanes at d = -1.85 and -5.35 m of the painted frame.
  for (const auto& lane : first.lanes) {
    const double truth = lane.index_from_left == 0 ? -1.85 : -5.35;
    double sq = 0;
    for (int i = 0; i < lane.centre.num_points; ++i) {
      const Eigen::Vector2d sd = layout.ref.toSD(Eigen::Vector2d(lane.centre.east[i], lane.centre.north[i]));
      sq += (sd.y() - truth) * (sd.y() - truth);
    }
    EXPECT_LT(std::sqrt(sq / lane.centre.num_points), 0.15) << "lane " << lane.index_from_left;
    EXPECT_EQ(lane.left_boundary.type, lane.index_from_left == 0 ? +polyline_t::TYPE_SOLID : +polyline_t::TYPE_DASHED);
    EXPECT_EQ(lane.right_boundary.type, lane.index_from_left == 0 ? +polyline_t::TYPE_DASHED : +polyline_t::TYPE_SOLID);
  }
  // The store: the road's file and the whole map, both readable Lanelet2.
  const std::string road_file = store + "/lanes/road_" + std::to_string(road->id) + ".osm";
  ASSERT_TRUE(fs::exists(road_file));
  EXPECT_EQ(first.map_path, store + "/lane_map.osm");
  const auto& o = sk.frame().origin();
  EXPECT_EQ(io::readLanelet2(first.map_path, o.lat, o.lon).lanelets.size(), 2u);

  // Restart: the stored road comes back without any BEV_ROAD.
  c.maps.clear();
  c.status.clear();
  {
    lanemap::testing::ChildProcess proc({kBinary, "--config", kConfig, "--osm", kOsm, "--store", store, "--lcm-url", url});
    ASSERT_TRUE(proc.started());
    // (a late STATUS of the first run may still arrive: wait for one of this run)
    EXPECT_TRUE(waitFor(lcm, [&] { return !c.maps.empty() && !c.status.empty() && statusCounter(c.status.back(), "roads_loaded") == 1; }, 20));
    EXPECT_GE(proc.stop(), 0);
  }
  ASSERT_EQ(c.maps.size(), 1u);
  const lane_map_t& again = c.maps[0];
  EXPECT_EQ(again.id, road->id);
  ASSERT_EQ(again.num_lanes, first.num_lanes);
  for (int k = 0; k < again.num_lanes; ++k) {
    const auto& a = again.lanes[k].centre;
    const auto& b = first.lanes[k].centre;
    ASSERT_EQ(a.num_points, b.num_points);
    for (int i = 0; i < a.num_points; ++i) {
      EXPECT_NEAR(a.east[i], b.east[i], 0.005);
      EXPECT_NEAR(a.north[i], b.north[i], 0.005);
    }
    EXPECT_EQ(again.lanes[k].left_boundary.type, first.lanes[k].left_boundary.type);
  }
}

// A partial road (issue 14: the BEV builder stored the road a drive ended on, driven to a station)
// is mapped as far as driven, its lanelets tagged partial in the store; once a drive closes the
// road (storeRoad merges the partial evidence) its BEV_ROAD maps it complete.
TEST(LaneMapperProcess, MapsAPartialRoadAsFarAsDrivenThenComplete) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(kOsm));
  const skeleton::AtomicRoad* road = straightRoad(sk);
  ASSERT_NE(road, nullptr);
  lanemap::testing::TempDir tmp("lane-mapper-partial");
  const std::string store = tmp.str("store");
  bev::RoadBev pass;
  pass.road_id = road->id;
  pass.grid = lanes::testing::paint(twoByTwo(*road));
  const double station = road->s_begin + 40.0;
  const auto stored = bev::storePartialRoad(store, pass, station, road->length);
  ASSERT_TRUE(stored.partial);
  const std::string url = lanemap::testing::testUdpmUrl(7684);
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  Collector c(lcm);
  const std::string road_file = store + "/lanes/road_" + std::to_string(road->id) + ".osm";
  const auto& o = sk.frame().origin();
  const lanes::FrenetFrame frame(road->polyline);
  auto furthest = [&](const map::LaneMap& m) {
    double s_max = 0;
    for (const auto& l : m.lanelets) {
      for (const auto& p : l.centre) s_max = std::max(s_max, frame.toFrenet(p.head<2>()).x());
    }
    return s_max;
  };
  lanemap::testing::ChildProcess proc({kBinary, "--config", kConfig, "--osm", kOsm, "--store", store, "--lcm-url", url});
  ASSERT_TRUE(proc.started());
  // On start it finds the partial road without lanes and maps it (catch-up); a BEV_ROAD as the
  // BEV builder sends it maps it again.
  ASSERT_TRUE(waitFor(lcm, [&] { return !c.status.empty() && statusCounter(c.status.back(), "roads_partial") >= 1; }, 30))
      << "the partial road was not mapped";
  bev_road_t msg{};
  msg.road_id = road->id;
  msg.path = stored.path;
  lcm.publish("BEV_ROAD", &msg);
  ASSERT_TRUE(waitFor(lcm, [&] { return statusCounter(c.status.back(), "roads_partial") >= 2; }, 30));
  {
    const auto m = io::readLanelet2(road_file, o.lat, o.lon);
    ASSERT_EQ(m.lanelets.size(), 2u);
    for (const auto& l : m.lanelets) {
      ASSERT_TRUE(l.partial.has_value()) << l.id;
      EXPECT_DOUBLE_EQ(l.partial->station_m, station);
      EXPECT_DOUBLE_EQ(l.partial->road_length_m, road->length);
      ASSERT_TRUE(l.confidence.has_value());
      EXPECT_GT(*l.confidence, 0.8) << "painted lanes, seen all along";
    }
    EXPECT_LT(furthest(m), station + 1.0) << "no lane past where the car stopped";
    EXPECT_GT(furthest(m), station - 3.0);
  }
  // A later drive closes the road: complete now.
  const auto complete = bev::storeRoad(store, pass);
  ASSERT_TRUE(complete.completed_partial);
  msg.path = complete.path;
  const int64_t mapped_before = statusCounter(c.status.back(), "roads_mapped");
  lcm.publish("BEV_ROAD", &msg);
  ASSERT_TRUE(waitFor(lcm, [&] { return statusCounter(c.status.back(), "roads_mapped") > mapped_before; }, 30));
  EXPECT_GE(proc.stop(), 0);
  const auto m = io::readLanelet2(road_file, o.lat, o.lon);
  ASSERT_EQ(m.lanelets.size(), 2u);
  for (const auto& l : m.lanelets) EXPECT_FALSE(l.partial.has_value()) << l.id;
  EXPECT_GT(furthest(m), road->s_end - 5.0) << "complete: the lanes reach the end intersection";
}

// export_interval_s > 0 (a city-sized store, issue 14): every road's file is written when it is
// mapped, lane_map.osm at most once per interval: here right after the first road, then not
// again while the process runs (a 600 s interval), and with every road when it stops.
TEST(LaneMapperProcess, ExportIntervalWritesTheWholeMapAtMostThatOftenAndAtStop) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(kOsm));
  const skeleton::AtomicRoad* road = straightRoad(sk);
  ASSERT_NE(road, nullptr);
  const skeleton::AtomicRoad* back = sk.road(road->reverse_id);
  ASSERT_NE(back, nullptr);
  lanemap::testing::TempDir tmp("lane-mapper-export");
  const std::string store = tmp.str("store");
  const std::string config = tmp.str("lane_mapper.yaml");
  {
    std::string yaml = lanemap::testing::readFile(kConfig);
    const std::string key = "export_interval_s: 0 ";
    const auto at = yaml.find(key);
    ASSERT_NE(at, std::string::npos) << "config/lane_mapper.yaml has no `" << key << "`";
    yaml.replace(at, key.size(), "export_interval_s: 600 ");
    std::ofstream(config) << yaml;
  }
  std::vector<std::string> grids;
  for (const auto* r : {road, back}) {
    grids.push_back(tmp.str("bev_" + std::to_string(r->id) + ".bin"));
    lanes::testing::paint(twoByTwo(*r)).save(grids.back());
  }
  const std::string url = lanemap::testing::testUdpmUrl(7694);
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  Collector c(lcm);
  const auto& o = sk.frame().origin();
  const std::string whole = store + "/lane_map.osm";
  const auto publish = [&](const skeleton::AtomicRoad& r, const std::string& grid) {
    const bev_road_t msg = bevRoad(r, grid);
    lcm.publish("BEV_ROAD", &msg);
  };
  {
    lanemap::testing::ChildProcess proc({kBinary, "--config", config, "--osm", kOsm, "--store", store, "--lcm-url", url});
    ASSERT_TRUE(proc.started());
    ASSERT_TRUE(waitFor(lcm, [&] { return !c.status.empty(); }, 20)) << "no STATUS from lanemap-lane-mapper";
    publish(*road, grids[0]);
    ASSERT_TRUE(waitFor(lcm, [&] { return statusCounter(c.status.back(), "map_exports") == 1; }, 30));
    EXPECT_EQ(io::readLanelet2(whole, o.lat, o.lon).lanelets.size(), 2u);  // the first road's two lanes
    publish(*back, grids[1]);
    publish(*road, grids[0]);  // driven again
    ASSERT_TRUE(waitFor(lcm, [&] { return statusCounter(c.status.back(), "roads_mapped") == 3; }, 60));
    ASSERT_TRUE(waitFor(lcm, [&] { return c.maps.size() == 3; }, 5));
    EXPECT_EQ(statusCounter(c.status.back(), "map_exports"), 1) << "lane_map.osm written again within the interval";
    EXPECT_TRUE(fs::exists(store + "/lanes/road_" + std::to_string(back->id) + ".osm"));
    EXPECT_EQ(io::readLanelet2(whole, o.lat, o.lon).lanelets.size(), 2u);
    EXPECT_GE(proc.stop(), 0);
  }
  // Stopped: the whole map holds both directions.
  const auto m = io::readLanelet2(whole, o.lat, o.lon);
  std::map<int64_t, int> lanes_of;
  for (const auto& ll : m.lanelets) {
    if (ll.kind == map::LaneletKind::kRoad) ++lanes_of[ll.road_id];
  }
  EXPECT_EQ(lanes_of[road->id], 2);
  EXPECT_EQ(lanes_of[back->id], 2);
}

// A short road (issue 16) whose BEV shows nothing drivable is mapped with no lane when it closes:
// the road before it was not mapped (the car turned into it) and the road after it is closed
// later. When the road after gets its lanes, the short road is mapped again and takes them
// (core/mapping/carried_lanes.h lanesLeadingOutOf): STATUS roads_mapped_again, its LANE_MAP
// again with the road after's two lanes at their offsets from the OSM line.
TEST(LaneMapperProcess, AShortRoadMappedWithNoLaneTakesTheLanesOfTheRoadAfterOnceItIsMapped) {
  // (Mapped first with the lanes of its own OSM way, which stand in until then.)
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(kOsm));
  const skeleton::AtomicRoad* after = straightRoad(sk);
  ASSERT_NE(after, nullptr);
  // The road leading straight into it (West Oakland's roads are long: the test's config takes any
  // road as short).
  const skeleton::AtomicRoad* link = nullptr;
  for (int64_t id : sk.intersection(after->from)->incoming) {
    const skeleton::AtomicRoad* r = sk.road(id);
    if (r->id == after->reverse_id || r->reverse_id < 0 || r->polyline.size() < 2) continue;
    const Eigen::Vector2d a = (r->polyline.back() - r->polyline[r->polyline.size() - 2]).normalized();
    const Eigen::Vector2d b = (after->polyline[1] - after->polyline.front()).normalized();
    if (a.dot(b) > std::cos(0.2)) link = r;
  }
  ASSERT_NE(link, nullptr) << "no road runs straight into road " << after->id;
  lanemap::testing::TempDir tmp("lane-mapper-carry");
  const std::string store = tmp.str("store");
  const std::string config = tmp.str("lane_mapper.yaml");
  {
    std::string yaml = lanemap::testing::readFile(kConfig);
    const std::string key = "carry_lanes_max_m: 15.0 ";
    const auto at = yaml.find(key);
    ASSERT_NE(at, std::string::npos) << "config/lane_mapper.yaml has no `" << key << "`";
    yaml.replace(at, key.size(), "carry_lanes_max_m: 100000 ");
    std::ofstream(config) << yaml;
  }
  // The grids, each written just before its BEV_ROAD (written into the store before the start,
  // the mapper would catch them up): the link's observed ground with nothing drivable, outside the
  // store (the mapper maps it again from the path its BEV_ROAD named), the road after's two lanes a
  // direction where the BEV builder stores it.
  const std::string link_grid = tmp.str("link.bev");
  bev::BevGrid empty;
  {
    const Eigen::Vector2d a = link->polyline.front(), b = link->polyline.back();
    for (double t = 0; t <= 1.0; t += 0.05 / (b - a).norm()) {
      const Eigen::Vector2d p = a + t * (b - a), n = Eigen::Vector2d(a.y() - b.y(), b.x() - a.x()).normalized();
      for (double d = -12.0; d <= 12.0; d += 0.05) empty.add(empty.cellOf(p + d * n), bev::Layer::kObserved, 4);
    }
  }
  const std::string after_grid = bev::roadGridPath(store, after->id);
  const auto layout = twoByTwo(*after);

  const std::string url = lanemap::testing::testUdpmUrl(7695);
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  Collector c(lcm);
  const auto mapsOf = [&](int64_t id) {
    std::vector<lane_map_t> out;
    for (const auto& m : c.maps) {
      if (m.id == id) out.push_back(m);
    }
    return out;
  };
  {
    lanemap::testing::ChildProcess proc({kBinary, "--config", config, "--osm", kOsm, "--store", store, "--lcm-url", url});
    ASSERT_TRUE(proc.started());
    ASSERT_TRUE(waitFor(lcm, [&] { return !c.status.empty(); }, 20)) << "no STATUS from lanemap-lane-mapper";
    empty.save(link_grid);
    const bev_road_t first = bevRoad(*link, link_grid);
    lcm.publish("BEV_ROAD", &first);
    ASSERT_TRUE(waitFor(lcm, [&] { return mapsOf(link->id).size() == 1; }, 30)) << "no LANE_MAP of the link";
    // Nothing drivable, nothing to carry yet: its own OSM way's lanes (two-way: right of its line,
    // the first 1.75 m from it), standing in until a road meeting it gets lanes.
    {
      const lane_map_t stand_in = mapsOf(link->id)[0];
      ASSERT_GE(stand_in.num_lanes, 1) << "no lane from the link's OSM way";
      const lanes::ExplorerOptions eo;
      const lanes::FrenetFrame frame(link->polyline, eo.frame_spacing_m, eo.frame_smoothing_m);
      for (const auto& lane : stand_in.lanes) {
        const double expected = -1.75 - 3.5 * lane.index_from_left;
        for (int i = 0; i < lane.centre.num_points; ++i) {
          const Eigen::Vector2d sd = frame.toFrenet(Eigen::Vector2d(lane.centre.east[i], lane.centre.north[i]));
          EXPECT_NEAR(sd.y(), expected, 0.05) << "lane " << lane.index_from_left << " point " << i;
        }
      }
    }
    fs::create_directories(fs::path(after_grid).parent_path());
    lanes::testing::paint(layout).save(after_grid);
    const bev_road_t second = bevRoad(*after, after_grid);
    lcm.publish("BEV_ROAD", &second);
    ASSERT_TRUE(waitFor(lcm, [&] { return mapsOf(link->id).size() == 2; }, 30)) << "the link was not mapped again";
    ASSERT_TRUE(waitFor(lcm, [&] { return statusCounter(c.status.back(), "roads_mapped") == 3; }, 5));
    EXPECT_EQ(statusCounter(c.status.back(), "roads_mapped_again"), 1);
    EXPECT_EQ(statusCounter(c.status.back(), "roads_lanes_from_osm_way"), 1);
    EXPECT_EQ(statusCounter(c.status.back(), "roads_lanes_carried"), 1);
    EXPECT_EQ(statusCounter(c.status.back(), "roads_failed", 0), 0);
    EXPECT_GE(proc.stop(), 0);
  }
  ASSERT_EQ(mapsOf(after->id).size(), 1u);
  ASSERT_EQ(mapsOf(after->id)[0].num_lanes, 2);
  const lane_map_t carried = mapsOf(link->id)[1];
  ASSERT_EQ(carried.num_lanes, 2);
  // Each carried lane at the road after's lane's offset (-1.85, -5.35 m right of the painted
  // line, which is the road after's OSM line) from the link's own OSM line.
  const lanes::ExplorerOptions eo;
  const lanes::FrenetFrame frame(link->polyline, eo.frame_spacing_m, eo.frame_smoothing_m);
  for (const auto& lane : carried.lanes) {
    const double truth = lane.index_from_left == 0 ? -1.85 : -5.35;
    for (int i = 0; i < lane.centre.num_points; ++i) {
      const Eigen::Vector2d sd = frame.toFrenet(Eigen::Vector2d(lane.centre.east[i], lane.centre.north[i]));
      EXPECT_NEAR(sd.y(), truth, 0.35) << "lane " << lane.index_from_left << " point " << i;
    }
  }
  // In the store: the link's file holds them.
  const auto& o = sk.frame().origin();
  EXPECT_EQ(io::readLanelet2(store + "/lanes/road_" + std::to_string(link->id) + ".osm", o.lat, o.lon).lanelets.size(), 2u);
}

// The car's path through a junction (core/tracking/passage_recorder.h): the lane mapper cuts it
// from POSE by the road tracker's ROAD_EVENT (reached the end of road A, entered road B from A),
// keeps it in the store (<store>/passages/) and reads it back after a restart (STATUS
// passages_recorded, passages_loaded). Events that do not follow on (B entered from another road)
// record nothing.
TEST(LaneMapperProcess, RecordsTheCarsPathThroughAJunctionAndKeepsItAcrossARestart) {
  if (!lanemap::testing::inPrivateNetns()) {
    ASSERT_EQ(lanemap::testing::rerunInPrivateNetns(), 0);
    return;
  }
  const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(kOsm));
  // Two roads meeting at an intersection, not each other's reverse.
  const skeleton::AtomicRoad *a = nullptr, *b = nullptr;
  for (const auto& r : sk.roads()) {
    for (const auto& q : sk.roads()) {
      if (!a && r.to == q.from && q.id != r.reverse_id && r.length > 40 && q.length > 40) {
        a = &r;
        b = &q;
      }
    }
  }
  ASSERT_TRUE(a && b);
  lanemap::testing::TempDir tmp("lane-mapper-passage");
  const std::string store = tmp.str("store");
  const std::string url = lanemap::testing::testUdpmUrl(7687);
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  Collector c(lcm);
  int64_t utime = 1000000;
  const auto pose = [&](const Eigen::Vector2d& p) {
    pose_t m{};
    m.utime = (utime += 40000);
    const auto ll = sk.frame().toWgs84(Eigen::Vector3d(p.x(), p.y(), 0.0));
    m.latitude = ll.lat;
    m.longitude = ll.lon;
    m.orientation[0] = 1.0;
    m.status = pose_t::STATUS_SIMULATED;
    lcm.publish("POSE", &m);
  };
  const auto event = [&](int8_t type, int64_t road, int64_t previous) {
    road_event_t e{};
    e.utime = utime;
    e.type = type;
    e.road_id = road;
    e.previous_road_id = previous;
    e.intersection_id = a->to;
    lcm.publish("ROAD_EVENT", &e);
  };
  // Along A's last 30 m to its end, then B's first 30 m: every 0.5 m.
  const auto drive = [&](int64_t previous_of_b) {
    for (double s = a->length - 30.0; s <= a->length; s += 0.5) {
      pose(sk.pointAt(*a, s));
      if (std::abs(s - a->s_end) < 0.25) event(road_event_t::TYPE_REACHED_INTERSECTION, a->id, -1);
    }
    for (double s = 0.0; s <= 30.0; s += 0.5) pose(sk.pointAt(*b, s));
    event(road_event_t::TYPE_ENTERED_ROAD, b->id, previous_of_b);
  };
  {
    lanemap::testing::ChildProcess proc({kBinary, "--config", kConfig, "--osm", kOsm, "--store", store, "--lcm-url", url});
    ASSERT_TRUE(proc.started());
    ASSERT_TRUE(waitFor(lcm, [&] { return !c.status.empty(); }, 20)) << "no STATUS from lanemap-lane-mapper";
    drive(/*previous_of_b=*/-7);  // entered from another road: nothing
    drive(a->id);
    ASSERT_TRUE(waitFor(lcm, [&] { return statusCounter(c.status.back(), "passages_recorded") == 1; }, 10));
    EXPECT_GE(proc.stop(), 0);
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(store + "/passages")) files.push_back(e.path());
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].filename().string(), "passage_" + std::to_string(a->id) + "_" + std::to_string(b->id) + "_0.json");
  const std::string text = lanemap::testing::readFile(files[0].string());
  EXPECT_NE(text.find("\"from_road\":" + std::to_string(a->id)), std::string::npos) << text.substr(0, 200);
  c.status.clear();
  {
    lanemap::testing::ChildProcess proc({kBinary, "--config", kConfig, "--osm", kOsm, "--store", store, "--lcm-url", url});
    ASSERT_TRUE(proc.started());
    EXPECT_TRUE(waitFor(lcm, [&] { return !c.status.empty() && statusCounter(c.status.back(), "passages_loaded") == 1; }, 20));
    EXPECT_GE(proc.stop(), 0);
  }
}

TEST(LaneMapperProcess, FailsClearlyWithoutAnOsmFile) {
  const auto r = lanemap::testing::runCommand(kBinary + " --config " + kConfig + " --osm /nonexistent.osm --store /tmp --lcm-url memq://");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("nonexistent.osm"), std::string::npos) << r.output;
}

}  // namespace
