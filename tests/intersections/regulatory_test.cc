// Junction controls from OSM (core/intersections/regulatory.h): which approach a highway=stop /
// give_way / traffic_signals node governs, and the regulatory elements made at stop lines.
#include "core/intersections/regulatory.h"

#include "tests/intersections/fixture.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace lanemap::intersections {
namespace {

using testing::Net;

// A four-way junction (node 1 at the origin) of two-way roads to dead ends 100 m away: west
// (way 11: 2 -> 20 -> 1, node 20 10 m before the junction), north (way 12: 4 -> 40 -> 1, node 40
// 10 m before it), east (way 13: 1 -> 3), south (way 14: 1 -> 5).
struct Junction {
  Net net;
  skeleton::Skeleton sk;
  std::unordered_map<int64_t, ControlNode> controls;
  static skeleton::Skeleton build(Net& n) {
    n.node(1, 0, 0);
    n.node(2, -100, 0);
    n.node(20, -10, 0);
    n.node(3, 100, 0);
    n.node(4, 0, 100);
    n.node(40, 0, 10);
    n.node(5, 0, -100);
    n.way(11, {2, 20, 1});
    n.way(12, {4, 40, 1});
    n.way(13, {1, 3});
    n.way(14, {1, 5});
    return n.build();
  }
  Junction() : sk(build(net)) {}
  void control(int64_t node, Control c, const std::string& direction = "") {
    const auto& n = net.data.nodes.at(node);
    controls[node] = ControlNode{node, n.lat, n.lon, c, direction};
  }
  // The atomic road from OSM node a's end to node b's (junction to junction).
  const skeleton::AtomicRoad& road(int64_t a, int64_t b) const {
    for (const auto& r : sk.roads()) {
      if (r.osm_nodes.front() == a && r.osm_nodes.back() == b) return r;
    }
    throw std::runtime_error("no road " + std::to_string(a) + " -> " + std::to_string(b));
  }
};

TEST(Regulatory, ControlNodeGovernsTheApproachItLiesOnInItsDirection) {
  Junction j;
  j.control(20, Control::kGiveWay, "forward");
  j.control(40, Control::kStop);
  EXPECT_EQ(approachControl(j.sk, j.road(2, 1).id, j.controls).control, Control::kGiveWay);
  EXPECT_EQ(approachControl(j.sk, j.road(2, 1).id, j.controls).node, 20);
  EXPECT_EQ(approachControl(j.sk, j.road(4, 1).id, j.controls).control, Control::kStop);
  // Leaving the junction the nodes are at the roads' start, not before their end.
  EXPECT_EQ(approachControl(j.sk, j.road(1, 2).id, j.controls).control, Control::kNone);
  EXPECT_EQ(approachControl(j.sk, j.road(1, 4).id, j.controls).control, Control::kNone);
  EXPECT_EQ(approachControl(j.sk, j.road(3, 1).id, j.controls).control, Control::kNone);
  // direction=backward: for travel against the way (1 -> 2), whose end it is not near: none.
  j.control(20, Control::kGiveWay, "backward");
  EXPECT_EQ(approachControl(j.sk, j.road(2, 1).id, j.controls).control, Control::kNone);
  // Signals on the junction node govern every approach and beat a stop sign.
  j.control(1, Control::kTrafficSignals);
  for (int64_t from : {2, 3, 4, 5}) {
    EXPECT_EQ(approachControl(j.sk, j.road(from, 1).id, j.controls).control, Control::kTrafficSignals) << from;
  }
}

// One lanelet per approach (id 1000 + from node), ending at the junction; the west and north ones
// end at stop lines 900 and 901; east and south continue into intersection lanelets 2003 / 2005.
map::LaneMap approaches(const Junction& j) {
  map::LaneMap m;
  int64_t next_line = 1;
  for (int64_t from : {2, 3, 4, 5}) {
    const auto& r = j.road(from, 1);
    map::Lanelet ll;
    ll.id = 1000 + from;
    ll.road_id = r.id;
    const Eigen::Vector2d end = r.polyline.back(), before = r.polyline[r.polyline.size() - 2];
    const Eigen::Vector2d t = (end - before).normalized(), right(t.y(), -t.x());
    const Eigen::Vector2d a = end - 5.0 * t, b = end - 5.0 * t + 3.5 * right;
    ll.centre = {Eigen::Vector3d(before.x(), before.y(), 0), Eigen::Vector3d(a.x(), a.y(), 0)};
    ll.left_id = next_line++;
    ll.right_id = next_line++;
    if (from == 2 || from == 4) {
      map::LineString stop;
      stop.id = from == 2 ? 900 : 901;
      stop.type = map::LineType::kStopLine;
      stop.points = {Eigen::Vector3d(a.x(), a.y(), 1.0), Eigen::Vector3d(b.x(), b.y(), 1.0)};
      m.lines.push_back(stop);
      ll.stop_line_id = stop.id;
    } else {
      map::Lanelet x;
      x.id = 2000 + from;
      x.kind = map::LaneletKind::kIntersection;
      ll.successors = {x.id};
      m.lanelets.push_back(x);
    }
    m.lanelets.push_back(ll);
  }
  return m;
}

TEST(Regulatory, ElementsAtStopLinesFollowTheirApproachesControl) {
  Junction j;
  j.control(20, Control::kGiveWay, "forward");
  j.control(40, Control::kStop);
  map::LaneMap m = approaches(j);
  ASSERT_EQ(addRegulatoryElements(m, j.sk, j.controls), 2u);
  const auto at = [&](int64_t stop) {
    const auto it = std::find_if(m.regulatory_elements.begin(), m.regulatory_elements.end(),
                                 [&](const auto& r) { return r.stop_line_id == stop; });
    EXPECT_NE(it, m.regulatory_elements.end()) << stop;
    return *it;
  };
  const auto give = at(900);
  EXPECT_EQ(give.kind, map::RegulatoryKind::kGiveWay);
  EXPECT_EQ(give.lanelets, (std::vector<int64_t>{1002}));
  EXPECT_EQ(give.osm_node, 20);
  // Priority: the approaches with no control that enter the junction (east, south), not north.
  auto prio = give.priority;
  std::sort(prio.begin(), prio.end());
  EXPECT_EQ(prio, (std::vector<int64_t>{1003, 1005}));
  const auto stop = at(901);
  EXPECT_EQ(stop.kind, map::RegulatoryKind::kStopSign);
  EXPECT_EQ(stop.lanelets, (std::vector<int64_t>{1004}));
  EXPECT_TRUE(stop.priority.empty());
  // Ids above every id of the map.
  EXPECT_GT(std::min(give.id, stop.id), 2005);

  // Signals: a light 5 m above the middle of the stop line, 0.4 m wide, marked as an estimate.
  j.control(40, Control::kTrafficSignals);
  ASSERT_EQ(addRegulatoryElements(m, j.sk, j.controls), 2u);
  const auto light = at(901);
  EXPECT_EQ(light.kind, map::RegulatoryKind::kTrafficLight);
  ASSERT_EQ(light.light.size(), 2u);
  const auto* line = m.line(901);
  const Eigen::Vector3d mid = 0.5 * (line->points[0] + line->points[1]);
  EXPECT_NEAR((0.5 * (light.light[0] + light.light[1]) - mid - Eigen::Vector3d(0, 0, kLightClearanceM)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((light.light[1] - light.light[0]).norm(), kLightWidthM, 1e-9);
  EXPECT_TRUE(light.light_estimated);
  // No control: no element, the stop line stays.
  j.controls.clear();
  EXPECT_EQ(addRegulatoryElements(m, j.sk, j.controls), 0u);
  EXPECT_TRUE(m.regulatory_elements.empty());
  EXPECT_NE(m.line(900), nullptr);
}

TEST(Regulatory, ReadsTheControlNodesOfAnExtract) {
  // grep -c 'k="highway" v="traffic_signals"' data/osm/west-oakland.osm -> 4; v="stop" -> 3
  const auto c = readControlNodes(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm");
  size_t signals = 0, stops = 0;
  for (const auto& [id, n] : c) {
    signals += n.control == Control::kTrafficSignals;
    stops += n.control == Control::kStop;
    EXPECT_EQ(id, n.id);
    EXPECT_NEAR(n.lat, 37.81, 0.05);
  }
  EXPECT_EQ(signals, 4u);
  EXPECT_EQ(stops, 3u);
  EXPECT_THROW(readControlNodes("/nonexistent.osm"), osm::OsmError);
}

}  // namespace
}  // namespace lanemap::intersections
