// Coverage of a city by a map store (issue 14, core/mapping/coverage.h, lanemap-coverage): a store
// made by hand over the 63 directed roads of the replay drive's West Oakland blocks: one road
// mapped from two traversals (two lanes, confidence 0.8 and 0.6), one partial to 25 m, one only
// driven, one whose lanes file is garbage, the rest never driven. The states, traversals, lanes,
// confidence and the mapped share come out as made; the plan for the next drive is a connected
// route from its start, within its time, that covers mostly new road and none of what is mapped
// twice, with no U-turn; the tool writes the same figures as JSON, GeoJSON, PNG and GPX, says
// which file it could not read (exit 3), and lanemap-sim takes its route.
#include "core/mapping/coverage.h"

#include "core/bev/bev_grid.h"
#include "core/bev/bev_store.h"
#include "core/config/map_config.h"
#include "core/io/lanelet2.h"
#include "core/osm/osm_data.h"
#include "tests/common/read_file.h"
#include "tests/common/sim_drive.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace lanemap::mapping {
namespace {

namespace fs = std::filesystem;

const std::string kOsm = std::string(LANEMAP_SOURCE_DIR) + "/tests/replay/roads.osm";

skeleton::Skeleton cityOf() {
  return skeleton::Skeleton::build(osm::readOsm(kOsm),
                                   config::MapConfig::fromYamlFile(std::string(LANEMAP_SOURCE_DIR) + "/config/map.yaml").skeleton);
}

// Lanes of `road`: straight from its first to its last point, `n` side by side.
map::LaneMap lanesOf(const skeleton::AtomicRoad& road, const skeleton::Skeleton& sk, const std::vector<double>& confidence,
                     std::optional<double> partial_station = std::nullopt) {
  map::LaneMap m;
  m.origin_lat = sk.frame().origin().lat;
  m.origin_lon = sk.frame().origin().lon;
  const Eigen::Vector2d a = road.polyline.front(), b = road.polyline.back(), d = (b - a).normalized(), n(-d.y(), d.x());
  int64_t id = (road.id + 1) * 100000;
  for (size_t k = 0; k < confidence.size(); ++k) {
    const double off = -3.5 * static_cast<double>(k) - 1.75;  // lane 0 next to the centre of the street
    const auto at = [&](const Eigen::Vector2d& p, double o) { return Eigen::Vector3d((p + o * n).x(), (p + o * n).y(), 0.0); };
    map::LineString left{++id, map::LineType::kDashed, {at(a, off + 1.75), at(b, off + 1.75)}};
    map::LineString right{++id, map::LineType::kSolid, {at(a, off - 1.75), at(b, off - 1.75)}};
    map::Lanelet ll;
    ll.id = ++id;
    ll.road_id = road.id;
    ll.from_node = road.from;
    ll.to_node = road.to;
    ll.index_from_left = static_cast<int>(k);
    ll.left_id = left.id;
    ll.right_id = right.id;
    ll.centre = {at(a, off), at(b, off)};
    ll.confidence = confidence[k];
    if (partial_station) ll.partial = map::PartialRoad{*partial_station, road.length};
    m.lines.push_back(left);
    m.lines.push_back(right);
    m.lanelets.push_back(ll);
  }
  return m;
}

bev::BevGrid gridOf(int frames) {
  bev::BevGrid g;
  g.add({1, 1}, bev::Layer::kDrivable, 3);
  for (int i = 0; i < frames; ++i) g.addFrame();
  return g;
}

struct Store {
  lanemap::testing::TempDir dir{"coverage"};
  int64_t mapped = -1, partial = -1, driven = -1, garbage = -1;
};

void makeStore(const skeleton::Skeleton& sk, Store& s) {
  const std::string store = s.dir.str();
  fs::create_directories(store + "/bev/partial");
  fs::create_directories(store + "/lanes");
  const auto& roads = sk.roads();
  ASSERT_GE(roads.size(), 10u);
  s.mapped = roads[2].id;
  s.partial = roads[5].id;
  s.driven = roads[7].id;
  s.garbage = roads[9].id;
  bev::BevGrid two = gridOf(30);
  bev::mergeGrid(gridOf(20), two);  // a second traversal merged in
  two.save(bev::roadGridPath(store, s.mapped));
  io::writeLanelet2(lanesOf(*sk.road(s.mapped), sk, {0.8, 0.6}), store + "/lanes/road_" + std::to_string(s.mapped) + ".osm");
  gridOf(12).save(bev::partialGridPath(store, s.partial));
  io::writeLanelet2(lanesOf(*sk.road(s.partial), sk, {0.5}, 25.0), store + "/lanes/road_" + std::to_string(s.partial) + ".osm");
  gridOf(40).save(bev::roadGridPath(store, s.driven));
  std::ofstream(store + "/lanes/road_" + std::to_string(s.garbage) + ".osm") << "<osm><way id=";
}

TEST(Coverage, EveryDirectedRoadSaysWhatTheStoreHoldsOfIt) {
  const auto sk = cityOf();
  Store s;
  makeStore(sk, s);
  const CityCoverage cov = cityCoverage(sk, s.dir.str());
  ASSERT_EQ(cov.roads.size(), sk.roads().size());
  double total = 0.0;
  for (const auto& r : sk.roads()) total += r.length;
  EXPECT_NEAR(cov.total_m, total, 1e-9);
  const auto of = [&](int64_t id) -> const RoadCoverage& {
    for (const auto& c : cov.roads) {
      if (c.road_id == id) return c;
    }
    throw std::runtime_error("no road " + std::to_string(id));
  };
  const RoadCoverage& m = of(s.mapped);
  EXPECT_EQ(m.state, RoadState::kMapped);
  EXPECT_EQ(m.traversals, 2);
  EXPECT_EQ(m.frames, 50);
  EXPECT_EQ(m.lanes, 2);
  ASSERT_TRUE(m.confidence.has_value());
  EXPECT_NEAR(*m.confidence, 0.7, 1e-3);
  EXPECT_DOUBLE_EQ(m.mapped_m, sk.road(s.mapped)->length);
  const RoadCoverage& p = of(s.partial);
  EXPECT_EQ(p.state, RoadState::kPartial);
  EXPECT_EQ(p.traversals, 1);
  EXPECT_EQ(p.lanes, 1);
  EXPECT_NEAR(p.mapped_m, std::min(25.0, sk.road(s.partial)->length), 1e-3);
  const RoadCoverage& d = of(s.driven);
  EXPECT_EQ(d.state, RoadState::kDriven);
  EXPECT_EQ(d.traversals, 1);
  EXPECT_EQ(d.mapped_m, 0.0);
  const RoadCoverage& g = of(s.garbage);
  EXPECT_EQ(g.state, RoadState::kNeverDriven);
  ASSERT_EQ(g.problems.size(), 1u);
  EXPECT_EQ(cov.count(RoadState::kMapped), 1);
  EXPECT_EQ(cov.count(RoadState::kPartial), 1);
  EXPECT_EQ(cov.count(RoadState::kDriven), 1);
  EXPECT_EQ(cov.count(RoadState::kNeverDriven), static_cast<int>(sk.roads().size()) - 3);
  EXPECT_NEAR(cov.mapped_m, m.mapped_m + p.mapped_m, 1e-9);
  EXPECT_NEAR(cov.share(), (m.mapped_m + p.mapped_m) / total, 1e-12);
  EXPECT_EQ(cityCoverage(sk, s.dir.str("no-such-store")).mapped_m, 0.0);
}

// lanemap-offline's --out has no lanes/ folder: its map.osm is read by the lanelets' road ids.
TEST(Coverage, AnOfflineOutputFolderIsReadFromItsWholeMap) {
  const auto sk = cityOf();
  lanemap::testing::TempDir dir("coverage-offline");
  const auto& a = sk.roads()[3];
  const auto& b = sk.roads()[4];
  map::LaneMap m = lanesOf(a, sk, {0.9, 0.7, 0.5});
  const map::LaneMap mb = lanesOf(b, sk, {0.4}, 10.0);
  m.lines.insert(m.lines.end(), mb.lines.begin(), mb.lines.end());
  m.lanelets.insert(m.lanelets.end(), mb.lanelets.begin(), mb.lanelets.end());
  io::writeLanelet2(m, dir.str("map.osm"));
  fs::create_directories(dir.str("bev"));
  gridOf(5).save(bev::roadGridPath(dir.str(), a.id));
  const CityCoverage cov = cityCoverage(sk, dir.str());
  EXPECT_TRUE(cov.problems.empty());
  EXPECT_EQ(cov.count(RoadState::kMapped), 1);
  EXPECT_EQ(cov.count(RoadState::kPartial), 1);
  for (const auto& c : cov.roads) {
    if (c.road_id == a.id) {
      EXPECT_EQ(c.lanes, 3);
      EXPECT_EQ(c.traversals, 1);
      EXPECT_NEAR(*c.confidence, 0.7, 1e-3);
    }
    if (c.road_id == b.id) {
      EXPECT_EQ(c.state, RoadState::kPartial);
      EXPECT_NEAR(c.mapped_m, std::min(10.0, b.length), 1e-3);
    }
  }
  EXPECT_NEAR(cov.mapped_m, a.length + std::min(10.0, b.length), 1e-3);
  std::ofstream(dir.str("map.osm")) << "not a map";
  EXPECT_EQ(cityCoverage(sk, dir.str()).problems.size(), 1u) << "an unreadable whole map is said";
}

TEST(Coverage, ThePlanIsAConnectedRouteThatCoversMostlyNewRoad) {
  const auto sk = cityOf();
  Store s;
  makeStore(sk, s);
  const CityCoverage cov = cityCoverage(sk, s.dir.str());
  const int64_t start = sk.road(s.mapped)->from;
  const double seconds = 150.0, speed = 8.0;
  const CoveragePlan plan = planCoverage(sk, cov, start, seconds, speed);
  ASSERT_GE(plan.roads.size(), 3u);
  ASSERT_EQ(plan.intersections.size(), plan.roads.size() + 1);
  EXPECT_EQ(plan.intersections.front(), start);
  double driven = 0.0, fresh = 0.0;
  std::set<int64_t> seen;
  for (size_t i = 0; i < plan.roads.size(); ++i) {
    const auto* r = sk.road(plan.roads[i]);
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->from, plan.intersections[i]) << "road " << i << " starts where the last ended";
    EXPECT_EQ(r->to, plan.intersections[i + 1]);
    if (i > 0) {
      EXPECT_NE(sk.road(plan.roads[i - 1])->reverse_id, r->id) << "no U-turn at road " << i;
    }
    driven += r->length;
    if (seen.insert(r->id).second && r->id != s.mapped) fresh += r->id == s.partial ? r->length - std::min(25.0, r->length) : r->length;
  }
  // The last road may be driven in part (the time ran out on it): the rest are whole.
  const double last_s = sk.road(plan.roads.back())->length / speed;
  EXPECT_LE(plan.seconds, driven / speed + 1e-6);
  EXPECT_GE(plan.seconds, driven / speed - last_s - 1e-6);
  EXPECT_LE(plan.seconds, seconds + 1e-9);
  EXPECT_LE(plan.new_m, fresh + 1e-6) << "new length: each unmapped road once, the mapped one never";
  EXPECT_GE(plan.new_m, fresh - last_s * speed - 1e-6);
  std::printf("plan: %zu roads, %.0f m driven, %.0f m new\n", plan.roads.size(), driven, plan.new_m);
  EXPECT_GE(plan.new_m, 0.8 * driven) << "a city that is nearly all new: most of the drive is new road";
  EXPECT_THROW(planCoverage(sk, cov, -5, seconds), std::invalid_argument);

  // From a dead end whose one road is longer than 60 s of driving (1.3 km here): that road, as far
  // as the time goes.
  const skeleton::AtomicRoad* longest = nullptr;
  for (const auto& r : sk.roads()) {
    if (r.length > 60.0 * speed && sk.intersection(r.from)->outgoing.size() == 1 && (!longest || r.length > longest->length)) longest = &r;
  }
  ASSERT_NE(longest, nullptr);
  const CoveragePlan part = planCoverage(sk, cov, longest->from, 60.0, speed);
  ASSERT_EQ(part.roads.size(), 1u);
  EXPECT_EQ(part.roads[0], longest->id);
  EXPECT_NEAR(part.seconds, 60.0, 1e-9);
  EXPECT_NEAR(part.new_m, 60.0 * speed, 1e-6);

  // Everything mapped: nothing left to plan.
  CityCoverage all = cov;
  for (auto& c : all.roads) {
    c.state = RoadState::kMapped;
    c.mapped_m = c.length_m;
  }
  const CoveragePlan none = planCoverage(sk, all, start, seconds, speed);
  EXPECT_TRUE(none.roads.empty());
  EXPECT_EQ(none.new_m, 0.0);
}

// A hairpin onto another road (a heading change over 150 degrees, no road's reverse) is a U-turn the
// simulator's world and the mapper do not connect: the plan drives round instead. This city has one
// (a one-way secondary road into a junction, and an unclassified road leaving it nearly back).
TEST(Coverage, ThePlanMakesNoHairpinTurn) {
  const auto sk = cityOf();
  const auto headingChangeDeg = [&](const skeleton::AtomicRoad& a, const skeleton::AtomicRoad& d) {
    const Eigen::Vector2d tin = sk.pointAt(a, a.s_end) - sk.pointAt(a, std::max(0.0, a.s_end - 15.0));
    const Eigen::Vector2d tout = sk.pointAt(d, std::min(d.length, d.s_begin + 15.0)) - sk.pointAt(d, d.s_begin);
    return std::abs(std::atan2(tin.x() * tout.y() - tin.y() * tout.x(), tin.dot(tout))) * 180.0 / M_PI;
  };
  std::vector<std::pair<const skeleton::AtomicRoad*, const skeleton::AtomicRoad*>> hairpins;
  for (const auto& a : sk.roads()) {
    for (const int64_t id : sk.intersection(a.to)->outgoing) {
      const auto* d = sk.road(id);
      if (d->id != a.reverse_id && headingChangeDeg(a, *d) > 150.0) hairpins.push_back({&a, d});
    }
  }
  ASSERT_FALSE(hairpins.empty()) << "the city has a hairpin to test on";
  for (const auto& [a, d] : hairpins) {
    // Everything mapped but the road the hairpin leads onto; the drive starts on the road into it.
    Store s;
    makeStore(sk, s);
    CityCoverage cov = cityCoverage(sk, s.dir.str());
    for (auto& c : cov.roads) {
      c.state = c.road_id == d->id ? RoadState::kNeverDriven : RoadState::kMapped;
      c.mapped_m = c.road_id == d->id ? 0.0 : c.length_m;
    }
    const CoveragePlan plan = planCoverage(sk, cov, a->from, 600.0, 8.0);
    ASSERT_FALSE(plan.roads.empty());
    EXPECT_NE(std::find(plan.roads.begin(), plan.roads.end(), d->id), plan.roads.end()) << "road " << d->id << " is reached round";
    for (size_t i = 1; i < plan.roads.size(); ++i) {
      const auto* p = sk.road(plan.roads[i - 1]);
      const auto* r = sk.road(plan.roads[i]);
      EXPECT_LE(headingChangeDeg(*p, *r), 150.0) << "road " << p->id << " -> " << r->id;
      EXPECT_NE(p->reverse_id, r->id);
    }
  }
}

// A campaign's next drive starts out of a dead end while a road leaving one into the network is
// still to cover: no U-turns, so only a drive's first road covers such a road (this city has 16
// dead ends, and a piece of road between two of them). Then at any road still to cover.
TEST(Coverage, ADriveStartsOnARoadOutOfADeadEndWhileOneIsStillToCover) {
  const auto sk = cityOf();
  Store s;
  makeStore(sk, s);
  CityCoverage cov = cityCoverage(sk, s.dir.str());
  const auto deadEnd = [&](int64_t node) { return sk.intersection(node)->dead_end; };
  std::set<int64_t> dead_end_starts, starts;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const int64_t at = coverageStart(sk, cov, seed);
    EXPECT_EQ(at, coverageStart(sk, cov, seed)) << "the same seed, the same start";
    ASSERT_NE(sk.intersection(at), nullptr);
    EXPECT_TRUE(deadEnd(at)) << "seed " << seed << ": intersection " << at << " is no dead end";
    const auto* road = sk.road(sk.intersection(at)->outgoing.at(0));
    EXPECT_FALSE(deadEnd(road->to)) << "seed " << seed << ": road " << road->id << " leads into another dead end: the drive would end at once";
    dead_end_starts.insert(at);
  }
  EXPECT_GE(dead_end_starts.size(), 3u) << "the seed chooses among the dead ends";
  // Every road out of a dead end mapped: the start of a road still to cover, no dead end (its one
  // road out is mapped).
  size_t open = 0;
  for (auto& c : cov.roads) {
    if (deadEnd(c.from)) {
      c.state = RoadState::kMapped;
      c.mapped_m = c.length_m;
    } else if (c.state != RoadState::kMapped) {
      ++open;
    }
  }
  ASSERT_GT(open, 0u);
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const int64_t at = coverageStart(sk, cov, seed);
    EXPECT_FALSE(deadEnd(at));
    bool leaves_open = false;
    for (const auto& c : cov.roads) leaves_open |= c.from == at && c.state != RoadState::kMapped;
    EXPECT_TRUE(leaves_open) << "seed " << seed << ": no road still to cover leaves " << at;
    starts.insert(at);
  }
  EXPECT_GE(starts.size(), 3u);
  // All mapped: a road's start all the same (a drive again over mapped roads).
  for (auto& c : cov.roads) {
    c.state = RoadState::kMapped;
    c.mapped_m = c.length_m;
  }
  EXPECT_NE(sk.intersection(coverageStart(sk, cov, 5)), nullptr);
  EXPECT_THROW(coverageStart(sk, CityCoverage{}, 5), std::invalid_argument);
}

TEST(Coverage, TheToolWritesTheFiguresAndNamesWhatItCouldNotRead) {
  const auto sk = cityOf();
  Store s;
  makeStore(sk, s);
  const std::string out = s.dir.str("out");
  fs::create_directories(out);
  const std::string cmd = std::string(LANEMAP_BIN_DIR) + "/lanemap-coverage --store " + s.dir.str() + " --osm " + kOsm +
                          " --map-config " + LANEMAP_SOURCE_DIR + "/config/map.yaml --json " + out + "/c.json --geojson " + out +
                          "/c.geojson --png " + out + "/c.png --plan 150 --from " + std::to_string(sk.road(s.mapped)->from) +
                          " --gpx " + out + "/plan.gpx";
  const auto run = lanemap::testing::runCommand(cmd);
  const std::string& text = run.output;
  EXPECT_EQ(run.exit_code, 3) << text;
  EXPECT_NE(text.find("road " + std::to_string(s.garbage) + ":"), std::string::npos) << text;
  const CityCoverage cov = cityCoverage(sk, s.dir.str());
  std::ifstream jf(out + "/c.json");
  const auto j = nlohmann::json::parse(jf);
  EXPECT_NEAR(j["share"].get<double>(), cov.share(), 1e-4);
  EXPECT_EQ(j["roads"].size(), sk.roads().size());
  const CoveragePlan plan = planCoverage(sk, cov, sk.road(s.mapped)->from, 150.0);
  EXPECT_EQ(j["plan"]["roads"].get<std::vector<int64_t>>(), plan.roads);
  std::ifstream gf(out + "/c.geojson");
  const auto geo = nlohmann::json::parse(gf);
  ASSERT_EQ(geo["features"].size(), sk.roads().size());
  int mapped = 0;
  for (const auto& f : geo["features"]) mapped += f["properties"]["state"] == "mapped";
  EXPECT_EQ(mapped, 1);
  const cv::Mat png = cv::imread(out + "/c.png");
  EXPECT_GT(png.cols, 100);
  const std::string gpx = lanemap::testing::readFile(out + "/plan.gpx");
  size_t points = 0, expected = 0;
  for (size_t at = gpx.find("<trkpt"); at != std::string::npos; at = gpx.find("<trkpt", at + 1)) ++points;
  for (const int64_t id : plan.roads) expected += sk.road(id)->polyline.size();
  EXPECT_EQ(points, expected);

  // The simulator takes the route (it checks the whole route before it drives: 2 s are enough).
  std::string route;
  for (const int64_t id : plan.intersections) route += (route.empty() ? "" : ",") + std::to_string(id);
  const std::string sim = std::string(LANEMAP_BIN_DIR) + "/lanemap-sim -q --osm " + kOsm + " --out " + out + "/drive --seed 1" +
                          " --duration 2 --no-lidar --route " + route + " > " + out + "/sim.log 2>&1";
  EXPECT_EQ(std::system(sim.c_str()), 0) << route;
}

// A plan the tool cannot make is refused before anything is read, naming the option.
TEST(Coverage, TheToolRefusesPlanOptionsItCannotUse) {
  lanemap::testing::TempDir dir("coverage-cli");
  const std::string tool = std::string(LANEMAP_BIN_DIR) + "/lanemap-coverage --store " + dir.str() + " --osm " + kOsm;
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {" --plan -5 --from 1", "--plan: must be greater than 0, not -5"},
           {" --plan 0 --from 1", "--plan: must be greater than 0, not 0"},
           {" --plan 60 --from 1 --speed 0", "--speed: must be greater than 0, not 0"},
           {" --gpx " + dir.str("x.gpx"), "--gpx requires --plan"},
           {" --from 1", "--from requires --plan"},
           {" --plan 60", "--plan needs --from"}}) {
    const auto run = lanemap::testing::runCommand(tool + args);
    EXPECT_NE(run.exit_code, 0) << args;
    EXPECT_NE(run.output.find(message), std::string::npos) << args << ": " << run.output;
    EXPECT_EQ(run.output.find("directed roads"), std::string::npos) << args << ": went on to read the store: " << run.output;
  }
  EXPECT_FALSE(fs::exists(dir.str("x.gpx")));
}

}  // namespace
}  // namespace lanemap::mapping
