// The line between opposite lanes is one line string (core/mapping/shared_dividers.h): a road's and
// its reverse's bounds, or two bounds of one junction's connections, that lie on top of each
// other and run against each other become one line; the lanelets that had the dropped one take
// the kept one, and lines that ended where it ended end at the kept line's end, moved smoothly.
// Two neighbouring connections of one junction whose facing bounds lie on top of each other share
// one too. Lines apart, a road's lines of one direction and bounds of roads that are not each
// other's reverse stay.
// Constructed lanelets on West Oakland's skeleton (only its roads' reverse ids are used).
#include "core/io/lanelet2_orientation.h"
#include "core/mapping/shared_dividers.h"
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

// A two-way road of the skeleton (its id, its reverse's).
std::pair<int64_t, int64_t> twoWayRoad() {
  for (const auto& r : westOakland().roads()) {
    if (r.reverse_id > r.id) return {r.id, r.reverse_id};
  }
  return {-1, -1};
}

// A straight line along x at height y, from x0 to x1, a point every metre.
map::LineString line(int64_t id, double y, double x0, double x1, map::LineType type = map::LineType::kSolid) {
  map::LineString l;
  l.id = id;
  l.type = type;
  const int n = static_cast<int>(std::round(std::abs(x1 - x0)));
  for (int i = 0; i <= n; ++i) l.points.emplace_back(x0 + (x1 - x0) * i / n, y, 0.0);
  return l;
}

map::Lanelet lanelet(int64_t id, int64_t left, int64_t right, double y, double x0, double x1, int64_t road) {
  map::Lanelet ll;
  ll.id = id;
  ll.left_id = left;
  ll.right_id = right;
  ll.road_id = road;
  ll.centre = {Eigen::Vector3d(x0, y, 0), Eigen::Vector3d(x1, y, 0)};
  return ll;
}

const map::LineString* find(const map::LaneMap& m, int64_t id) {
  const auto it = std::find_if(m.lines.begin(), m.lines.end(), [&](const map::LineString& l) { return l.id == id; });
  return it == m.lines.end() ? nullptr : &*it;
}

// Road r eastwards (y -3.5..0), its reverse westwards (y 0..3.5) with its left bound `gap` m north
// of r's, 0.5 m short of r's line at the east end; a connection's bound leaving the reverse's left
// bound's end westwards, a point every 0.5 m.
map::LaneMap twoWay(int64_t r, int64_t rev, double gap, map::LineType r_divider = map::LineType::kSolid,
                    map::LineType rev_divider = map::LineType::kVirtual) {
  map::LaneMap m;
  m.lines = {line(1, 0.0, 0, 30, r_divider), line(2, -3.5, 0, 30), line(3, gap, 29.7, 0, rev_divider), line(4, 3.5, 30, 0)};
  m.lanelets = {lanelet(10, 1, 2, -1.75, 0, 30, r), lanelet(20, 3, 4, 1.75, 30, 0, rev)};
  map::LineString c;
  c.id = 5;
  c.type = map::LineType::kVirtual;
  for (int i = 0; i <= 20; ++i) c.points.emplace_back(-0.5 * i, gap, 0.0);
  m.lines.push_back(c);
  return m;
}

TEST(SharedDividers, ARoadsAndItsReversesBoundsOnTopOfEachOtherAreOneLine) {
  const auto [r, rev] = twoWayRoad();
  ASSERT_GE(r, 0);
  map::LaneMap m = twoWay(r, rev, 0.05);
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 1u);
  ASSERT_EQ(m.lines.size(), 4u);
  EXPECT_EQ(find(m, 3), nullptr);           // the reverse's virtual copy is dropped ...
  EXPECT_EQ(m.lanelets[1].left_id, 1);      // ... and its lanelet takes the observed line,
  EXPECT_EQ(m.lanelets[0].left_id, 1);      //     which runs against it
  for (const auto& ll : m.lanelets) {
    const auto* left = find(m, ll.left_id);
    const auto* right = find(m, ll.right_id);
    ASSERT_TRUE(left && right);
    EXPECT_EQ(io::orientationProblem(ll, *left, *right), "") << ll.id;
  }
  // The connection that left the dropped line's end leaves the kept line's now (0.05 m south),
  // less and less moved along its first 4 m, not at all beyond.
  const auto* c = find(m, 5);
  ASSERT_NE(c, nullptr);
  EXPECT_NEAR(c->points[0].x(), 0.0, 1e-9);
  EXPECT_NEAR(c->points[0].y(), 0.0, 1e-9);
  EXPECT_NEAR(c->points[4].y(), 0.025, 1e-9);  // 2 m along: half
  EXPECT_NEAR(c->points[4].x(), -2.0, 1e-9);
  EXPECT_NEAR(c->points[8].y(), 0.05, 1e-9);   // 4 m along: as it was
  EXPECT_NEAR(c->points[20].y(), 0.05, 1e-9);
  // The other lines are as they were.
  EXPECT_NEAR(find(m, 1)->points.front().y(), 0.0, 1e-12);
  EXPECT_NEAR(find(m, 4)->points.front().y(), 3.5, 1e-12);
}

TEST(SharedDividers, TheObservedLineIsKeptWhicheverRoadItBelongsTo) {
  const auto [r, rev] = twoWayRoad();
  map::LaneMap m = twoWay(r, rev, 0.05, map::LineType::kVirtual, map::LineType::kDashed);
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 1u);
  EXPECT_EQ(find(m, 1), nullptr);
  EXPECT_EQ(m.lanelets[0].left_id, 3);
  EXPECT_EQ(m.lanelets[1].left_id, 3);
  // Both virtual: the lower road's stays.
  m = twoWay(r, rev, 0.05, map::LineType::kVirtual, map::LineType::kVirtual);
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 1u);
  EXPECT_NE(find(m, 1), nullptr);
  EXPECT_EQ(find(m, 3), nullptr);
}

TEST(SharedDividers, LinesApartOrOfRoadsThatAreNotEachOthersReverseStay) {
  const auto [r, rev] = twoWayRoad();
  // 0.3 m apart: two lines (the check flags 0.1 m).
  map::LaneMap m = twoWay(r, rev, 0.3);
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 0u);
  EXPECT_EQ(m.lines.size(), 5u);
  EXPECT_EQ(m.lanelets[1].left_id, 3);
  // On top of each other but of two roads that are not a road and its reverse.
  int64_t other = -1;
  for (const auto& road : westOakland().roads()) {
    if (road.id != r && road.id != rev) other = road.id;
  }
  m = twoWay(r, other, 0.05);
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 0u);
  EXPECT_EQ(m.lines.size(), 5u);
  // A road and its reverse whose lines run the same way (not a divider drawn from both sides).
  m = twoWay(r, rev, 0.05);
  std::reverse(m.lines[2].points.begin(), m.lines[2].points.end());
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 0u);
  // Ends more than end_gap_max_m apart (one line 2 m longer).
  m = twoWay(r, rev, 0.05);
  m.lines[2] = line(3, 0.05, 31.7, 0, map::LineType::kVirtual);
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 0u);
}

TEST(SharedDividers, OppositeConnectionsOfOneJunctionShareTheirBoundOnTheRoadsLine) {
  map::LaneMap m;
  m.lines = {line(1, 0.0, 0, 20, map::LineType::kVirtual), line(2, -3.5, 0, 20, map::LineType::kVirtual),
             line(3, 0.02, 20, 0, map::LineType::kVirtual), line(4, 3.5, 20, 0, map::LineType::kVirtual)};
  m.lanelets = {lanelet(10, 1, 2, -1.75, 0, 20, -1), lanelet(20, 3, 4, 1.75, 20, 0, -1)};
  for (auto& ll : m.lanelets) {
    ll.kind = map::LaneletKind::kIntersection;
    ll.intersection_id = 77;
  }
  map::LaneMap other = m;
  other.lanelets[1].intersection_id = 78;  // two junctions: not compared
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 1u);
  EXPECT_EQ(m.lanelets[1].left_id, 1);
  EXPECT_EQ(mapping::shareDividers(other, westOakland()), 0u);
}

// Two straight connections side by side through one junction (seattle_slip_lane, truth labels): the
// left one's right bound and the right one's left bound run the same way 0.08-0.1 m apart, from
// the ends of two road lanes' bounds (the two probes of one dashed line) to the next road's. They
// become one line; the road bound that ended at the dropped line's start ends at the kept line's,
// moved smoothly; the lanelet on the dropped line takes the kept one. Bounds 1 m apart, or from
// ends 0.8 m apart, stay.
TEST(SharedDividers, NeighbouringConnectionsOfOneJunctionShareTheBorderBetweenThem) {
  const auto build = [](double gap, double start_gap) {
    map::LaneMap m;
    map::LineString inner = line(3, -3.5 - gap, 0, 20, map::LineType::kVirtual);
    inner.points.front().y() = -3.5 - start_gap;
    m.lines = {line(1, 0.0, 0, 20, map::LineType::kVirtual), line(2, -3.5, 0, 20, map::LineType::kVirtual), inner,
               line(4, -7.0, 0, 20, map::LineType::kVirtual),
               line(6, -3.5 - start_gap, -10, 0, map::LineType::kDashed)};  // the right road lane's left bound
    m.lanelets = {lanelet(10, 1, 2, -1.75, 0, 20, -1), lanelet(20, 3, 4, -5.25, 0, 20, -1)};
    for (auto& ll : m.lanelets) {
      ll.kind = map::LaneletKind::kIntersection;
      ll.intersection_id = 77;
    }
    return m;
  };
  map::LaneMap m = build(0.08, 0.1);
  EXPECT_EQ(mapping::shareDividers(m, westOakland()), 1u);
  EXPECT_EQ(m.lanelets[0].right_id, 2);
  EXPECT_EQ(m.lanelets[1].left_id, 2);
  EXPECT_EQ(find(m, 3), nullptr);
  const map::LineString* road = find(m, 6);
  ASSERT_NE(road, nullptr);
  EXPECT_NEAR(road->points.back().y(), -3.5, 1e-9);  // its end on the kept line's start
  EXPECT_NEAR(road->points.back().x(), 0.0, 1e-9);
  EXPECT_NEAR(road->points.front().y(), -3.6, 1e-9);  // 10 m back: untouched
  EXPECT_GT(road->points[road->points.size() - 2].y(), -3.6);  // moved by less, 1 m back
  EXPECT_LT(road->points[road->points.size() - 2].y(), -3.5);

  map::LaneMap apart = build(1.0, 1.0);
  EXPECT_EQ(mapping::shareDividers(apart, westOakland()), 0u);
  map::LaneMap ends_apart = build(0.08, 0.8);
  EXPECT_EQ(mapping::shareDividers(ends_apart, westOakland()), 0u);
}

}  // namespace
