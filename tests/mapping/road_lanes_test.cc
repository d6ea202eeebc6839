// One lanelet Lanelet2 would misread costs that lanelet, not the map (core/mapping/road_lanes.h
// dropMisreadLanelets): a road of three lanes, the third splitting off the second half-way, its
// bounds the wrong way round (left bound on the right). writeLanelet2 refuses the road as explored;
// after the drop the two good lanes' three lanelets are written, the dropped lanelet's bounds, its
// stop line and the stop sign of it alone are gone, and so is the split's successor link to it.
#include "core/mapping/road_lanes.h"

#include "core/io/lanelet2.h"
#include "core/lanes/frenet.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace lanemap::mapping {
namespace {

lanes::Lane lane(int id, double d, double s0, double s1, bool swapped, const lanes::FrenetFrame& frame) {
  lanes::Lane l;
  l.id = id;
  l.s_begin = s0;
  l.s_end = s1;
  lanes::PiecewiseLinearFit fit;
  fit.knots = {s0, s1};
  fit.values = {d, d};
  l.centre = lanes::CentreLine(fit, s0, s1);
  for (double s = s0; s <= s1 + 1e-9; s += 2.0) {
    l.waypoint_s.push_back(s);
    l.waypoints.push_back(frame.toEnu(s, d));
    l.left.d.push_back(swapped ? d - 1.7 : d + 1.7);
    l.right.d.push_back(swapped ? d + 1.7 : d - 1.7);
    l.left.points.push_back(frame.toEnu(s, l.left.d.back()));
    l.right.points.push_back(frame.toEnu(s, l.right.d.back()));
  }
  return l;
}

TEST(RoadLanes, AMisreadLaneletIsLeftOutAndTheRestOfTheRoadIsWritten) {
  const lanes::ExplorerOptions o;
  lanes::ExplorationResult r;
  r.road_id = 7;
  r.frame = std::make_shared<lanes::FrenetFrame>(std::vector<Eigen::Vector2d>{{0, 0}, {60, 0}}, o.frame_spacing_m, 0.0);
  r.lanes = {lane(0, 5.25, 0, 60, false, *r.frame), lane(1, 1.75, 0, 60, false, *r.frame), lane(2, -1.75, 30, 60, true, *r.frame)};
  for (int i = 0; i < 3; ++i) r.lanes[i].index_from_left = i;
  r.lanes[2].split_from = 1;
  map::LaneMap m = lanes::toLaneMap(r, 49.0, 8.4, 0.0);
  // Lanes 0 and 1 run side by side and share their border, so both are cut at the split; lane 2.
  ASSERT_EQ(m.lanelets.size(), 5u);
  const auto bad = std::find_if(m.lanelets.begin(), m.lanelets.end(), [](const map::Lanelet& l) { return l.index_from_left == 2; });
  ASSERT_NE(bad, m.lanelets.end());
  const map::Lanelet dropped = *bad;
  const auto parent = std::find_if(m.lanelets.begin(), m.lanelets.end(), [&](const map::Lanelet& l) {
    return std::count(l.successors.begin(), l.successors.end(), dropped.id) > 0;
  });
  ASSERT_NE(parent, m.lanelets.end()) << "the split links lane 1's first piece to lane 2";
  const int64_t parent_id = parent->id;
  // A stop line at the end of the bad lanelet, with a stop sign for it alone, and one at lane 0's end.
  map::LineString stop_bad{900, map::LineType::kStopLine, {{60, -3.4, 0}, {60, -0.1, 0}}};
  map::LineString stop_good{901, map::LineType::kStopLine, {{60, 3.6, 0}, {60, 6.9, 0}}};
  m.lines.push_back(stop_bad);
  m.lines.push_back(stop_good);
  bad->stop_line_id = stop_bad.id;
  int64_t lane0 = -1;
  for (auto& l : m.lanelets) {
    if (l.index_from_left == 0) {
      l.stop_line_id = stop_good.id;
      lane0 = l.id;
    }
  }
  const auto rule = [](int64_t id, map::RegulatoryKind kind, int64_t stop_line, std::vector<int64_t> lanelets,
                       std::vector<int64_t> priority) {
    map::RegulatoryElement r;
    r.id = id;
    r.kind = kind;
    r.stop_line_id = stop_line;
    r.lanelets = std::move(lanelets);
    r.priority = std::move(priority);
    return r;
  };
  m.regulatory_elements.push_back(rule(950, map::RegulatoryKind::kStopSign, stop_bad.id, {dropped.id}, {}));
  m.regulatory_elements.push_back(rule(951, map::RegulatoryKind::kGiveWay, stop_good.id, {lane0}, {dropped.id}));

  lanemap::testing::TempDir tmp("road-lanes");
  try {
    io::writeLanelet2(m, tmp.str("explored.osm"));
    ADD_FAILURE() << "the writer took a lanelet with its left bound on the right";
  } catch (const io::Lanelet2Error& e) {  // for that lanelet
    EXPECT_NE(std::string(e.what()).find("lanelet " + std::to_string(dropped.id)), std::string::npos) << e.what();
  }

  const auto problems = dropMisreadLanelets(m);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("lanelet " + std::to_string(dropped.id) + ":"), std::string::npos) << problems[0];
  EXPECT_NE(problems[0].find("against its driving direction"), std::string::npos) << problems[0];
  ASSERT_EQ(m.lanelets.size(), 4u);
  EXPECT_EQ(m.lanelet(dropped.id), nullptr);
  std::set<int64_t> lines;
  for (const auto& l : m.lines) lines.insert(l.id);
  EXPECT_EQ(lines.size(), 4u * 2u - 2u + 1u) << "the good lanelets' bounds (two shared) and lane 0's stop line";
  EXPECT_EQ(lines.count(dropped.left_id) + lines.count(dropped.right_id) + lines.count(stop_bad.id), 0u);
  for (const auto& l : m.lanelets) {
    EXPECT_EQ(lines.count(l.left_id) + lines.count(l.right_id), 2u) << l.id;
    EXPECT_EQ(std::count(l.successors.begin(), l.successors.end(), dropped.id), 0) << l.id;
  }
  ASSERT_NE(m.lanelet(parent_id), nullptr);
  EXPECT_EQ(m.lanelet(parent_id)->successors.size(), 1u) << "lane 1's second piece is still its successor";
  ASSERT_EQ(m.regulatory_elements.size(), 1u) << "the stop sign of the dropped lanelet alone is gone";
  EXPECT_EQ(m.regulatory_elements[0].id, 951);
  EXPECT_TRUE(m.regulatory_elements[0].priority.empty());
  EXPECT_TRUE(dropMisreadLanelets(m).empty()) << "nothing left to drop";

  ASSERT_NO_THROW(io::writeLanelet2(m, tmp.str("mapped.osm")));
  const auto back = io::readLanelet2(tmp.str("mapped.osm"), 49.0, 8.4);
  EXPECT_EQ(back.lanelets.size(), 4u);
}

}  // namespace
}  // namespace lanemap::mapping
