// restrictToMappedRoads / restrictToRoads / drivenRoadsFromScenario: the truth a drive could have mapped.
#include "core/eval/area.h"
#include "core/eval/evaluate.h"
#include "tests/eval/test_maps.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>

#include "tests/common/sim_drive.h"

namespace {

using lanemap::map::LaneletKind;
using lanemap::map::LaneMap;
using lanemap::testing::network;

std::set<std::pair<int64_t, int64_t>> roadsOf(const LaneMap& m) {
  std::set<std::pair<int64_t, int64_t>> out;
  for (const auto& l : m.lanelets) {
    if (l.kind == LaneletKind::kRoad) out.insert({l.from_node, l.to_node});
  }
  return out;
}

TEST(MappedArea, KeepsTheMappedRoadsAndTheConnectionsBetweenThem) {
  const LaneMap truth = network({});  // roads 1 (2 lanes), 2 (2 lanes), 3 (1 lane); 3 connections
  LaneMap built;                       // a drive that mapped roads 1 and 2 only
  for (const auto& l : truth.lanelets) {
    if (l.kind == LaneletKind::kRoad && l.road_id != 3) built.lanelets.push_back(l);
  }
  built.lines = truth.lines;
  const LaneMap area = lanemap::eval::restrictToMappedRoads(truth, built);
  EXPECT_EQ(roadsOf(area), (std::set<std::pair<int64_t, int64_t>>{{10, 20}, {20, 30}}));
  size_t road = 0, connectors = 0;
  for (const auto& l : area.lanelets) (l.kind == LaneletKind::kRoad ? road : connectors)++;
  EXPECT_EQ(road, 4u);
  EXPECT_EQ(connectors, 2u) << "A0->B0 and A1->B1 stay, A0->C0 leads to an unmapped road";
  for (const auto& l : area.lanelets) {
    for (int64_t s : l.successors) EXPECT_NE(area.lanelet(s), nullptr) << "dangling successor " << s;
    EXPECT_NE(area.line(l.left_id), nullptr);
    EXPECT_NE(area.line(l.right_id), nullptr);
  }
  // Scored against the area, the built map (all of roads 1 and 2) has full lane recall; against
  // the whole truth it misses road 3's lane.
  const auto in_area = lanemap::eval::evaluate(area, built);
  const auto whole = lanemap::eval::evaluate(truth, built);
  EXPECT_DOUBLE_EQ(in_area.lane_recall.value(), 1.0);
  EXPECT_DOUBLE_EQ(whole.lane_recall.value(), 4.0 / 5.0);
}

TEST(MappedArea, NothingMappedKeepsNothing) {
  const LaneMap area = lanemap::eval::restrictToMappedRoads(network({}), LaneMap{});
  EXPECT_TRUE(area.lanelets.empty());
  EXPECT_TRUE(area.lines.empty());
}

TEST(DrivenArea, ADrivenRoadWithNoLanesCountsAsMissed) {
  const LaneMap truth = network({});  // roads 1 (10->20), 2 (20->30), 3 (30->40)
  LaneMap built;                       // the mapper built road 1 only; the car drove 1 and 2
  for (const auto& l : truth.lanelets) {
    if (l.kind == LaneletKind::kRoad && l.road_id == 1) built.lanelets.push_back(l);
  }
  built.lines = truth.lines;
  const LaneMap driven = lanemap::eval::restrictToRoads(truth, {{10, 20}, {20, 30}});
  EXPECT_EQ(roadsOf(driven), (std::set<std::pair<int64_t, int64_t>>{{10, 20}, {20, 30}}));
  const auto by_driven = lanemap::eval::evaluate(driven, built);
  const auto by_mapped = lanemap::eval::evaluate(lanemap::eval::restrictToMappedRoads(truth, built), built);
  EXPECT_EQ(by_driven.lane_recall.total, 4u);
  EXPECT_DOUBLE_EQ(by_driven.lane_recall.value(), 2.0 / 4.0) << "road 2's two lanes were driven and missed";
  EXPECT_DOUBLE_EQ(by_mapped.lane_recall.value(), 1.0) << "the mapped-roads view cannot see them";
  EXPECT_EQ(by_driven.intersection_recall.total, 2u);  // A0->B0, A1->B1; not A0->C0 (road 3 not driven)
  EXPECT_EQ(by_driven.intersection_recall.hits, 0u);
}

// Two atomic roads between the same two junctions (Monaco: a street and the tunnel under it, both
// from node A to node B): the route's road ids tell which one was driven. Keyed by (from, to)
// alone, the other road's lane counted as driven and missed (seen on the broad benchmark).
TEST(DrivenArea, OfTwoRoadsBetweenTheSameJunctionsOnlyTheDrivenOneCounts) {
  LaneMap truth = network({});  // roads 1 (10->20, 2 lanes), 2 (20->30, 2 lanes), 3 (1 lane)
  for (auto& l : truth.lanelets) {
    if (l.road_id == 3) l.from_node = 20, l.to_node = 30;  // road 3 now also joins 20 to 30
  }
  LaneMap built;  // the mapper built roads 1 and 2, all the car drove
  for (const auto& l : truth.lanelets) {
    if (l.kind == LaneletKind::kRoad && l.road_id != 3) built.lanelets.push_back(l);
  }
  built.lines = truth.lines;
  lanemap::eval::DrivenArea area;
  area.roads = {{10, 20}, {20, 30}};
  const auto roadIds = [](const LaneMap& m) {
    std::set<int64_t> ids;
    for (const auto& l : m.lanelets) if (l.kind == LaneletKind::kRoad) ids.insert(l.road_id);
    return ids;
  };
  area.road_ids = {1, 2};
  const LaneMap driven = lanemap::eval::restrictToDriven(truth, area);
  EXPECT_EQ(roadIds(driven), (std::set<int64_t>{1, 2}));
  size_t connectors = 0;
  for (const auto& l : driven.lanelets) connectors += l.kind == LaneletKind::kIntersection;
  EXPECT_EQ(connectors, 2u) << "A0->B0 and A1->B1; not A0->C0 into the road not driven";
  const auto report = lanemap::eval::evaluate(driven, built);
  EXPECT_EQ(report.lane_recall.total, 4u);
  EXPECT_DOUBLE_EQ(report.lane_recall.value(), 1.0);
  // Ids of another numbering (none of the parallel roads among them), or none: both kept, the
  // road 3 lane counted as missed, as before.
  for (const std::set<int64_t>& ids : {std::set<int64_t>{1, 99}, std::set<int64_t>{}}) {
    area.road_ids = ids;
    const LaneMap both = lanemap::eval::restrictToDriven(truth, area);
    EXPECT_EQ(roadIds(both), (std::set<int64_t>{1, 2, 3}));
    EXPECT_EQ(lanemap::eval::evaluate(both, built).lane_recall.total, 5u);
  }
}

TEST(DrivenArea, RouteFromScenarioSkipsTheRoadTheDriveEndedOn) {
  lanemap::testing::TempDir dir("driven");
  {
    std::ofstream f(dir.str("scenario.json"));
    f << R"({"route": [{"road_id": 4, "from": 10, "to": 20, "left_utime": 100},
                       {"road_id": 7, "from": 20, "to": 30, "left_utime": 200},
                       {"road_id": 9, "from": 30, "to": 40, "left_utime": null}]})";
  }
  EXPECT_EQ(lanemap::eval::drivenRoadsFromScenario(dir.str("scenario.json")),
            (std::set<lanemap::eval::RoadKey>{{10, 20}, {20, 30}}));
  // Every entry's road id, the one it ended on included (its road is scored as far as driven).
  EXPECT_EQ(lanemap::eval::drivenAreaFromScenario(dir.str("scenario.json"), lanemap::geo::LocalFrame({0, 0, 0})).road_ids,
            (std::set<int64_t>{4, 7, 9}));
  {
    std::ofstream f(dir.str("bad.json"));
    f << R"({"seed": 1})";
  }
  try {
    lanemap::eval::drivenRoadsFromScenario(dir.str("bad.json"));
    FAIL() << "a file without a route must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
  }
  EXPECT_THROW(lanemap::eval::drivenRoadsFromScenario(dir.str("missing.json")), std::runtime_error);
}

// The road a drive ended on (issue 14): the car drove road 1 (10->20) to its end and road 2
// (20->30, east x 10..100) to x = 40. A mapper that maps road 2 as far as driven is scored on
// that part; the old scoring dropped road 2's truth and counted its lanes against precision.
LaneMap builtAsFarAsDriven(const LaneMap& truth, double x_end) {
  lanemap::testing::MapBuilder b;
  b.next = 1000;
  for (const auto& l : truth.lanelets) {
    if (l.kind != LaneletKind::kRoad || l.road_id == 3) continue;
    lanemap::eval::Polyline c;
    for (const auto& p : l.centre) {
      if (l.road_id == 1 || p.x() <= x_end + 1e-9) c.push_back(p.head<2>());
    }
    const int64_t id = b.lane(c, l.road_id);
    for (auto& ll : b.m.lanelets) {
      if (ll.id == id) ll.partial = l.road_id == 2 ? std::optional<lanemap::map::PartialRoad>({x_end - 10, 90}) : std::nullopt;
    }
  }
  return b.m;
}

TEST(DrivenArea, TheRoadTheDriveEndedOnIsScoredAsFarAsDriven) {
  const LaneMap truth = network({});
  lanemap::eval::DrivenArea area;
  area.roads = {{10, 20}};
  area.partial.push_back({{20, 30}, {40.0, -3.0}});
  const LaneMap driven = lanemap::eval::restrictToDriven(truth, area);
  EXPECT_EQ(roadsOf(driven), (std::set<std::pair<int64_t, int64_t>>{{10, 20}, {20, 30}}));
  size_t road2 = 0, connectors = 0;
  for (const auto& l : driven.lanelets) {
    if (l.kind == LaneletKind::kIntersection) ++connectors;
    if (l.road_id != 2) continue;
    ++road2;
    EXPECT_NEAR(l.centre.front().x(), 10.0, 1e-9);
    EXPECT_NEAR(l.centre.back().x(), 40.0, 1e-6) << "cut across the road at the car's last position";
    for (const int64_t b : {l.left_id, l.right_id}) {
      const auto* line = driven.line(b);
      ASSERT_NE(line, nullptr);
      EXPECT_NEAR(line->points.back().x(), 40.0, 1e-6);
      EXPECT_NEAR(line->points.front().x(), 10.0, 1e-6);
    }
  }
  EXPECT_EQ(road2, 2u);
  EXPECT_EQ(connectors, 2u) << "the junction into road 2 was driven";
  // The original (uncut) bounds are still in the truth for anyone else: the cut ones are copies.
  EXPECT_NEAR(truth.line(truth.lanelets[2].left_id)->points.back().x(), 100.0, 1e-9);

  const LaneMap built = builtAsFarAsDriven(truth, 40.0);
  const auto by_driven = lanemap::eval::evaluate(driven, built);
  EXPECT_DOUBLE_EQ(by_driven.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(by_driven.lane_recall.value(), 1.0);
  EXPECT_LT(by_driven.lane_rms_m, 0.01);
  EXPECT_GT(by_driven.lane_miou, 0.95);
  // The old scoring: road 2 dropped from the truth, its two lanes false positives.
  const auto old = lanemap::eval::evaluate(lanemap::eval::restrictToRoads(truth, area.roads), built);
  EXPECT_DOUBLE_EQ(old.lane_precision.value(), 2.0 / 4.0);
  // Scoring road 2 whole would miss its lanes past x = 40 (IoU 0.33).
  const auto whole = lanemap::eval::evaluate(lanemap::eval::restrictToRoads(truth, {{10, 20}, {20, 30}}), built);
  EXPECT_LT(whole.lane_recall.value(), 1.0);
  // A map without the partial road misses its two lanes.
  LaneMap without = built;
  without.lanelets.erase(std::remove_if(without.lanelets.begin(), without.lanelets.end(),
                                        [](const auto& l) { return l.road_id == 2; }),
                         without.lanelets.end());
  EXPECT_DOUBLE_EQ(lanemap::eval::evaluate(driven, without).lane_recall.value(), 2.0 / 4.0);
}

TEST(DrivenArea, ACutKeepsWholePiecesBeforeItAndDropsThoseAfter) {
  const LaneMap truth = network(lanemap::testing::with([](lanemap::testing::Net& n) { n.split_b0 = true; }));
  // B0 in pieces 10..40, 40..70, 70..100; B1 whole 10..100. Cut at x = 55.
  const LaneMap cut = lanemap::eval::cutRoadAt(truth, {20, 30}, {55.0, -2.0});
  size_t pieces = 0;
  for (const auto& l : cut.lanelets) {
    if (l.road_id != 2) continue;
    ++pieces;
    EXPECT_LE(l.centre.back().x(), 55.0 + 1e-6);
    for (int64_t s : l.successors) EXPECT_NE(cut.lanelet(s), nullptr) << "dangling successor " << s;
    if (l.centre.front().x() < 11 && l.centre.back().x() > 39 && l.centre.back().x() < 41) {
      EXPECT_EQ(l.successors.size(), 1u) << "the whole piece before the cut keeps its successor";
    }
  }
  EXPECT_EQ(pieces, 3u) << "B0's 10..40 and 40..55, B1's 10..55; B0's 70..100 is dropped";
  // A cut on a road the truth has no lanes on changes nothing.
  EXPECT_EQ(lanemap::eval::cutRoadAt(truth, {70, 80}, {0, 0}).lanelets.size(), truth.lanelets.size());
}

// The road a drive began on: the car stood 55 m into road 1 (x = -45 of -100..-10) when the
// recording started; nothing behind it was seen. Scored from there, a map with road 1's lanes from
// where the camera first saw them (x = -40) has them all; scored whole, it misses them.
TEST(DrivenArea, TheRoadTheDriveBeganOnIsScoredFromWhereTheCarStarted) {
  const LaneMap truth = network({});
  lanemap::eval::DrivenArea area;
  area.roads = {{10, 20}, {20, 30}};
  area.entered.push_back({{10, 20}, {-45.0, -1.75}});
  const LaneMap driven = lanemap::eval::restrictToDriven(truth, area);
  EXPECT_EQ(roadsOf(driven), (std::set<std::pair<int64_t, int64_t>>{{10, 20}, {20, 30}}));
  size_t road1 = 0, connectors = 0;
  for (const auto& l : driven.lanelets) {
    if (l.kind == LaneletKind::kIntersection) ++connectors;
    if (l.road_id != 1) continue;
    ++road1;
    EXPECT_NEAR(l.centre.front().x(), -45.0, 1e-6) << "cut across the road at the car's first position";
    EXPECT_NEAR(l.centre.back().x(), -10.0, 1e-9) << "its end is kept";
    EXPECT_EQ(l.successors.size(), 1u) << "its connection out to road 2 is kept";
    for (const int64_t b : {l.left_id, l.right_id}) {
      const auto* line = driven.line(b);
      ASSERT_NE(line, nullptr);
      EXPECT_NEAR(line->points.front().x(), -45.0, 1e-6);
      EXPECT_NEAR(line->points.back().x(), -10.0, 1e-6);
    }
  }
  EXPECT_EQ(road1, 2u);
  EXPECT_EQ(connectors, 2u) << "A0->B0 and A1->B1; A0->C0 leads to road 3, not driven";
  EXPECT_NEAR(truth.line(truth.lanelets[0].left_id)->points.front().x(), -100.0, 1e-9) << "the truth itself is not cut";

  // What the map could have: road 1 from x = -40 (where the camera first saw it), road 2 whole.
  LaneMap built = lanemap::eval::restrictToRoads(truth, area.roads);
  const auto seenFromX40 = [](std::vector<Eigen::Vector3d>& pts) {
    pts.erase(std::remove_if(pts.begin(), pts.end(), [](const auto& p) { return p.x() < -40.0 - 1e-9; }), pts.end());
  };
  std::set<int64_t> road1_bounds;
  for (auto& l : built.lanelets) {
    if (l.road_id != 1) continue;
    seenFromX40(l.centre);
    road1_bounds.insert({l.left_id, l.right_id});
  }
  for (auto& line : built.lines) {
    if (road1_bounds.count(line.id)) seenFromX40(line.points);
  }
  const auto from_start = lanemap::eval::evaluate(driven, built);
  EXPECT_DOUBLE_EQ(from_start.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(from_start.lane_recall.value(), 1.0);
  // Road 1 scored whole: 30 m of 90 m is no detection (IoU 0.33, coverage under a half).
  const auto whole = lanemap::eval::evaluate(lanemap::eval::restrictToRoads(truth, area.roads), built);
  EXPECT_DOUBLE_EQ(whole.lane_recall.value(), 2.0 / 4.0);
}

TEST(DrivenArea, TheRoadTheDriveEndedOnComesFromScenarioAndTrajectory) {
  lanemap::testing::TempDir dir("driven-partial");
  {
    std::ofstream f(dir.str("scenario.json"));
    f << R"({"origin": {"lat": 37.8, "lon": -122.3, "alt": 5.0},
             "route": [{"road_id": 4, "from": 10, "to": 20, "left_utime": 100},
                       {"road_id": 9, "from": 20, "to": 30, "left_utime": null}]})";
    std::ofstream t(dir.str("trajectory.csv"));
    t << "t_s,utime,east_m,north_m,up_m,yaw_rad,speed_mps,lanelet,road_id\n"
         "0.000,0,0.0,0.0,0.0,0.0,5.0,1,4\n"
         "0.100,100000,40.0,-3.0,0.0,0.0,5.0,2,9\n";
  }
  const lanemap::geo::LocalFrame same({37.8, -122.3, 5.0});
  auto area = lanemap::eval::drivenAreaFromScenario(dir.str("scenario.json"), same);
  EXPECT_EQ(area.roads, (std::set<lanemap::eval::RoadKey>{{10, 20}}));
  ASSERT_EQ(area.partial.size(), 1u);
  EXPECT_EQ(area.partial[0].road, (lanemap::eval::RoadKey{20, 30}));
  EXPECT_NEAR(area.partial[0].end.x(), 40.0, 1e-6);
  EXPECT_NEAR(area.partial[0].end.y(), -3.0, 1e-6);
  // The road it began on, from the first row's position.
  ASSERT_EQ(area.entered.size(), 1u);
  EXPECT_EQ(area.entered[0].road, (lanemap::eval::RoadKey{10, 20}));
  EXPECT_NEAR(area.entered[0].start.norm(), 0.0, 1e-6);
  // In another frame (the truth's origin 100 m east of the scenario's), the same point.
  const lanemap::geo::LocalFrame other(same.toWgs84({100.0, 0.0, 0.0}));
  area = lanemap::eval::drivenAreaFromScenario(dir.str("scenario.json"), other);
  ASSERT_EQ(area.partial.size(), 1u);
  EXPECT_NEAR(area.partial[0].end.x(), -60.0, 0.01);
  EXPECT_NEAR(area.partial[0].end.y(), -3.0, 0.01);
  // Without trajectory.csv: the closed roads only.
  std::filesystem::remove(dir.str("trajectory.csv"));
  EXPECT_TRUE(lanemap::eval::drivenAreaFromScenario(dir.str("scenario.json"), same).partial.empty());
  EXPECT_TRUE(lanemap::eval::drivenAreaFromScenario(dir.str("scenario.json"), same).entered.empty());
}

// A drive that comes back to the road it began on and drives it whole: the road counts whole.
TEST(DrivenArea, TheRoadTheDriveBeganOnDrivenWholeLaterIsNotCut) {
  lanemap::testing::TempDir dir("driven-entered");
  {
    std::ofstream f(dir.str("scenario.json"));
    f << R"({"origin": {"lat": 37.8, "lon": -122.3, "alt": 5.0},
             "route": [{"road_id": 4, "from": 10, "to": 20, "left_utime": 100},
                       {"road_id": 9, "from": 20, "to": 10, "left_utime": 200},
                       {"road_id": 4, "from": 10, "to": 20, "left_utime": 300}]})";
    std::ofstream t(dir.str("trajectory.csv"));
    t << "t_s,utime,east_m,north_m,up_m,yaw_rad,speed_mps,lanelet,road_id\n"
         "0.000,0,5.0,0.0,0.0,0.0,5.0,1,4\n"
         "0.300,300000,40.0,-3.0,0.0,0.0,5.0,2,4\n";
  }
  const auto area = lanemap::eval::drivenAreaFromScenario(dir.str("scenario.json"), lanemap::geo::LocalFrame({37.8, -122.3, 5.0}));
  EXPECT_TRUE(area.entered.empty());
  EXPECT_TRUE(area.partial.empty());
  EXPECT_EQ(area.roads, (std::set<lanemap::eval::RoadKey>{{10, 20}, {20, 10}}));
}

}  // namespace
