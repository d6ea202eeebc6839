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

}  // namespace
}  // namespace lanemap::lanes
