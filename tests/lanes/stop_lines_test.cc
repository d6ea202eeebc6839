// Stop lines from the BEV (core/lanes/stop_lines.h) on a hand-made grid: a painted bar across both
// lanes of a road becomes one stop line at its middle, shared by both lanelets; a bar over one lane
// only is that lane's; paint over less than min_cover of a lane, or unobserved paint, is none.
#include "core/lanes/stop_lines.h"

#include <gtest/gtest.h>

namespace lanemap::lanes {
namespace {

// Two eastbound lanes x = 0..40 (lanelet 10: lines 1|2 for y 3.5..0, lanelet 11: lines 2|3 for
// y 0..-3.5), sampled every 5 m; the whole road observed 5 times.
struct Road {
  map::LaneMap m;
  bev::BevGrid grid;
  explicit Road(bool observed = true) {
    const auto line = [&](int64_t id, double y) {
      map::LineString l;
      l.id = id;
      l.type = map::LineType::kDashed;
      for (double x = 0; x <= 40.0 + 1e-9; x += 5.0) l.points.emplace_back(x, y, 0.0);
      m.lines.push_back(l);
    };
    line(1, 3.5);
    line(2, 0.0);
    line(3, -3.5);
    for (int k = 0; k < 2; ++k) {
      map::Lanelet ll;
      ll.id = 10 + k;
      ll.left_id = 1 + k;
      ll.right_id = 2 + k;
      ll.index_from_left = k;
      for (size_t i = 0; i < m.lines[0].points.size(); ++i) {
        ll.centre.push_back(0.5 * (m.lines[k].points[i] + m.lines[k + 1].points[i]));
      }
      m.lanelets.push_back(ll);
    }
    if (observed) paint(-1.0, 41.0, -4.0, 4.0, bev::Layer::kObserved, 5);
  }
  void paint(double x0, double x1, double y0, double y1, bev::Layer layer, uint16_t n) {
    for (double x = x0 + 0.05; x < x1; x += 0.1) {
      for (double y = y0 + 0.05; y < y1; y += 0.1) grid.add(grid.cellOf({x, y}), layer, n);
    }
  }
};

TEST(StopLines, BarAcrossBothLanesIsOneStopLineAtItsMiddle) {
  Road r;
  r.paint(36.8, 37.2, -3.5, 3.5, bev::Layer::kStopLine, 4);  // 0.4 m bar at x = 37, 80 % of frames
  ASSERT_EQ(addStopLines(r.grid, r.m), 1u);
  const map::LineString& s = r.m.lines.back();
  EXPECT_EQ(s.type, map::LineType::kStopLine);
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_NEAR(s.points[0].x(), 37.0, 0.1);
  EXPECT_NEAR(s.points[1].x(), 37.0, 0.1);
  EXPECT_NEAR(s.points[0].y(), 3.5, 1e-9);   // the left bound of the left lane
  EXPECT_NEAR(s.points[1].y(), -3.5, 1e-9);  // the right bound of the right lane
  EXPECT_EQ(r.m.lanelets[0].stop_line_id.value_or(-1), s.id);
  EXPECT_EQ(r.m.lanelets[1].stop_line_id.value_or(-1), s.id);
  EXPECT_GT(s.id, 11);  // a fresh id
}

TEST(StopLines, SpansTheLanesByWhereTheyAreNotByTheirIndex) {
  // index_from_left is counted at each lane's middle: two lanes ending side by side can carry it
  // the wrong way round (or the same). The stop line still runs from the left lane's left bound
  // to the right lane's right bound (it was a point where the two share their border: Lanelet2's
  // points_too_close on the demo drive).
  Road r;
  r.m.lanelets[0].index_from_left = 1;
  r.m.lanelets[1].index_from_left = 0;
  r.paint(36.8, 37.2, -3.5, 3.5, bev::Layer::kStopLine, 4);
  ASSERT_EQ(addStopLines(r.grid, r.m), 1u);
  const map::LineString& s = r.m.lines.back();
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_NEAR(s.points[0].y(), 3.5, 1e-9);
  EXPECT_NEAR(s.points[1].y(), -3.5, 1e-9);
}

TEST(StopLines, BarOverOneLaneIsThatLanesOnly) {
  Road r;
  r.paint(30.0, 30.4, -3.5, 0.0, bev::Layer::kStopLine, 5);
  ASSERT_EQ(addStopLines(r.grid, r.m), 1u);
  EXPECT_FALSE(r.m.lanelets[0].stop_line_id.has_value());
  ASSERT_TRUE(r.m.lanelets[1].stop_line_id.has_value());
  const map::LineString& s = r.m.lines.back();
  EXPECT_NEAR(s.points[0].x(), 30.2, 0.1);
  EXPECT_NEAR(s.points[0].y(), 0.0, 1e-9);
  EXPECT_NEAR(s.points[1].y(), -3.5, 1e-9);
}

TEST(StopLines, TooLittleOrUnobservedOrFaintPaintIsNone) {
  Road r;
  r.paint(36.8, 37.2, 2.0, 3.5, bev::Layer::kStopLine, 5);  // 1.5 m of the 3.5 m lane: under 60 %
  r.paint(20.0, 20.4, -3.5, 0.0, bev::Layer::kStopLine, 1);  // seen as paint in 1 of 5 frames
  EXPECT_EQ(addStopLines(r.grid, r.m), 0u);
  // Paint the camera never saw as anything (no kObserved) is no evidence either.
  Road unseen(false);
  unseen.paint(36.8, 37.2, -3.5, 3.5, bev::Layer::kStopLine, 5);
  EXPECT_EQ(addStopLines(unseen.grid, unseen.m), 0u);
  // Beyond search_m (15 m) from the lane's end: not searched.
  Road early;
  early.paint(20.0, 20.4, -3.5, 3.5, bev::Layer::kStopLine, 5);
  EXPECT_EQ(addStopLines(early.grid, early.m), 0u);
  StopLineOptions wide;
  wide.search_m = 25.0;
  EXPECT_EQ(addStopLines(early.grid, early.m, wide), 1u);
}

// Zebra stripes 0.5 m wide every metre across y = -6 .. 6 (beyond both lanes), x = x0 .. x0 + 3.
void zebra(Road& r, double x0) {
  for (double y = -6.0; y < 6.0; y += 1.0) r.paint(x0, x0 + 3.0, y, y + 0.5, bev::Layer::kCrosswalk, 4);
  r.paint(x0 - 1.0, x0 + 4.0, -7.0, 7.0, bev::Layer::kObserved, 5);
}

TEST(Crosswalks, ZebraAtTheRoadsEndIsOneCrossingOverItsWholeWidth) {
  Road r;
  zebra(r, 34.0);
  const auto found = findCrosswalks(r.grid, r.m, 500);
  ASSERT_EQ(found.size(), 1u);
  const map::Crosswalk& c = found[0];
  EXPECT_EQ(c.id, 500);
  EXPECT_EQ(c.crossing, (std::vector<int64_t>{10, 11}));
  // Walking from the right curb (south) to the left one (north): the left edge is the one
  // nearer the road's start (x = 34), the right edge the far one (x = 37).
  ASSERT_EQ(c.left.size(), 2u);
  EXPECT_NEAR(c.left[0].x(), 34.0, 0.15);
  EXPECT_NEAR(c.right[0].x(), 37.0, 0.15);
  EXPECT_LT(c.left[0].y(), c.left[1].y());
  // Beyond the lanes (|y| <= 3.5) as far as the stripes go (the last one ends at y = 5.5).
  EXPECT_NEAR(c.left[0].y(), -6.0, 0.2);
  EXPECT_NEAR(c.left[1].y(), 5.5, 0.2);
  // At the road's start too; and a map takes both, with fresh ids.
  Road both;
  zebra(both, 34.0);
  zebra(both, 2.0);
  const auto two = findCrosswalks(both.grid, both.m, 1);
  ASSERT_EQ(two.size(), 2u);
  map::LaneMap m = both.m;
  EXPECT_EQ(addCrosswalks(m, two), 2u);
  EXPECT_GT(std::min(m.crosswalks[0].id, m.crosswalks[1].id), 11);
  // The same crossing found twice (e.g. from both directions) is one.
  auto dup = found;
  dup.push_back(found[0]);
  dup.back().crossing = {77};
  mergeCrosswalks(dup);
  ASSERT_EQ(dup.size(), 1u);
  EXPECT_EQ(dup[0].crossing, (std::vector<int64_t>{10, 11, 77}));
}

// A lane tapering to its end (3.5 m wide to x = 38, 2 cm at x = 40), crossing paint over it from
// x = 34 to its tip, none beyond it: the crossing's far edge is
// where the lane is still min_edge_m (1 m) wide, not at the tip (lanelet2_validate's
// points_too_close, seen on a fused West Oakland map: an edge of 9 mm).
TEST(Crosswalks, ALaneTaperingToAPointGivesNoEdgeShorterThanMinEdge) {
  Road r;
  r.m = map::LaneMap();
  map::LineString left, right;
  left.id = 1;
  right.id = 2;
  for (const double x : {0.0, 10.0, 20.0, 30.0, 34.0, 38.0, 40.0}) {
    left.points.emplace_back(x, x <= 38.0 ? 3.5 : 0.02, 0.0);
    right.points.emplace_back(x, 0.0, 0.0);
  }
  map::Lanelet ll;
  ll.id = 10;
  ll.left_id = 1;
  ll.right_id = 2;
  for (size_t i = 0; i < left.points.size(); ++i) ll.centre.push_back(0.5 * (left.points[i] + right.points[i]));
  r.m.lines = {left, right};
  r.m.lanelets = {ll};
  r.paint(33.0, 41.0, -1.0, 4.0, bev::Layer::kObserved, 5);
  for (double x = 34.0; x < 40.0 - 1e-9; x += 0.1) {  // over the lane's cells, none beyond its left bound
    const double w = x + 0.05 <= 38.0 ? 3.5 : 3.5 + (0.02 - 3.5) * (x + 0.05 - 38.0) / 2.0;
    r.paint(x, x + 0.1, 0.0, w, bev::Layer::kCrosswalk, 4);
  }
  const auto found = findCrosswalks(r.grid, r.m, 1);
  ASSERT_EQ(found.size(), 1u);
  for (const auto* edge : {&found[0].left, &found[0].right}) {
    ASSERT_EQ(edge->size(), 2u);
    EXPECT_GE((edge->back() - edge->front()).head<2>().norm(), 1.0 - 1e-9);
  }
  // The far edge (the right one, at the road's end) is where the lane is 1 m wide: x = 39.43.
  EXPECT_NEAR(found[0].right[0].x(), 39.43, 0.15);
  EXPECT_NEAR(found[0].left[0].x(), 34.0, 0.15);
}

TEST(Crosswalks, ThinOrShallowPaintIsNone) {
  Road r;
  // One stripe across 1 m of the 7 m road: under 30 % of the samples.
  r.paint(34.0, 37.0, 0.0, 1.0, bev::Layer::kCrosswalk, 5);
  EXPECT_TRUE(findCrosswalks(r.grid, r.m, 1).empty());
  // Zebra stripes only 1 m deep along the road: under min_depth_m (1.5 m).
  Road s;
  for (double y = -3.5; y < 3.5; y += 1.0) s.paint(34.0, 35.0, y, y + 0.5, bev::Layer::kCrosswalk, 5);
  EXPECT_TRUE(findCrosswalks(s.grid, s.m, 1).empty());
}

}  // namespace
}  // namespace lanemap::lanes
