// Lanes carried through a short road (issue 16; core/lanes/carried_lanes.h, core/mapping/
// carried_lanes.h). A 12 m link between two junctions seen only from inside them has no drivable
// cell: exploring it finds nothing, and it takes the lanes of the road leading straight into it.
// On the simulator's West Oakland world (its truth's road lanelets standing for mapped roads),
// the lanes carried into every road whose road before (or after) runs straight on with as many
// lanes lie on that road's own truth lanes; a turn carries nothing; a road where exploring found
// lanes keeps them.
#include "core/lanes/carried_lanes.h"
#include "core/mapping/carried_lanes.h"
#include "core/mapping/road_lanes.h"

#include "core/lanes/frenet.h"
#include "tests/common/truth_world.h"
#include "tests/lanes/synthetic_bev.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <vector>

namespace lanemap {
namespace {

using World = lanemap::testing::TruthWorld;

// Lateral offsets (road frame) of a road's truth lanes where `s` is.
std::vector<double> truthOffsets(const map::LaneMap& m, const lanes::FrenetFrame& frame, double s) {
  std::vector<double> out;
  for (const auto& ll : m.lanelets) {
    if (ll.kind != map::LaneletKind::kRoad || ll.centre.size() < 2) continue;
    double best = INFINITY, d = 0.0;
    for (const auto& p : ll.centre) {
      const Eigen::Vector2d sd = frame.toFrenet(p.head<2>());
      if (std::abs(sd.x() - s) < best) {
        best = std::abs(sd.x() - s);
        d = sd.y();
      }
    }
    if (best < 2.0) out.push_back(d);
  }
  return out;
}

size_t laneCount(const map::LaneMap& m) {
  std::set<int> idx;
  for (const auto& ll : m.lanelets) {
    if (ll.kind == map::LaneletKind::kRoad) idx.insert(ll.index_from_left);
  }
  return idx.size();
}

// The lanes carried into every road from the road before it (or after it) that runs straight on
// with as many lanes lie on the road's own truth lanes, at the end they come through.
enum class From { kBefore, kAfter };

void carriedLanesLieOnTheTruth(From from) {
  const bool before_it = from == From::kBefore;
  const auto carry = before_it ? &mapping::lanesLeadingInto : &mapping::lanesLeadingOutOf;
  const World& w = lanemap::testing::westOaklandTruthWorld();
  lanes::ExplorerOptions o;
  o.carry_lanes_max_m = 1e9;  // every road as if short: West Oakland's are long, their truth is known
  int compared = 0, turns = 0, shorts = 0;
  for (const auto& road : w.sk->roads()) {
    auto own = w.roads.find(road.id);
    if (own == w.roads.end() || own->second.lanelets.empty()) continue;
    std::map<int64_t, map::LaneMap> others = w.roads;
    others.erase(road.id);  // the road itself is not mapped yet
    int64_t before = -1;
    const auto carried = carry(*w.sk, road, others, o, &before);
    if (carried.empty()) {
      // Roads meeting it at that end that are mapped but all turn: nothing carried.
      const auto* junction = w.sk->intersection(before_it ? road.from : road.to);
      for (int64_t id : before_it ? junction->incoming : junction->outgoing) turns += id != road.reverse_id && w.roads.count(id) > 0;
      continue;
    }
    ASSERT_GE(before, 0);
    EXPECT_NE(before, road.reverse_id);
    if (before_it) {  // what a short road takes: the road before's lanes first
      int64_t via = -1;
      EXPECT_EQ(mapping::lanesRunningThrough(*w.sk, road, others, o, &via).size(), carried.size());
      EXPECT_EQ(via, before);
    }
    const bool short_road = road.s_end - road.s_begin < lanes::ExplorerOptions{}.carry_lanes_max_m;
    EXPECT_EQ(carry(*w.sk, road, others, lanes::ExplorerOptions{}, nullptr).size(), short_road ? carried.size() : 0)
        << "road " << road.id << ": with the shipped options only a short road is looked at";
    shorts += short_road;
    if (laneCount(w.roads.at(before)) != laneCount(own->second)) continue;  // offsets move with the count
    const lanes::RoadGeometry geometry = lanes::RoadGeometry::fromSkeleton(road);
    const lanes::ExplorationResult r = lanes::carryLanesThrough(geometry, carried, o);
    ASSERT_EQ(r.lanes.size(), carried.size()) << "road " << road.id;
    for (size_t k = 0; k < r.lanes.size(); ++k) {
      const lanes::Lane& lane = r.lanes[k];
      EXPECT_EQ(lane.index_from_left, static_cast<int>(k));
      const double s = before_it ? lane.s_begin : lane.s_end;  // its end by the junction it came through
      if (k > 0) {
        EXPECT_LT(lane.centre.d(s), r.lanes[k - 1].centre.d(s)) << "left to right";
      }
      // There, on a truth lane of this road.
      const auto truth = truthOffsets(own->second, *r.frame, s);
      ASSERT_FALSE(truth.empty()) << "road " << road.id;
      double nearest = INFINITY;
      for (double d : truth) nearest = std::min(nearest, std::abs(d - lane.centre.d(s)));
      EXPECT_LT(nearest, 0.25) << "road " << road.id << " lane " << k << " carried from road " << before;
      // Its bounds a lane's width apart.
      EXPECT_GT(lane.left.d.front() - lane.right.d.front(), 2.5) << "road " << road.id;
      EXPECT_LT(lane.left.d.front() - lane.right.d.front(), 4.5) << "road " << road.id;
      EXPECT_EQ(lane.particle_samples, 0) << "no particle supports a carried lane";
    }
    ++compared;
  }
  std::printf("%s: roads compared: %d (%d short); mapped roads turning at that end: %d\n", before_it ? "before" : "after", compared, shorts, turns);
  EXPECT_GE(compared, 20);
  EXPECT_GT(turns, 0);
}

TEST(CarriedLanes, TheLanesOfTheRoadBeforeLieOnTheTruthOfEveryRoadThatRunsStraightOn) { carriedLanesLieOnTheTruth(From::kBefore); }

TEST(CarriedLanes, TheLanesOfTheRoadAfterLieOnTheTruthOfEveryRoadThatRunsStraightOn) { carriedLanesLieOnTheTruth(From::kAfter); }

lanes::RoadGeometry link(double length, double roi) {
  lanes::RoadGeometry g;
  g.road_id = 11;
  g.from_node = 1;
  g.to_node = 2;
  g.polyline = {{0.0, 0.0}, {length, 0.0}};
  g.s_begin = roi;
  g.s_end = length - roi;
  return g;
}

std::vector<lanes::CarriedLane> twoLanes() {
  lanes::CarriedLane a, b;
  a.d = 1.75;
  a.left_type = map::LineType::kCurb;
  a.right_type = map::LineType::kDashed;
  b.d = -1.75;
  b.half_left_m = 1.75;
  b.half_right_m = 1.6;
  b.left_type = map::LineType::kDashed;
  b.right_type = map::LineType::kSolid;
  return {b, a};  // any order
}

// A 12 m link (30 m junction to junction, the ROIs leave 12 m) seen only from the junctions: not
// one cell of it labelled drivable. Exploring finds no lane; the road before's two lanes run on.
TEST(CarriedLanes, ATwelveMetreLinkSeenOnlyFromTheJunctionsTakesThem) {
  const lanes::ExplorerOptions o;
  bev::BevGrid grid;  // junction ground: observed, background, across the whole corridor
  for (int i = -10; i < 310; ++i) {
    for (int j = -170; j < 170; ++j) grid.add(bev::BevGrid::Cell(i, j), bev::Layer::kObserved, 6);
  }
  const lanes::RoadGeometry g = link(30.0, 9.0);
  const geo::LatLonAlt origin{49.0, 8.4, 0.0};
  const mapping::RoadLanes alone = mapping::exploreRoadLanes(grid, g, std::nullopt, o, origin);
  EXPECT_TRUE(alone.result.lanes.empty()) << "nothing drivable: nothing explored";
  EXPECT_FALSE(alone.lanes_carried);

  const mapping::RoadLanes carried = mapping::exploreRoadLanes(grid, g, std::nullopt, o, origin, twoLanes());
  EXPECT_TRUE(carried.lanes_carried);
  ASSERT_EQ(carried.result.lanes.size(), 2u);
  const lanes::Lane& left = carried.result.lanes[0];
  const lanes::Lane& right = carried.result.lanes[1];
  EXPECT_DOUBLE_EQ(left.centre.d(15.0), 1.75);
  EXPECT_DOUBLE_EQ(right.centre.d(15.0), -1.75);
  EXPECT_NEAR(left.s_begin, 9.0, 1e-9);
  EXPECT_NEAR(left.s_end, 21.0, 1e-9);
  EXPECT_EQ(left.left.type, map::LineType::kCurb);
  EXPECT_EQ(right.right.type, map::LineType::kSolid);
  EXPECT_NEAR(right.right.d[3], -3.35, 1e-9);
  // As lanelets: two, side by side, sharing their border (toLaneMap), each 12 m long.
  ASSERT_EQ(carried.lanes.lanelets.size(), 2u);
  EXPECT_EQ(carried.lanes.lanelets[0].right_id == carried.lanes.lanelets[1].left_id ||
                carried.lanes.lanelets[1].right_id == carried.lanes.lanelets[0].left_id,
            true);
  for (const auto& ll : carried.lanes.lanelets) {
    EXPECT_NEAR((ll.centre.back() - ll.centre.front()).head<2>().norm(), 12.0, 0.05);
  }

  // A long road is explored, never carried (its own evidence is the map): 40 m between the ROIs.
  const lanes::RoadGeometry long_road = link(58.0, 9.0);
  EXPECT_FALSE(mapping::exploreRoadLanes(grid, long_road, std::nullopt, o, origin, twoLanes()).lanes_carried);
  // Nor is the road the drive ended on (partial: mapped as far as driven, nothing more).
  EXPECT_FALSE(mapping::exploreRoadLanes(grid, g, map::PartialRoad{21.0, 30.0}, o, origin, twoLanes()).lanes_carried);
  // Nor anything with carry_lanes_max_m 0.
  lanes::ExplorerOptions off = o;
  off.carry_lanes_max_m = 0.0;
  EXPECT_FALSE(mapping::exploreRoadLanes(grid, g, std::nullopt, off, origin, twoLanes()).lanes_carried);
}

// A 30 m painted layout's road as a link whose ROIs leave its 12 m between s 9 and 21.
lanes::RoadGeometry linkAlong(const lanes::testing::Layout& L) {
  lanes::RoadGeometry g;
  g.road_id = 5;
  g.polyline = L.ref.polyline();
  g.s_begin = 9.0;
  g.s_end = 21.0;
  return g;
}

// Where exploring found lanes, they stay, even when the road before brings others (its lanes sit
// elsewhere relative to the OSM line when the count changes at the junction).
TEST(CarriedLanes, ARoadWhoseLanesWereFoundKeepsThem) {
  using namespace lanes::testing;
  Layout L;
  L.ref.length = 30.0;
  L.lines.push_back({constant(3.5), -1e9, 1e9, Line::kSolid, false});
  L.lines.push_back({constant(0.0), -1e9, 1e9, Line::kDashed, true});
  L.lines.push_back({constant(-3.5), -1e9, 1e9, Line::kSolid, false});
  L.areas.push_back({constant(-3.5), constant(3.5)});
  const bev::BevGrid grid = paint(L);
  const lanes::RoadGeometry g = linkAlong(L);
  const lanes::ExplorerOptions o;
  std::vector<lanes::CarriedLane> three(3);
  three[0].d = 3.5;
  three[1].d = 0.0;
  three[2].d = -3.5;
  const mapping::RoadLanes r = mapping::exploreRoadLanes(grid, g, std::nullopt, o, {49.0, 8.4, 0.0}, three);
  EXPECT_FALSE(r.lanes_carried);
  ASSERT_EQ(r.result.lanes.size(), 2u);
  for (const auto& lane : r.result.lanes) {
    EXPECT_NEAR(lane.centre.d(15.0), lane.index_from_left == 0 ? 1.75 : -1.75, 0.2) << "explored, where the lanes are";
  }
}

TEST(CarriedLanes, OneLaneCarriedTwiceIsOneLane) {
  lanes::ExplorerOptions o;
  std::vector<lanes::CarriedLane> c(3);
  c[0].d = -1.7;
  c[1].d = 1.8;
  c[2].d = -1.2;  // within same_lane_m (1.2 m) of -1.7? 0.5 m: the same lane
  const lanes::ExplorationResult r = lanes::carryLanesThrough(link(30.0, 9.0), c, o);
  ASSERT_EQ(r.lanes.size(), 2u);
  EXPECT_DOUBLE_EQ(r.lanes[0].centre.d(12.0), 1.8);
  EXPECT_DOUBLE_EQ(r.lanes[1].centre.d(12.0), -1.2);  // the left one of the two stays
  EXPECT_THROW(lanes::carryLanesThrough(link(30.0, 9.0), {}, o), lanes::LanesError);
  // A 4 m link (under short_road_min_m) is carried over the 6 m around its middle, as explored.
  const lanes::ExplorationResult shortest = lanes::carryLanesThrough(link(20.0, 8.0), c, o);
  EXPECT_NEAR(shortest.lanes[0].s_end - shortest.lanes[0].s_begin, o.short_road_min_m, 1e-9);
}

// A link no mapped road runs straight into or out of (the crossing between the two carriageways of
// a divided road, entered and left by turns) takes its own OSM way's lanes: their count from the
// way's tags, default widths, right of a two-way way's line, centred on a one-way way's.
skeleton::AtomicRoad osmLink(bool two_way, const osm::Tags& tags, bool along_way = true) {
  skeleton::AtomicRoad r;
  r.id = 7;
  r.from = 1;
  r.to = 2;
  r.reverse_id = two_way ? 8 : -1;
  r.along_way = along_way;
  r.polyline = {{0.0, 0.0}, {20.0, 0.0}};
  r.length = 20.0;
  r.s_begin = 6.0;
  r.s_end = 14.0;  // 8 m between the ROIs: short
  r.tags = tags;
  return r;
}

std::vector<double> offsets(const std::vector<lanes::CarriedLane>& lanes) {
  std::vector<double> d;
  for (const auto& l : lanes) d.push_back(l.d);
  return d;
}

TEST(CarriedLanes, ALinkNothingRunsStraightIntoTakesItsOwnOsmWaysLanes) {
  lanes::ExplorerOptions o;
  using V = std::vector<double>;
  // Two-way: one lane a direction unless the tags say more, right of the line, left to right.
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(true, {}), o)), (V{-1.75}));
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(true, {{"lanes", "4"}}), o)), (V{-1.75, -5.25}));
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(true, {{"lanes", "3"}}), o)), (V{-1.75, -5.25}));  // rounded up
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(true, {{"lanes", "3"}, {"lanes:forward", "1"}, {"lanes:backward", "2"}}), o)),
            (V{-1.75}));
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(true, {{"lanes", "3"}, {"lanes:forward", "1"}, {"lanes:backward", "2"}}, false), o)),
            (V{-1.75, -5.25}));  // against the way's direction: its backward lanes
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(true, {{"lanes", "2;3"}}), o)), (V{-1.75}));  // not a count: one
  // One-way: centred on the line.
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(false, {}), o)), (V{0.0}));
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(false, {{"lanes", "3"}}), o)), (V{3.5, 0.0, -3.5}));
  // Left-hand traffic: left of the line, still left to right.
  lanes::ExplorerOptions left = o;
  left.right_hand_traffic = false;
  EXPECT_EQ(offsets(mapping::lanesFromOsmWay(osmLink(true, {{"lanes", "4"}}), left)), (V{5.25, 1.75}));
  for (const auto& l : mapping::lanesFromOsmWay(osmLink(true, {{"lanes", "4"}}), o)) {
    EXPECT_EQ(l.half_left_m, o.default_half_width_m);
    EXPECT_EQ(l.half_right_m, o.default_half_width_m);
    EXPECT_EQ(l.left_type, map::LineType::kVirtual) << "nothing was seen of its lines";
  }
  // A road that is not short: nothing (its own evidence decides, or it has no lane).
  skeleton::AtomicRoad long_road = osmLink(true, {});
  long_road.s_end = 6.0 + o.carry_lanes_max_m + 1.0;
  EXPECT_TRUE(mapping::lanesFromOsmWay(long_road, o).empty());

  // lanesRunningThrough falls back to them, naming the road itself, only when asked to.
  const std::map<int64_t, map::LaneMap> none;
  const World& w = lanemap::testing::westOaklandTruthWorld();
  // Any West Oakland road as if short, with no road mapped around it.
  lanes::ExplorerOptions all_short = o;
  all_short.carry_lanes_max_m = 1e9;
  const skeleton::AtomicRoad& some = w.sk->roads().front();
  int64_t via = -1;
  EXPECT_FALSE(mapping::lanesRunningThrough(*w.sk, some, none, all_short, &via).empty());
  EXPECT_EQ(via, some.id);
  all_short.lanes_from_osm_way = false;
  EXPECT_TRUE(mapping::lanesRunningThrough(*w.sk, some, none, all_short, &via).empty());
  EXPECT_EQ(via, -1);
}

// On the simulator's West Oakland world (every road as if short, its truth known): where the
// truth has as many lanes this way as the OSM way says, the OSM way's lanes lie near the truth's.
TEST(CarriedLanes, TheOsmWaysLanesLieNearTheTruthWhereTheCountsAgree) {
  const World& w = lanemap::testing::westOaklandTruthWorld();
  lanes::ExplorerOptions o;
  o.carry_lanes_max_m = 1e9;
  std::vector<double> errors;
  int counts_differ = 0;
  for (const auto& road : w.sk->roads()) {
    auto own = w.roads.find(road.id);
    if (own == w.roads.end() || own->second.lanelets.empty()) continue;
    const auto lanes = mapping::lanesFromOsmWay(road, o);
    const lanes::RoadGeometry geometry = lanes::RoadGeometry::fromSkeleton(road);
    const lanes::ExplorationResult r = lanes::carryLanesThrough(geometry, lanes, o);
    const double s = 0.5 * (r.lanes.front().s_begin + r.lanes.front().s_end);
    const auto truth = truthOffsets(own->second, *r.frame, s);
    if (truth.size() != lanes.size()) {
      ++counts_differ;
      continue;
    }
    for (const auto& lane : r.lanes) {
      double nearest = INFINITY;
      for (double d : truth) nearest = std::min(nearest, std::abs(d - lane.centre.d(s)));
      errors.push_back(nearest);
    }
  }
  ASSERT_GE(errors.size(), 20u);
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2];
  const double within_half_metre = static_cast<double>(std::upper_bound(errors.begin(), errors.end(), 0.5) - errors.begin()) / errors.size();
  std::printf("OSM way's lanes vs truth: %zu lanes, median %.2f m, %.0f %% within 0.5 m; roads whose counts differ: %d\n",
              errors.size(), median, 100.0 * within_half_metre, counts_differ);
  EXPECT_LT(median, 0.3) << "a lane from the OSM way lies off its truth lane";
  EXPECT_GT(within_half_metre, 0.9);
}

// Lanes at these offsets over a link's explored stretch, as exploring would give them.
lanes::ExplorationResult exploredAt(const lanes::RoadGeometry& g, const std::vector<double>& offsets) {
  std::vector<lanes::CarriedLane> c;
  for (double d : offsets) {
    c.emplace_back();
    c.back().d = d;
  }
  return lanes::carryLanesThrough(g, c, lanes::ExplorerOptions());
}

std::vector<double> offsetsOf(const lanes::ExplorationResult& r) {
  std::vector<double> out;
  for (const auto& lane : r.lanes) out.push_back(lane.centre.d(0.5 * (lane.s_begin + lane.s_end)));
  return out;
}

// A sausage link (aurora_sausage_link on the model's labels): a 12 m link of a divided road whose
// island the carriageway walk did not see along most of a bin; exploring found the other
// carriageway's two lanes across it (7.6 and 11.2 m left) besides the link's own two. The road
// before runs on with two lanes at +-1.75 m: the two across the island are dropped. A lane added
// beside the carried ones (a flare, 3.5 m on) stays; so does everything when the carried lanes
// are the link's own OSM way's (nothing seen), when the road is not short, when exploring found no
// more lanes than were carried, or with the option off.
TEST(CarriedLanes, AShortRoadsLanesAcrossAnIslandFromTheCarriedOnesAreDropped) {
  const lanes::ExplorerOptions o;
  const lanes::RoadGeometry g = link(30.0, 9.0);
  lanes::ExplorationResult r = exploredAt(g, {1.9, -1.8, 7.6, 11.2});  // left to right: 11.2, 7.6, 1.9, -1.8
  r.lanes[2].split_from = 1;  // a link to a dropped lane goes with it
  r.lanes[3].split_from = 2;  // one to a kept lane is renumbered
  EXPECT_EQ(lanes::dropLanesApartFromCarried(g, twoLanes(), o, &r), 2);
  ASSERT_EQ(r.lanes.size(), 2u);
  EXPECT_NEAR(offsetsOf(r)[0], 1.9, 1e-9);
  EXPECT_NEAR(offsetsOf(r)[1], -1.8, 1e-9);
  for (size_t k = 0; k < r.lanes.size(); ++k) {
    EXPECT_EQ(r.lanes[k].id, static_cast<int>(k));
    EXPECT_EQ(r.lanes[k].index_from_left, static_cast<int>(k));
  }
  EXPECT_EQ(r.lanes[0].split_from, -1);
  EXPECT_EQ(r.lanes[1].split_from, 0);

  // The road before had a lane across the island itself (5.9 m left, 7.6 m from its own): only
  // its own carriageway's lanes count.
  lanes::CarriedLane own, across;
  own.d = -1.67;
  across.d = 5.93;
  r = exploredAt(g, {-1.76, 1.92, 8.11, 11.67});
  EXPECT_EQ(lanes::dropLanesApartFromCarried(g, {own, across}, o, &r), 2);
  ASSERT_EQ(r.lanes.size(), 2u);
  EXPECT_NEAR(offsetsOf(r)[0], 1.92, 1e-9);

  // One-way: one lane carried on the OSM line, two explored half a lane either side of it (the
  // line is the carriageway's middle: it moved where the count changed), and one 6.25 m on.
  lanes::CarriedLane one;
  r = exploredAt(g, {1.75, -1.75, 8.0});
  EXPECT_EQ(lanes::dropLanesApartFromCarried(g, {one}, o, &r), 1);
  ASSERT_EQ(r.lanes.size(), 2u);
  EXPECT_NEAR(offsetsOf(r)[0], 1.75, 1e-9);

  // A lane beside the carried ones: kept, and one beside it too.
  r = exploredAt(g, {1.75, -1.75, -5.25, -8.75});
  EXPECT_EQ(lanes::dropLanesApartFromCarried(g, twoLanes(), o, &r), 0);
  EXPECT_EQ(r.lanes.size(), 4u);

  auto osm_way = twoLanes();
  for (auto& c : osm_way) c.seen = false;
  r = exploredAt(g, {1.9, -1.8, 7.6, 11.2});
  EXPECT_EQ(lanes::dropLanesApartFromCarried(g, osm_way, o, &r), 0);
  const lanes::RoadGeometry long_road = link(58.0, 9.0);
  r = exploredAt(long_road, {1.9, -1.8, 7.6, 11.2});
  EXPECT_EQ(lanes::dropLanesApartFromCarried(long_road, twoLanes(), o, &r), 0);
  r = exploredAt(g, {1.9, 7.6});
  EXPECT_EQ(lanes::dropLanesApartFromCarried(g, twoLanes(), o, &r), 0);
  lanes::ExplorerOptions off = o;
  off.drop_lanes_apart_from_carried = false;
  r = exploredAt(g, {1.9, -1.8, 7.6, 11.2});
  EXPECT_EQ(lanes::dropLanesApartFromCarried(g, twoLanes(), off, &r), 0);
  EXPECT_EQ(r.lanes.size(), 4u);
}

// The same through exploreRoadLanes on painted evidence: a 12 m link whose island (2 m wide, 1.75
// m left of the link's left lane) and its kerbs were seen over 5 m only (the walk needs a wall
// along 80 % of a 10 m bin, a kerb along 70 %), the ground beyond it labelled drivable, the other
// carriageway's two lanes beyond. Explored alone: its own two lanes and more; with the road
// before's two lanes carried: its own two.
TEST(CarriedLanes, ALinkBesideTheOtherCarriagewayKeepsItsOwnLanes) {
  using namespace lanes::testing;
  Layout L;
  L.ref.length = 30.0;
  L.lines.push_back({constant(-3.5), -1e9, 1e9, Line::kCurb, false});
  L.lines.push_back({constant(0.0), -1e9, 1e9, Line::kDashed, true});
  L.lines.push_back({constant(3.5), 13.0, 18.0, Line::kCurb, false});   // the island's kerbs, seen in part
  L.lines.push_back({constant(5.5), 13.0, 18.0, Line::kCurb, false});
  L.lines.push_back({constant(9.0), -1e9, 1e9, Line::kDashed, true});   // the other carriageway
  L.lines.push_back({constant(12.5), -1e9, 1e9, Line::kCurb, false});
  L.areas.push_back({constant(-3.5), constant(12.5)});
  L.boxes.push_back({13.0, 18.0, 3.65, 5.35});  // the island: ground, not drivable, where it is seen
  const bev::BevGrid grid = paint(L);
  const lanes::RoadGeometry g = linkAlong(L);
  const lanes::ExplorerOptions o;
  const geo::LatLonAlt origin{49.0, 8.4, 0.0};
  const mapping::RoadLanes alone = mapping::exploreRoadLanes(grid, g, std::nullopt, o, origin);
  EXPECT_GE(alone.result.lanes.size(), 3u) << "the other carriageway explored as ours";
  const mapping::RoadLanes with = mapping::exploreRoadLanes(grid, g, std::nullopt, o, origin, twoLanes());
  EXPECT_FALSE(with.lanes_carried);
  EXPECT_EQ(with.lanes_apart_dropped, static_cast<int>(alone.result.lanes.size()) - 2);
  ASSERT_EQ(with.result.lanes.size(), 2u);
  EXPECT_EQ(with.lanes.lanelets.size(), 2u);
  for (const auto& lane : with.result.lanes) {
    EXPECT_NEAR(lane.centre.d(15.0), lane.index_from_left == 0 ? 1.75 : -1.75, 0.3);
  }
}


// A link whose second lane exploring missed (seattle_slip_lane, fremantle_placement on the model's
// labels: over a link's few metres, seen from inside the junctions, the segmentation names the ego
// lane's cross-section only, and a lane's ground can be all background). The road before runs on
// with two lanes at +-1.75 m; exploring found the left one: the right one is added as wide as it
// was carried (3.35 m) against the explored lane's right bound, with its line types, over the
// explored lane's stretch, with no particle behind it.
// Nothing is added when the explored lanes fit the carried ones only with the line moved by half a
// lane (the count changed at the junction) or only loosely, when an explored lane matches none,
// beyond a kerb of the explored lanes, for lanes from the link's own OSM way (nothing seen), on a
// road that is not short, or with the option off.
TEST(CarriedLanes, AShortRoadsLanesExploringMissedAreAddedFromTheCarriedOnes) {
  const lanes::ExplorerOptions o;
  const lanes::RoadGeometry g = link(30.0, 9.0);
  lanes::ExplorationResult r = exploredAt(g, {1.8});
  r.lanes[0].particle_samples = 500;
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, twoLanes(), o, &r), 1);
  ASSERT_EQ(r.lanes.size(), 2u);
  EXPECT_NEAR(offsetsOf(r)[0], 1.8, 1e-9);
  EXPECT_NEAR(offsetsOf(r)[1], 0.05 - 3.35 / 2, 1e-9);  // the explored lane's right bound is at 0.05
  for (size_t k = 0; k < r.lanes.size(); ++k) {
    EXPECT_EQ(r.lanes[k].id, static_cast<int>(k));
    EXPECT_EQ(r.lanes[k].index_from_left, static_cast<int>(k));
    EXPECT_DOUBLE_EQ(r.lanes[k].s_begin, r.lanes[0].s_begin);
    EXPECT_DOUBLE_EQ(r.lanes[k].s_end, r.lanes[0].s_end);
  }
  const lanes::Lane& added = r.lanes[1];
  EXPECT_EQ(added.particle_samples, 0);
  EXPECT_EQ(r.lanes[0].particle_samples, 500);
  ASSERT_FALSE(added.left.d.empty());
  for (size_t i = 0; i < added.left.d.size(); ++i) {
    EXPECT_NEAR(added.left.d[i], 0.05, 1e-9);  // on the explored lane's bound
    EXPECT_NEAR(added.right.d[i], 0.05 - 3.35, 1e-9);
  }
  const auto shared = lanes::laneNeighbours(r);
  ASSERT_EQ(shared.size(), 1u);  // one border line string between them
  EXPECT_EQ(shared[0].left, 0);
  EXPECT_EQ(shared[0].right, 1);
  EXPECT_EQ(added.left.type, map::LineType::kDashed);
  EXPECT_EQ(added.right.type, map::LineType::kSolid);

  // One-way, three lanes carried about the line; exploring found the left two, 0.1 m off: the
  // right one is added against the middle one (its right bound at -1.65).
  std::vector<lanes::CarriedLane> three(3);
  three[0].d = 3.5;
  three[1].d = 0.0;
  three[2].d = -3.5;
  r = exploredAt(g, {3.4, 0.1});
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, three, o, &r), 1);
  ASSERT_EQ(r.lanes.size(), 3u);
  EXPECT_NEAR(offsetsOf(r)[2], -3.4, 1e-9);

  // Two lanes half a lane either side of the line: they fit the three only with the line moved,
  // the link has two lanes.
  r = exploredAt(g, {1.75, -1.75});
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, three, o, &r), 0);
  EXPECT_EQ(r.lanes.size(), 2u);
  // Matched only loosely (0.9 m off under any shift of up to 0.6 m): not where the carried lanes are.
  r = exploredAt(g, {-1.71, 1.71});
  std::vector<lanes::CarriedLane> three_off = three;
  for (auto& c : three_off) c.d += 0.3;  // -3.2, 0.3, 3.8 (aurora_sausage_link road 8)
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, three_off, o, &r), 0);
  // A lane matching no carried one.
  r = exploredAt(g, {0.1, -8.0});
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, three, o, &r), 0);
  // A kerb beside the explored lane on the side the missing one would be: the carriageway ends.
  r = exploredAt(g, {1.8});
  r.lanes[0].right.type = map::LineType::kCurb;
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, twoLanes(), o, &r), 0);
  r.lanes[0].right.type = map::LineType::kDashed;
  r.lanes[0].left.type = map::LineType::kCurb;  // the other side: no matter
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, twoLanes(), o, &r), 1);
  auto osm_way = twoLanes();
  for (auto& c : osm_way) c.seen = false;
  r = exploredAt(g, {1.8});
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, osm_way, o, &r), 0);
  const lanes::RoadGeometry long_road = link(58.0, 9.0);
  r = exploredAt(long_road, {1.8});
  EXPECT_EQ(lanes::addCarriedLanesNotFound(long_road, twoLanes(), o, &r), 0);
  lanes::ExplorerOptions off = o;
  off.add_carried_lanes_not_found = false;
  r = exploredAt(g, {1.8});
  EXPECT_EQ(lanes::addCarriedLanesNotFound(g, twoLanes(), off, &r), 0);
  EXPECT_EQ(r.lanes.size(), 1u);
}

// The same through exploreRoadLanes on painted evidence: a 12 m two-lane link whose right lane was
// seen but neither its ground labelled drivable nor the dashed line between the lanes caught (a
// blocked strip between painted lines would be a lane the segmentation does not name). Explored
// alone: one lane; with the road before's two lanes carried: both, the right one where it was
// carried.
TEST(CarriedLanes, ALinkGetsTheLaneItsEvidenceMissedFromTheRoadBefore) {
  using namespace lanes::testing;
  Layout L;
  L.ref.length = 30.0;
  L.lines.push_back({constant(3.5), -1e9, 1e9, Line::kCurb, false});
  L.lines.push_back({constant(-3.5), -1e9, 1e9, Line::kCurb, false});
  L.areas.push_back({constant(0.0), constant(3.5)});  // the right lane's ground: seen, not drivable
  const bev::BevGrid grid = paint(L);
  const lanes::RoadGeometry g = linkAlong(L);
  const lanes::ExplorerOptions o;
  const geo::LatLonAlt origin{49.0, 8.4, 0.0};
  const mapping::RoadLanes alone = mapping::exploreRoadLanes(grid, g, std::nullopt, o, origin);
  ASSERT_EQ(alone.result.lanes.size(), 1u) << "the right lane's ground is not drivable";
  const mapping::RoadLanes with = mapping::exploreRoadLanes(grid, g, std::nullopt, o, origin, twoLanes());
  EXPECT_FALSE(with.lanes_carried);
  EXPECT_EQ(with.lanes_carried_added, 1);
  ASSERT_EQ(with.result.lanes.size(), 2u);
  ASSERT_EQ(with.lanes.lanelets.size(), 2u);
  const auto& a = with.lanes.lanelets[0];
  const auto& b = with.lanes.lanelets[1];
  EXPECT_TRUE(a.right_id == b.left_id || b.right_id == a.left_id) << "the two share one border line string";
  for (const auto& lane : with.result.lanes) {
    EXPECT_NEAR(lane.centre.d(15.0), lane.index_from_left == 0 ? 1.75 : -1.75, 0.3);
  }
  lanes::ExplorerOptions off = o;
  off.add_carried_lanes_not_found = false;
  EXPECT_EQ(mapping::exploreRoadLanes(grid, g, std::nullopt, off, origin, twoLanes()).result.lanes.size(), 1u);
}

}  // namespace
}  // namespace lanemap
