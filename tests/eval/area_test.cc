// restrictToMappedRoads / restrictToRoads / drivenRoadsFromScenario: the truth a drive could have mapped.
#include "core/eval/area.h"
#include "core/eval/evaluate.h"
#include "tests/eval/test_maps.h"

#include <gtest/gtest.h>

#include <fstream>
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

}  // namespace
