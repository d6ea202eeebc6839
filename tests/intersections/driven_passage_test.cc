// The car's own path through an intersection shapes its connections (core/intersections/
// driven_passage.h): the path between the lane ends it passes, its offsets there taken off; a
// junction that the OSM data draws as one node but the car drove around (a roundabout) gets
// connections that go around it, for the lane driven and the one beside it; other road pairs keep
// their Bezier; the map does not depend on the order passages come in. The lanes it drove correct
// the pairing rules of their road pair (a lane added on the right, where the rules align on the
// left; the lane that feeds a road with fewer lanes), unless the path passed between two lanes.
#include "core/intersections/driven_passage.h"
#include "core/intersections/intersections.h"
#include "core/mapping/map_assembler.h"
#include "tests/intersections/fixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace {

using Eigen::Vector2d;
using lanemap::intersections::DrivenPassage;
using lanemap::intersections::PassageOptions;
using lanemap::testing::LaneSpec;
using lanemap::testing::Net;

std::vector<Vector2d> flat(const std::vector<Eigen::Vector3d>& pts) {
  std::vector<Vector2d> out;
  for (const auto& p : pts) out.push_back(p.head<2>());
  return out;
}

TEST(DrivenPassage, ThePathBetweenTheLaneEndsItPassesWithItsOffsetsTakenOff) {
  // A quarter circle of radius 10 from (0, -10) heading east to (10, 0) heading north, driven off
  // the lane ends by (0.1, -0.3) m (pose offset and the car's place in its lane), 3 m on either side.
  std::vector<Vector2d> path;
  const Vector2d off(0.1, -0.3);
  for (double x = -3.0; x < 0.0; x += 0.5) path.push_back(Vector2d(x, -10.0) + off);
  for (int k = 0; k <= 30; ++k) {
    const double a = -M_PI / 2 + M_PI / 2 * k / 30.0;
    path.push_back(10.0 * Vector2d(std::cos(a), std::sin(a)) + off);  // centred on the origin
  }
  for (double y = 0.5; y <= 3.0; y += 0.5) path.push_back(Vector2d(10.0, y) + off);
  const Vector2d p0(0.0, -10.0), p2(10.0, 0.0);
  const auto c = lanemap::intersections::drivenCentre(path, p0, p2);
  ASSERT_TRUE(c);
  EXPECT_LT((c->front() - p0).norm(), 1e-12);
  EXPECT_LT((c->back() - p2).norm(), 1e-12);
  // The offset is gone at both ends; in between it is taken off as the ends saw it (each end
  // sees the offset across the path there, not along it): every point within 0.15 m of the circle,
  // where the path itself is up to 0.32 m off it.
  double worst = 0.0, path_worst = 0.0;
  for (const auto& q : *c) worst = std::max(worst, std::abs(q.norm() - 10.0));
  for (size_t k = 6; k + 6 < path.size(); ++k) path_worst = std::max(path_worst, std::abs(path[k].norm() - 10.0));
  EXPECT_LT(worst, 0.15);
  EXPECT_GT(path_worst, 0.25);

  PassageOptions tight;
  tight.max_offset_m = 0.2;  // the path passes 0.32 m from the ends: not these lanes'
  EXPECT_FALSE(lanemap::intersections::drivenCentre(path, p0, p2, tight));
  std::vector<Vector2d> backwards(path.rbegin(), path.rend());
  EXPECT_FALSE(lanemap::intersections::drivenCentre(backwards, p0, p2)) << "driven the other way";

  // Its displacement from the straight chord: zero at both ends, 10 - 7.07 m out at the middle.
  const auto d = lanemap::intersections::displacementBetween(*c, {p0, p2});
  EXPECT_LT(d(0.0).norm(), 1e-12);
  EXPECT_LT(d(1.0).norm(), 1e-12);
  EXPECT_NEAR(d(0.5).norm(), 10.0 - 10.0 / std::sqrt(2.0), 0.15);
  const auto moved = d.apply({p0, Vector2d(5.0, -5.0), p2});
  EXPECT_EQ(moved.front(), p0);
  EXPECT_EQ(moved.back(), p2);
  EXPECT_NEAR(moved[1].norm(), 10.0, 0.15);
}

// A roundabout the OSM data draws as one node (0, 0) with the ways' next nodes 14 m out (its ROI):
// two-way roads from the south, to the east and to the west, two lanes each way, both lanes from
// the south turning right. The car came from the south in its right lane and drove around the
// ring (about the node, through the lane ends: radius 15 m) into the east road's right lane.
struct Roundabout {
  Net net;
  lanemap::skeleton::Skeleton sk;
  int64_t in = -1, east = -1, west = -1, from_west = -1;
  std::map<int64_t, lanemap::map::LaneMap> roads;
  Vector2d p0, p2;
  DrivenPassage passage;

  Roundabout() : sk(make(net)) {
    for (const auto& r : sk.roads()) {
      const Vector2d a = sk.pointAt(r, 0.0), b = sk.pointAt(r, r.length);
      if (a.y() < -50 && b.norm() < 1) in = r.id;
      if (a.norm() < 1 && b.x() > 50) east = r.id;
      if (a.norm() < 1 && b.x() < -50) west = r.id;
      if (a.x() < -50 && b.norm() < 1) from_west = r.id;
    }
    LaneSpec two;
    two.lanes = 2;
    roads = lanemap::testing::allLanes(sk, [&](const auto&) { return two; });
    const auto end = [&](int64_t road, int index, bool last) {
      for (const auto& ll : roads.at(road).lanelets) {
        if (ll.index_from_left == index) return Vector2d((last ? ll.centre.back() : ll.centre.front()).head<2>());
      }
      return Vector2d(NAN, NAN);
    };
    p0 = end(in, 1, true);     // the right lane's end, ~(5.25, -14)
    p2 = end(east, 1, false);  // the right lane's start, ~(14, -5.25)
    const Vector2d off(0.15, 0.2);  // the drive's pose offset
    for (double y = p0.y() - 15.0; y < p0.y(); y += 0.5) passage.path.push_back(Vector2d(p0.x(), y) + off);
    const double r0 = p0.norm(), a0 = std::atan2(p0.y(), p0.x()), a2 = std::atan2(p2.y(), p2.x());
    for (int k = 0; k <= 40; ++k) {
      const double a = a0 + (a2 - a0) * k / 40.0;
      passage.path.push_back(r0 * Vector2d(std::cos(a), std::sin(a)) + off);
    }
    for (double x = p2.x() + 0.5; x < p2.x() + 15.0; x += 0.5) passage.path.push_back(Vector2d(x, p2.y()) + off);
    passage.from_road = in;
    passage.to_road = east;
  }
  static lanemap::skeleton::Skeleton make(Net& net) {
    net.node(1, 0, -150);
    net.node(5, 0, -14);  // the ways' nodes at the ring: the junction's ROI reaches them
    net.node(2, 0, 0);
    net.node(6, 14, 0);
    net.node(3, 150, 0);
    net.node(7, -14, 0);
    net.node(4, -150, 0);
    net.way(10, {1, 5, 2}, {{"lanes", "4"}, {"turn:lanes:forward", "right|right"}});  // both lanes turn right
    net.way(11, {2, 6, 3}, {{"lanes", "4"}});
    net.way(12, {2, 7, 4}, {{"lanes", "4"}});
    return net.build();
  }
  const lanemap::map::Lanelet* connection(const lanemap::intersections::IntersectionResult& r, int64_t from, int64_t to,
                                          int in_index, int* passages = nullptr) const {
    for (const auto& c : r.connections) {
      if (c.in_road != from || c.out_road != to || c.in_index != in_index) continue;
      if (passages) *passages = c.passages;
      for (const auto& ll : r.map.lanelets) {
        if (ll.id == c.lanelet_id) return &ll;
      }
    }
    return nullptr;
  }
};

TEST(DrivenPassage, ARoundaboutDrawnAsOneNodeIsDrivenAround) {
  Roundabout t;
  ASSERT_GE(t.in, 0);
  ASSERT_GE(t.east, 0);
  ASSERT_GE(t.west, 0);
  ASSERT_GE(t.from_west, 0);
  ASSERT_TRUE(t.p0.allFinite() && t.p2.allFinite());
  const auto& sk = t.sk;
  const int64_t node = sk.road(t.in)->to;
  const auto plain = lanemap::intersections::buildIntersection(sk, node, t.roads);
  const auto shaped = lanemap::intersections::buildIntersection(sk, node, t.roads, {}, {}, {t.passage});
  EXPECT_EQ(lanemap::testing::pairsOf(sk, plain), lanemap::testing::pairsOf(sk, shaped)) << "a passage changes no pair";

  // The lane driven: its connection runs along the ring (the path less the offset), where the
  // Bezier cuts inside it by metres.
  int used = 0;
  const auto* driven = t.connection(shaped, t.in, t.east, 1, &used);
  const auto* bezier = t.connection(plain, t.in, t.east, 1);
  ASSERT_TRUE(driven && bezier);
  EXPECT_EQ(used, 1);
  const double r0 = t.p0.norm();
  double worst = 0.0, bezier_worst = 0.0;
  for (const auto& p : driven->centre) worst = std::max(worst, std::abs(p.head<2>().norm() - r0));
  for (const auto& p : bezier->centre) bezier_worst = std::max(bezier_worst, std::abs(p.head<2>().norm() - r0));
  std::printf("driven lane: off the ring by at most %.3f m (the Bezier: %.3f m)\n", worst, bezier_worst);
  // (the pose offset, taken off as the ends see it: test above; the smoothing rounds the corners
  // where this path turns onto the ring and off it)
  EXPECT_LT(worst, 0.35);
  EXPECT_GT(bezier_worst, 2.0);
  EXPECT_LT((Vector2d(driven->centre.front().head<2>()) - t.p0).norm(), 1e-9);
  EXPECT_LT((Vector2d(driven->centre.back().head<2>()) - t.p2).norm(), 1e-9);

  // The lane beside it turns with it: moved out as far (within half a metre) at its middle.
  const auto* beside = t.connection(shaped, t.in, t.east, 0, &used);
  const auto* beside_plain = t.connection(plain, t.in, t.east, 0);
  ASSERT_TRUE(beside && beside_plain);
  EXPECT_EQ(used, 1);
  const auto mid = [](const lanemap::map::Lanelet& ll) {
    return lanemap::intersections::resampleEvenly(flat(ll.centre), 3)[1];
  };
  const double moved = (mid(*beside) - mid(*beside_plain)).norm(), moved_driven = (mid(*driven) - mid(*bezier)).norm();
  EXPECT_GT(moved, 1.0);
  EXPECT_NEAR(moved, moved_driven, 0.5);
  // The two share their border, shaped.
  EXPECT_TRUE(beside->right_id == driven->left_id || beside->left_id == driven->right_id);

  // A road pair nobody drove (west to east, straight on) keeps its Bezier, point for point.
  const auto* other = t.connection(shaped, t.from_west, t.east, 0, &used);
  const auto* other_plain = t.connection(plain, t.from_west, t.east, 0);
  ASSERT_TRUE(other && other_plain);
  EXPECT_EQ(used, 0);
  EXPECT_EQ(other->centre, other_plain->centre);
}

// Poses are noisy: a path zigzagging 5 cm either side every 0.5 m, taken as it is, turns the
// bounds tighter than Lanelet2's validator accepts (curvature 0.5). The displacement is smoothed
// as much as that takes (PassageOptions::smoothing_passes, least first): the connection is still
// shaped, its bounds within the limit, still along the ring.
TEST(DrivenPassage, ANoisyPathStillShapesTheConnectionWithinTheCurvatureLimit) {
  Roundabout t;
  for (size_t k = 0; k < t.passage.path.size(); ++k) t.passage.path[k] += Vector2d(k % 2 ? 0.05 : -0.05, k % 2 ? -0.05 : 0.05);
  const int64_t node = t.sk.road(t.in)->to;
  lanemap::intersections::IntersectionOptions raw;
  raw.passage.smoothing_passes = {0};  // as the poses are
  const auto unsmoothed = lanemap::intersections::buildIntersection(t.sk, node, t.roads, raw, {}, {t.passage});
  int used = -1;
  ASSERT_TRUE(t.connection(unsmoothed, t.in, t.east, 1, &used));
  EXPECT_EQ(used, 0) << "the case no longer needs smoothing";
  const auto shaped = lanemap::intersections::buildIntersection(t.sk, node, t.roads, {}, {}, {t.passage});
  const auto* driven = t.connection(shaped, t.in, t.east, 1, &used);
  ASSERT_TRUE(driven);
  EXPECT_EQ(used, 1);
  for (const auto id : {driven->left_id, driven->right_id}) {
    const auto* line = shaped.map.line(id);
    ASSERT_TRUE(line);
    EXPECT_LE(lanemap::intersections::maxCurvature(flat(line->points)), 0.5 + 1e-9);
  }
  double worst = 0.0;
  for (const auto& p : driven->centre) worst = std::max(worst, std::abs(p.head<2>().norm() - t.p0.norm()));
  EXPECT_LT(worst, 0.5);
}

TEST(DrivenPassage, APathThatPassesNoLaneEndShapesNothing) {
  Roundabout t;
  DrivenPassage far = t.passage;
  for (auto& p : far.path) p.x() += 30.0;  // 30 m off: another street's
  const int64_t node = t.sk.road(t.in)->to;
  const auto shaped = lanemap::intersections::buildIntersection(t.sk, node, t.roads, {}, {}, {far});
  for (const auto& c : shaped.connections) EXPECT_EQ(c.passages, 0);
}

// A straight-on junction: road 10 (four lanes, two each way) northbound into road 11 (`lanes_out`
// lanes in all), a side road west, every road mapped with its OSM lane count. pairs() lists the
// connections from the northbound in road to the northbound out road; path() is a passage between
// them from x_in to x_out (north-bound lanes lie right of the line, 3.5 m wide).
lanemap::skeleton::Skeleton straightOnNet(const std::string& lanes_out) {
  Net net;
  net.node(1, 0, -150);
  net.node(2, 0, 0);
  net.node(3, 0, 150);
  net.node(4, -150, 0);
  net.way(10, {1, 2}, {{"lanes", "4"}});
  net.way(11, {2, 3}, {{"lanes", lanes_out}});
  net.way(12, {2, 4});
  return net.build();
}

struct StraightOn {
  explicit StraightOn(const std::string& lanes_out) : sk(straightOnNet(lanes_out)) {
    for (const auto& r : sk.roads()) {
      const Vector2d a = sk.pointAt(r, 0.0), b = sk.pointAt(r, r.length);
      if (a.y() < -50 && b.norm() < 1) in = r.id;
      if (a.norm() < 1 && b.y() > 50) out = r.id;
    }
    roads = lanemap::testing::allLanes(sk, [](const auto& r) {
      LaneSpec s;
      s.lanes = lanemap::testing::laneCount(r);
      return s;
    });
  }
  std::vector<std::pair<int, int>> pairs(const lanemap::intersections::IntersectionOptions& o = {},
                                         const std::vector<DrivenPassage>& passages = {}) const {
    const auto r = lanemap::intersections::buildIntersection(sk, sk.road(in)->to, roads, o, {}, passages);
    std::vector<std::pair<int, int>> out_pairs;
    for (const auto& c : r.connections) {
      if (c.in_road == in && c.out_road == out) out_pairs.emplace_back(c.in_index, c.out_index);
    }
    std::sort(out_pairs.begin(), out_pairs.end());
    return out_pairs;
  }
  DrivenPassage path(double x_in, double x_out) const {
    DrivenPassage p;
    p.from_road = in;
    p.to_road = out;
    for (double y = -30.0; y <= 30.0; y += 0.5) {
      const double u = std::clamp((y + 8.0) / 16.0, 0.0, 1.0);
      p.path.emplace_back(x_in + (x_out - x_in) * u, y);
    }
    return p;
  }
  lanemap::skeleton::Skeleton sk;
  std::map<int64_t, lanemap::map::LaneMap> roads;
  int64_t in = -1, out = -1;
};

// Straight on from two lanes to three (a lane added on the right). Untagged, the rules pair the
// lanes by their offsets from the road's line: 0 -> 0, 1 -> 1. The car drove from the right lane
// into the new right lane: the lanes line up on the right, 0 -> 1, 1 -> 2. A path that crosses the
// junction between two out lanes (changing lanes there) says nothing.
TEST(DrivenPassage, TheLanesDrivenCorrectThePairingOfTheirRoads) {
  const StraightOn j("6");
  ASSERT_GE(j.in, 0);
  ASSERT_GE(j.out, 0);
  using Pairs = std::vector<std::pair<int, int>>;
  EXPECT_EQ(j.pairs(), (Pairs{{0, 0}, {1, 1}}));
  // Northbound lanes right of the line: the right lane at x = 5.25, the new right lane at 8.75.
  EXPECT_EQ(j.pairs({}, {j.path(5.25, 8.75)}), (Pairs{{0, 1}, {1, 2}}));
  lanemap::intersections::IntersectionOptions rules_only;
  rules_only.passage.pairs = false;
  EXPECT_EQ(j.pairs(rules_only, {j.path(5.25, 8.75)}), (Pairs{{0, 0}, {1, 1}}));
  // Between the two right out lanes (x = 7.0): no lane of them is clearly the one driven.
  EXPECT_EQ(j.pairs({}, {j.path(5.25, 7.0)}), (Pairs{{0, 0}, {1, 1}}));
}

// Two lanes into one straight on (perth_peanut_roundabout road 0, monaco, seattle_slip_lane): the
// rules pair the inner lane with the one lane out (the outer lane, with no pair, runs on into it
// too); the car came from the outer lane. The rules' pairing shifts by one in lane: the outer lane
// continues, the inner one (which has its left turn) no longer feeds the lane out as well.
TEST(DrivenPassage, TheLaneDrivenIntoARoadWithFewerLanesIsTheOneThatFeedsIt) {
  const StraightOn j("2");
  ASSERT_GE(j.in, 0);
  ASSERT_GE(j.out, 0);
  using Pairs = std::vector<std::pair<int, int>>;
  EXPECT_EQ(j.pairs(), (Pairs{{0, 0}, {1, 0}}));
  // Northbound: the inner lane at x = 1.75, the outer at 5.25; the lane out at 1.75.
  EXPECT_EQ(j.pairs({}, {j.path(5.25, 1.75)}), (Pairs{{1, 0}}));
  lanemap::intersections::IntersectionOptions out_lanes_only;
  out_lanes_only.passage.shift_in_lanes = false;
  EXPECT_EQ(j.pairs(out_lanes_only, {j.path(5.25, 1.75)}), (Pairs{{0, 0}, {1, 0}}));
}

TEST(DrivenPassage, TheMapIsTheSameWhateverOrderPassagesComeIn) {
  Roundabout t;
  DrivenPassage second = t.passage;
  for (auto& p : second.path) p += Vector2d(-0.2, 0.1);  // another drive, another offset
  second.path[second.path.size() / 2] += Vector2d(0.3, 0.0);
  lanemap::mapping::MapAssembler a(t.sk), b(t.sk);
  for (const auto& [id, m] : t.roads) {
    a.setRoad(id, m);
    b.setRoad(id, m);
  }
  EXPECT_TRUE(a.addPassage(t.passage));
  EXPECT_TRUE(a.addPassage(second));
  EXPECT_TRUE(b.addPassage(second));
  EXPECT_TRUE(b.addPassage(t.passage));
  const auto ma = a.map(), mb = b.map();
  ASSERT_EQ(ma.lanelets.size(), mb.lanelets.size());
  for (size_t i = 0; i < ma.lanelets.size(); ++i) EXPECT_EQ(ma.lanelets[i].centre, mb.lanelets[i].centre);
  // A passage between roads that do not meet is refused.
  DrivenPassage wrong = t.passage;
  wrong.to_road = t.in;
  EXPECT_FALSE(a.addPassage(wrong));
}

}  // namespace
