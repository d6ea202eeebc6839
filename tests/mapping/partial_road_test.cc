// The road a drive ended on, driven only a few metres past its start junction (issue 16; core/
// mapping/partial_road.h). The drive's scoring cuts that road's truth where the car stopped and
// counts its lanes and the junction connections into them; the map used to leave any road driven
// under min_lane_length_m (10 m) unmapped. From partial_min_driven_m (2 m) on it is explored over
// short_road_min_m behind where the car stopped (into the start ROI), and no lane runs past it.
#include "core/mapping/partial_road.h"
#include "core/mapping/road_lanes.h"

#include "tests/lanes/synthetic_bev.h"

#include <gtest/gtest.h>

namespace lanemap {
namespace {

using namespace lanemap::lanes::testing;

// A one-way road of two lanes (3.5 m and 3.4 m), 40 m junction to junction, its start ROI 8 m.
struct TwoLaneRoad {
  Layout layout;
  skeleton::AtomicRoad road;
  TwoLaneRoad() {
    layout.ref.length = 40.0;
    auto& lines = layout.lines;
    lines.push_back({constant(3.45), -1e9, 1e9, Line::kSolid, false});
    lines.push_back({constant(-0.05), -1e9, 1e9, Line::kDashed, true});
    lines.push_back({constant(-3.45), -1e9, 1e9, Line::kSolid, false});
    lines.push_back({constant(3.95), -1e9, 1e9, Line::kCurb, false});
    lines.push_back({constant(-3.95), -1e9, 1e9, Line::kCurb, false});
    layout.areas.push_back({constant(-3.95), constant(3.95)});
    road.id = 4;
    road.from = 10;
    road.to = 11;
    road.polyline = layout.ref.polyline(2.0);
    road.length = 40.0;
    road.s_begin = 8.0;
    road.s_end = 32.0;
  }
};

TEST(PartialRoad, TheStretchOfAFewMetresDrivenReachesBackIntoTheStartRoiNeverPastTheCar) {
  const TwoLaneRoad r;
  const lanes::ExplorerOptions o;
  ASSERT_DOUBLE_EQ(o.partial_min_driven_m, 2.0);
  ASSERT_DOUBLE_EQ(o.short_road_min_m, 6.0);
  // 3.5 m past the ROI: short_road_min_m behind the car.
  const lanes::RoadGeometry g = mapping::drivenStretch(r.road, 11.5, o);
  EXPECT_NEAR(g.s_end, 11.5, 1e-9);
  EXPECT_NEAR(g.s_begin, 5.5, 1e-9);
  // 20 m past it: the road's own stretch, to the car.
  const lanes::RoadGeometry far = mapping::drivenStretch(r.road, 28.0, o);
  EXPECT_NEAR(far.s_begin, 8.0, 1e-9);
  EXPECT_NEAR(far.s_end, 28.0, 1e-9);
  // Past the end ROI: the road's own stretch.
  EXPECT_NEAR(mapping::drivenStretch(r.road, 39.0, o).s_end, 32.0, 1e-9);
  // Under partial_min_driven_m past the ROI, or still inside it: nothing to map, said why.
  EXPECT_THROW(mapping::drivenStretch(r.road, 9.5, o), lanes::LanesError);
  EXPECT_THROW(mapping::drivenStretch(r.road, 6.0, o), lanes::LanesError);
  try {
    mapping::drivenStretch(r.road, 9.5, o);
  } catch (const lanes::LanesError& e) {
    EXPECT_NE(std::string(e.what()).find("road 4: only 1.5 m driven"), std::string::npos) << e.what();
  }
  lanes::ExplorerOptions zero = o;
  zero.partial_min_driven_m = 0.0;
  EXPECT_NO_THROW(mapping::drivenStretch(r.road, 9.5, zero));
}

TEST(PartialRoad, ADriveEndingFourMetresPastAJunctionMapsTheRoadsLanesThatFar) {
  const TwoLaneRoad r;
  const lanes::ExplorerOptions o;
  const bev::BevGrid grid = paint(r.layout);
  const double station = 12.0;  // 4 m past the start ROI
  const lanes::RoadGeometry g = mapping::drivenStretch(r.road, station, o);
  const mapping::RoadLanes out = mapping::exploreRoadLanes(grid, g, map::PartialRoad{station, r.road.length}, o,
                                                           geo::LatLonAlt{49.0, 8.4, 0.0});
  ASSERT_EQ(out.result.lanes.size(), 2u);
  const double truth_d[2] = {1.7, -1.75};  // left to right
  for (const lanes::Lane& l : out.result.lanes) {
    EXPECT_LE(l.s_end, station + 1e-6) << "lane " << l.id << " runs past where the car stopped";
    EXPECT_GE(l.s_end - l.s_begin, 0.8 * o.short_road_min_m - 1e-6) << "lane " << l.id;
    ASSERT_GE(l.index_from_left, 0);
    ASSERT_LE(l.index_from_left, 1);
    for (const auto& p : l.waypoints) {
      EXPECT_NEAR(r.layout.ref.toSD(p).y(), truth_d[l.index_from_left], 0.25) << "lane " << l.id;
      EXPECT_LE(r.layout.ref.toSD(p).x(), station + 1e-6) << "lane " << l.id;
    }
  }
  ASSERT_EQ(out.lanes.lanelets.size(), 2u);
  for (const auto& ll : out.lanes.lanelets) {
    ASSERT_TRUE(ll.partial.has_value()) << "lanelet " << ll.id;
    EXPECT_DOUBLE_EQ(ll.partial->station_m, station);
  }
}

}  // namespace
}  // namespace lanemap
