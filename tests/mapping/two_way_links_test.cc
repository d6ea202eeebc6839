// A two-way link's two directions end their lanes at one place (core/mapping/two_way_links.h):
// each direction's lanelets, placed on its own evidence, cut to the stretch both cover, points
// interpolated at the cut, a stop line moving with its lanelet's end; the map assembler does it
// whatever order the two directions come in. Left alone: a long road, ends too far apart, a
// direction with lanelets in pieces. Lanelets constructed along a two-way road of West Oakland's
// skeleton (its polyline is what the stretches are measured on).
#include "core/mapping/map_assembler.h"
#include "core/mapping/two_way_links.h"
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace {

using namespace lanemap;

const skeleton::Skeleton& westOakland() {
  static const skeleton::Skeleton sk = skeleton::Skeleton::build(osm::readOsm(std::string(LANEMAP_DATA_DIR) + "/osm/west-oakland.osm"));
  return sk;
}

// A two-way road at least 40 m long.
const skeleton::AtomicRoad& twoWayRoad() {
  for (const auto& r : westOakland().roads()) {
    if (r.reverse_id > r.id && r.length >= 40.0) return r;
  }
  throw std::runtime_error("West Oakland has no two-way road of 40 m");
}

// A line at offset d (left of road `a`'s direction) from station s0 to s1 of road a, a point every
// half metre (reversed when s0 > s1).
map::LineString line(int64_t id, int64_t a, double d, double s0, double s1, map::LineType type = map::LineType::kSolid) {
  const auto& sk = westOakland();
  const auto& road = *sk.road(a);
  map::LineString l;
  l.id = id;
  l.type = type;
  const int n = std::max(2, static_cast<int>(std::round(std::abs(s1 - s0) / 0.5)));
  for (int i = 0; i <= n; ++i) {
    const double s = s0 + (s1 - s0) * i / n;
    const Eigen::Vector2d t = sk.tangentAt(road, s);
    const Eigen::Vector2d p = sk.pointAt(road, s) + d * Eigen::Vector2d(-t.y(), t.x());
    l.points.emplace_back(p.x(), p.y(), 0.0);
  }
  return l;
}

// One direction's lane over [s0, s1] of road a (a's direction when `along`, else against it), 3.5 m
// wide beside the line between the two directions; line ids from `id`.
map::LaneMap direction(int64_t road_id, int64_t a, bool along, double s0, double s1, int64_t id) {
  const double side = along ? -1.0 : 1.0;
  const double from = along ? s0 : s1, to = along ? s1 : s0;
  map::LaneMap m;
  m.lines = {line(id, a, 0.02 * side, from, to), line(id + 1, a, 3.5 * side, from, to, map::LineType::kCurb)};
  const map::LineString centre = line(0, a, 1.75 * side, from, to);
  map::Lanelet ll;
  ll.id = id + 2;
  ll.road_id = road_id;
  ll.left_id = along ? id : id + 1;
  ll.right_id = along ? id + 1 : id;
  ll.centre = centre.points;
  m.lanelets = {ll};
  return m;
}

double station(int64_t a, const Eigen::Vector3d& p) { return westOakland().project(a, p.head<2>()).s; }

// Every line's and centre line's two ends, as stations along road a.
void expectEnds(const map::LaneMap& m, int64_t a, double s0, double s1) {
  for (const auto& l : m.lines) {
    const double e0 = station(a, l.points.front()), e1 = station(a, l.points.back());
    EXPECT_NEAR(std::min(e0, e1), s0, 0.02) << "line " << l.id;
    EXPECT_NEAR(std::max(e0, e1), s1, 0.02) << "line " << l.id;
  }
  for (const auto& ll : m.lanelets) {
    const double e0 = station(a, ll.centre.front()), e1 = station(a, ll.centre.back());
    EXPECT_NEAR(std::min(e0, e1), s0, 0.02) << "lanelet " << ll.id;
    EXPECT_NEAR(std::max(e0, e1), s1, 0.02) << "lanelet " << ll.id;
  }
}

TEST(TwoWayLinks, ALinksTwoDirectionsAreCutToTheStretchBothCover) {
  const auto& r = twoWayRoad();
  const int64_t a = r.id, b = r.reverse_id;
  map::LaneMap la = direction(a, a, true, 10.0, 14.5, 1);
  map::LaneMap lb = direction(b, a, false, 9.4, 14.0, 11);
  // A stop line across the reverse's lane at its end (station 9.4 of road a).
  map::LineString stop;
  stop.id = 20;
  stop.type = map::LineType::kStopLine;
  stop.points = {line(0, a, 0.1, 9.4, 9.5).points.front(), line(0, a, 3.4, 9.4, 9.5).points.front()};
  lb.lines.push_back(stop);
  lb.lanelets[0].stop_line_id = 20;
  ASSERT_TRUE(mapping::matchTwoWayLink(la, a, lb, b, westOakland()));
  expectEnds(la, a, 10.0, 14.0);  // the road's lane loses its last 0.5 m ...
  map::LaneMap lb_lanes = lb;
  lb_lanes.lines.pop_back();
  expectEnds(lb_lanes, a, 10.0, 14.0);  // ... the reverse's its last 0.6 m,
  for (const auto& p : lb.lines.back().points) EXPECT_NEAR(station(a, p), 10.0, 0.02);  // and its stop line moves with it
  // Cut already: nothing more to do.
  EXPECT_FALSE(mapping::matchTwoWayLink(la, a, lb, b, westOakland()));
}

TEST(TwoWayLinks, LeftAloneALongRoadEndsFarApartAndALaneInPieces) {
  const auto& r = twoWayRoad();
  const int64_t a = r.id, b = r.reverse_id;
  const auto unchanged = [&](map::LaneMap la, map::LaneMap lb) {
    const map::LaneMap la0 = la, lb0 = lb;
    EXPECT_FALSE(mapping::matchTwoWayLink(la, a, lb, b, westOakland()));
    EXPECT_EQ(la.lines[0].points, la0.lines[0].points);
    EXPECT_EQ(lb.lines[0].points, lb0.lines[0].points);
  };
  unchanged(direction(a, a, true, 5.0, 35.0, 1), direction(b, a, false, 4.0, 34.0, 11));  // 30 m: no link
  unchanged(direction(a, a, true, 10.0, 16.0, 1), direction(b, a, false, 6.0, 15.0, 11));  // 4 m apart
  map::LaneMap pieces = direction(a, a, true, 10.0, 14.5, 1);
  map::LaneMap second = direction(a, a, true, 12.0, 14.5, 5);  // a lane starting 2 m in
  pieces.lines.insert(pieces.lines.end(), second.lines.begin(), second.lines.end());
  pieces.lanelets.push_back(second.lanelets[0]);
  unchanged(pieces, direction(b, a, false, 9.4, 14.0, 11));
}

TEST(TwoWayLinks, TheAssemblerCutsThemWhateverOrderTheyCome) {
  const auto& r = twoWayRoad();
  const int64_t a = r.id, b = r.reverse_id;
  const map::LaneMap la = direction(a, a, true, 10.0, 14.5, 1), lb = direction(b, a, false, 9.4, 14.0, 11);
  mapping::MapAssembler one(westOakland()), two(westOakland());
  one.setRoad(a, la);
  EXPECT_EQ(one.roads().at(a).lines[0].points, la.lines[0].points);  // alone: as given
  one.setRoad(b, lb);
  two.setRoad(b, lb);
  two.setRoad(a, la);
  EXPECT_EQ(one.twoWayLinksCut(), 1u);
  EXPECT_EQ(two.twoWayLinksCut(), 1u);
  for (const int64_t id : {a, b}) {
    const auto& m1 = one.roads().at(id);
    const auto& m2 = two.roads().at(id);
    ASSERT_EQ(m1.lines.size(), m2.lines.size());
    for (size_t k = 0; k < m1.lines.size(); ++k) EXPECT_EQ(m1.lines[k].points, m2.lines[k].points) << id;
    expectEnds(m1, a, 10.0, 14.0);
  }
  // The road set again as explored: cut again from what was given, not from the cut one.
  one.setRoad(a, la);
  expectEnds(one.roads().at(a), a, 10.0, 14.0);
  EXPECT_EQ(one.roads().at(b).lines[0].points, two.roads().at(b).lines[0].points);
  // Mapped again as a 30 m lane (no link now): the reverse is as it was set again.
  one.setRoad(a, direction(a, a, true, 5.0, 35.0, 1));
  EXPECT_EQ(one.roads().at(b).lines[0].points, lb.lines[0].points);
  expectEnds(one.roads().at(a), a, 5.0, 35.0);
}

}  // namespace
