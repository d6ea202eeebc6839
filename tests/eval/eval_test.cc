// Tests of core/eval on hand-made map pairs with answers worked out by hand:
// - identical maps: P = R = 1, RMS 0, IoU 1, intersections and lane graph P = R = 1, Chamfer AP 1;
// - a lane shifted sideways by 0.3 m: RMS 0.3 and IoU (3.5 - 0.3) / (3.5 + 0.3) (a 3.5 m wide lane
//   overlaps its shifted copy over 3.2 m of width, their union is 3.8 m wide); by 1.0 m: IoU 2.5/4.5
//   and RMS 1.0, no detection, so precision and recall lose exactly that lane;
// - a missing lane lowers recall by exactly one lane (and its connection the intersection recall);
// - a wrong intersection connection lowers topology precision and recall by exactly one pair;
// - different lanelet cuts (pieces, a split at a turn pocket placed elsewhere) change nothing;
// - MapTR Chamfer AP on three parallel lanes, one shifted by 0.7 m (see ChamferAp below);
// - the overlap rules of the RMS and the coverage guard of the RMS criterion;
// - the polygon fallback for bounds that cross.
//
// The test network (ENU metres, right-hand traffic, lanes 3.5 m wide): road A eastbound from x=-100
// to x=-10 with lanes A0 (centre y=-1.75) and A1 (y=-5.25); road B the same from x=10 to x=100;
// road C northbound at x=1.75 from y=10 to y=100 (lane C0). Intersection lanelets A0->B0, A1->B1
// (straight) and A0->C0 (left turn).
#include "core/eval/evaluate.h"
#include "core/eval/geometry.h"
#include "core/intersections/curve.h"
#include "tests/eval/test_maps.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using Eigen::Vector2d;
using lanemap::eval::EvalReport;
using lanemap::eval::evaluate;
using lanemap::eval::Polyline;
using lanemap::map::LaneMap;
using lanemap::testing::kW;
using lanemap::testing::MapBuilder;
using lanemap::testing::Net;
using lanemap::testing::network;
using lanemap::testing::straight;
using lanemap::testing::with;

const lanemap::eval::LaneMatch* matchOf(const EvalReport& r, int64_t truth_first_lanelet) {
  for (const auto& m : r.matches) {
    if (r.truth_lanes[m.truth].lanelets.front() == truth_first_lanelet) return &m;
  }
  return nullptr;
}

TEST(Evaluate, IdenticalMapsScorePerfectly) {
  const LaneMap t = network({});
  const EvalReport r = evaluate(t, t);
  EXPECT_EQ(r.truth_lanes.size(), 5u);
  EXPECT_EQ(r.built_lanes.size(), 5u);
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 1.0);
  EXPECT_NEAR(r.lane_rms_m, 0.0, 1e-12);
  EXPECT_NEAR(r.lane_miou, 1.0, 1e-9);
  EXPECT_EQ(r.intersection_recall.total, 3u);
  EXPECT_DOUBLE_EQ(r.intersection_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.intersection_recall.value(), 1.0);
  EXPECT_NEAR(r.intersection_rms_m, 0.0, 1e-12);
  EXPECT_EQ(r.graph_recall.total, 3u);
  EXPECT_DOUBLE_EQ(r.graph_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.graph_recall.value(), 1.0);
  // 5 lanes + 3 intersection lanelets; 10 bounds of which A0/A1 and B0/B1 share one each.
  EXPECT_EQ(r.ap_centre.truth_instances, 8u);
  EXPECT_EQ(r.ap_boundary.truth_instances, 8u);
  for (const auto& [thr, ap] : r.chamfer_ap) EXPECT_DOUBLE_EQ(ap, 1.0) << thr;
  EXPECT_EQ(r.repaired_polygons, 0u);
  // Per road: three truth roads with their lanes, all detected.
  ASSERT_EQ(r.roads.size(), 3u);
  EXPECT_EQ(r.roads[0].road_id, 1);
  EXPECT_EQ(r.roads[0].truth_lanes, 2u);
  EXPECT_EQ(r.roads[0].built_lanes, 2u);
  EXPECT_EQ(r.roads[0].detected, 2u);
}

TEST(Evaluate, LaneShiftedBy30CmGivesRms30CmAndTheIouByHand) {
  const LaneMap t = network({}), b = network(with([](Net& n) { n.a1_shift = 0.3; }));
  const EvalReport r = evaluate(t, b);
  const auto* m = matchOf(r, t.lanelets[1].id);  // A1
  ASSERT_NE(m, nullptr);
  EXPECT_NEAR(m->rms_m, 0.3, 1e-9);
  EXPECT_NEAR(m->iou, (kW - 0.3) / (kW + 0.3), 1e-9);
  EXPECT_NEAR(m->coverage, 1.0, 1e-9);
  EXPECT_TRUE(m->detected);
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 1.0);
  EXPECT_NEAR(r.lane_rms_m, 0.3 / 5.0, 1e-9);  // mean over the five matched lanes
  EXPECT_NEAR(r.lane_miou, (4.0 + (kW - 0.3) / (kW + 0.3)) / 5.0, 1e-9);
}

TEST(Evaluate, LaneShiftedBy1MIsNoDetection) {
  const LaneMap t = network({}), b = network(with([](Net& n) { n.a1_shift = 1.0; }));
  const EvalReport r = evaluate(t, b);
  const auto* m = matchOf(r, t.lanelets[1].id);
  ASSERT_NE(m, nullptr);
  EXPECT_NEAR(m->rms_m, 1.0, 1e-9);
  EXPECT_NEAR(m->iou, (kW - 1.0) / (kW + 1.0), 1e-9);
  EXPECT_FALSE(m->detected);
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 4.0 / 5.0);
  // Still matched one-to-one: the topology through it is right.
  EXPECT_DOUBLE_EQ(r.intersection_precision.value(), 1.0);
}

TEST(Evaluate, MissingLaneLowersRecallByExactlyOneLane) {
  const LaneMap t = network({}), b = network(with([](Net& n) { n.drop_b1 = true; }));
  const EvalReport r = evaluate(t, b);
  EXPECT_EQ(r.built_lanes.size(), 4u);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 1.0);
  EXPECT_NEAR(r.lane_rms_m, 0.0, 1e-12);
  // Its connection A1 -> B1 is gone too.
  EXPECT_DOUBLE_EQ(r.intersection_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.intersection_recall.value(), 2.0 / 3.0);
  // Per road: road 2 has 2 truth lanes, 1 built and detected.
  ASSERT_EQ(r.roads.size(), 3u);
  EXPECT_EQ(r.roads[1].road_id, 2);
  EXPECT_EQ(r.roads[1].truth_lanes, 2u);
  EXPECT_EQ(r.roads[1].built_lanes, 1u);
  EXPECT_EQ(r.roads[1].detected, 1u);
}

TEST(Evaluate, WrongConnectionLowersTopologyPrecisionExactly) {
  const LaneMap t = network({}), b = network(with([](Net& n) { n.wrong_connection = true; }));
  const EvalReport r = evaluate(t, b);
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 1.0);
  EXPECT_EQ(r.intersection_precision.total, 3u);
  EXPECT_EQ(r.intersection_precision.hits, 2u);
  EXPECT_DOUBLE_EQ(r.intersection_precision.value(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(r.intersection_recall.value(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(r.graph_precision.value(), 2.0 / 3.0);
  EXPECT_NEAR(r.intersection_rms_m, 0.0, 1e-12);  // the two right ones are exact
}

TEST(Evaluate, DifferentLaneletCutsChangeNothing) {
  const LaneMap t = network(with([](Net& n) { n.split_c0 = true; })), b = network(with([](Net& n) { n.split_b0 = true; }));
  const EvalReport r = evaluate(t, b);
  EXPECT_EQ(r.truth_lanes.size(), 5u);
  EXPECT_EQ(r.built_lanes.size(), 5u);
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 1.0);
  EXPECT_NEAR(r.lane_rms_m, 0.0, 1e-12);
  EXPECT_NEAR(r.lane_miou, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(r.intersection_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.intersection_recall.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.graph_recall.value(), 1.0);
  for (const auto& [thr, ap] : r.chamfer_ap) EXPECT_DOUBLE_EQ(ap, 1.0) << thr;
}

TEST(Evaluate, TurnPocketSplitElsewhereIsStillOneLaneAndOnePocket) {
  // Truth: A0 cut at x=-40 where a left pocket (centre y=+1.75) splits off. Built: A0 in one piece
  // and the pocket from x=-45, not linked.
  MapBuilder t, b;
  const int64_t a0a = t.lane(straight({-100, -1.75}, {-40, -1.75}), 1);
  const int64_t a0b = t.lane(straight({-40, -1.75}, {-10, -1.75}), 1);
  const int64_t p = t.lane(straight({-40, 1.75}, {-10, 1.75}), 1);
  t.link(a0a, a0b);
  t.link(a0a, p);
  b.lane(straight({-100, -1.75}, {-10, -1.75}), 1);
  b.lane(straight({-45, 1.75}, {-10, 1.75}), 1);
  const EvalReport r = evaluate(t.m, b.m);
  ASSERT_EQ(r.truth_lanes.size(), 2u);
  EXPECT_EQ(r.truth_lanes[0].lanelets, (std::vector<int64_t>{a0a, a0b}));
  EXPECT_EQ(r.truth_lanes[1].lanelets, std::vector<int64_t>{p});
  EXPECT_DOUBLE_EQ(r.lane_precision.value(), 1.0);
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 1.0);
  const auto* m = matchOf(r, p);
  ASSERT_NE(m, nullptr);
  EXPECT_NEAR(m->iou, 30.0 / 35.0, 1e-9);
  // The lane graph: truth has the split edge A0 -> pocket, the built map does not.
  EXPECT_EQ(r.graph_recall.total, 1u);
  EXPECT_EQ(r.graph_recall.hits, 0u);
}

TEST(Evaluate, RmsOverTheOverlapAndTheCoverageGuard) {
  MapBuilder t;
  t.lane(straight({0, 0}, {100, 0}), 1);
  {
    // Longer than the truth on both ends and 0.1 m off: RMS over the overlap only.
    MapBuilder b;
    b.lane(straight({-20, 0.1}, {120, 0.1}), 1);
    const EvalReport r = evaluate(t.m, b.m);
    ASSERT_EQ(r.matches.size(), 1u);
    EXPECT_NEAR(r.matches[0].rms_m, 0.1, 1e-9);
    EXPECT_NEAR(r.matches[0].coverage, 1.0, 1e-9);
    EXPECT_NEAR(r.matches[0].iou, 100.0 * 3.4 / (140.0 * 3.5 + 100.0 * 0.1), 1e-9);
  }
  for (const double len : {30.0, 60.0}) {
    // Exactly on the truth but short: IoU len/100 < 0.7; RMS 0 counts when it covers >= 50 %.
    MapBuilder b;
    b.lane(straight({0, 0}, {len, 0}), 1);
    const EvalReport r = evaluate(t.m, b.m);
    ASSERT_EQ(r.matches.size(), 1u);
    EXPECT_NEAR(r.matches[0].rms_m, 0.0, 1e-12);
    EXPECT_NEAR(r.matches[0].coverage, len / 100.0, 1e-9);
    EXPECT_NEAR(r.matches[0].iou, len / 100.0, 1e-9);
    EXPECT_EQ(r.matches[0].detected, len > 50.0) << len;
  }
  {
    // Beside the truth lane (no polygon overlap): no match at all.
    MapBuilder b;
    b.lane(straight({0, 3.6}, {100, 3.6}), 1);
    const EvalReport r = evaluate(t.m, b.m);
    EXPECT_TRUE(r.matches.empty());
    EXPECT_DOUBLE_EQ(r.lane_recall.value(), 0.0);
    EXPECT_TRUE(std::isnan(r.lane_rms_m));
  }
}

TEST(Evaluate, ChamferApLikeMapTR) {
  // Three parallel 100 m lanes (centres y = 0, -3.5, -7; bounds 1.75, -1.75, -5.25, -8.75; the
  // shared ones counted once: 4 truth bounds). The built map has the third lane 0.7 m to the right.
  // All scores are 100 (lengths): predictions ranked in map order.
  // Centre lines: TP, TP, then the shifted one, Chamfer distance 0.7: FP at 0.5 (AP 2/3), TP at 1.0
  // and 1.5 (AP 1). Bounds: predictions 1.75, -1.75, -5.25 (TP) then -5.95 and -9.45 (their own
  // lane's, not shared any more). At 0.5 both FP: AP 3/4. At 1.0: -5.95's nearest truth bound is
  // -5.25 (0.7), already taken: FP; -9.45's is -8.75: TP. Precision 1, 1, 1, 3/4, 4/5 at recall
  // 1/4, 1/2, 3/4, 3/4, 1: AP = 3/4 * 1 + 1/4 * 4/5 = 0.95; the same at 1.5.
  MapBuilder t, b;
  for (int k = 0; k < 3; ++k) t.lane(straight({0, -3.5 * k}, {100, -3.5 * k}), 1);
  for (int k = 0; k < 3; ++k) b.lane(straight({0, -3.5 * k - (k == 2 ? 0.7 : 0.0)}, {100, -3.5 * k - (k == 2 ? 0.7 : 0.0)}), 1);
  const EvalReport r = evaluate(t.m, b.m);
  EXPECT_EQ(r.ap_centre.truth_instances, 3u);
  EXPECT_EQ(r.ap_boundary.truth_instances, 4u);
  EXPECT_EQ(r.ap_boundary.predictions, 5u);
  EXPECT_NEAR(r.ap_centre.ap.at(0.5), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(r.ap_centre.ap.at(1.0), 1.0, 1e-12);
  EXPECT_NEAR(r.ap_centre.ap.at(1.5), 1.0, 1e-12);
  EXPECT_NEAR(r.ap_boundary.ap.at(0.5), 0.75, 1e-12);
  EXPECT_NEAR(r.ap_boundary.ap.at(1.0), 0.95, 1e-12);
  EXPECT_NEAR(r.ap_boundary.ap.at(1.5), 0.95, 1e-12);
  EXPECT_NEAR(r.chamfer_ap.at(1.0), (1.0 + 0.95) / 2.0, 1e-12);
  // The shifted lane: IoU 2.8/4.2 < 0.7 and RMS 0.7: no detection.
  EXPECT_DOUBLE_EQ(r.lane_recall.value(), 2.0 / 3.0);
}

TEST(EvalGeometry, OverlapDistanceOnACurve) {
  // Quarter circles of radius 50 and 50.4 around the origin: every foot is on the truth arc, the
  // distance is 0.4 everywhere (up to the chords of the polygonal arcs).
  Polyline truth, built;
  for (int i = 0; i <= 900; ++i) {
    const double a = M_PI / 2 * i / 900.0;
    truth.emplace_back(50 * std::cos(a), 50 * std::sin(a));
    built.emplace_back(50.4 * std::cos(a), 50.4 * std::sin(a));
  }
  const auto d = lanemap::eval::overlapDistance(built, truth, 0.5);
  EXPECT_NEAR(d.rms, 0.4, 1e-3);
  EXPECT_NEAR(d.covered_m, 50 * M_PI / 2, 0.2);
  EXPECT_EQ(lanemap::eval::chamferDistance(lanemap::eval::resampleCount(truth, 100), lanemap::eval::resampleCount(truth, 100)), 0.0);
}

TEST(EvalGeometry, CrossingBoundsFallBackToQuadrilaterals) {
  // Left bound from y=+1 to y=-1, right bound from -1 to +1 over 10 m: they cross at x=5, the ring
  // is a bow tie of two triangles of area 1/2 * 2 * 5 each.
  const lanemap::eval::LanePolygon p(straight({0, 1}, {10, -1}, 1.0), straight({0, -1}, {10, 1}, 1.0));
  EXPECT_TRUE(p.repaired());
  EXPECT_NEAR(p.area(), 10.0, 1e-9);
  const lanemap::eval::LanePolygon q(straight({0, 1}, {10, 1}, 1.0), straight({0, -1}, {10, -1}, 1.0));
  EXPECT_FALSE(q.repaired());
  EXPECT_NEAR(q.area(), 20.0, 1e-9);
  EXPECT_NEAR(p.iou(q), 10.0 / 20.0, 1e-9);
}

}  // namespace
