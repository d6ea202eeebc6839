// Per-lane confidence (core/mapping/lane_confidence.h) from hand-made evidence: a lane seen drivable
// all along, with both bounds found and the most particles, driven once, is 0.875; one seen on half its length,
// with half its bounds at the default width and a quarter of the particle density, is the mean of
// those shares. setConfidence puts each lane's value on its lanelets. A lane's lines agree (its own
// share) when the traversals put them in the same place.
#include "core/mapping/lane_confidence.h"

#include "core/lanes/frenet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

namespace lanemap::mapping {
namespace {

lanes::Lane lane(int id, double d, int64_t samples) {
  lanes::Lane l;
  l.id = id;
  l.s_begin = 0.0;
  l.s_end = 60.0;
  lanes::PiecewiseLinearFit fit;
  fit.knots = {0.0, 60.0};
  fit.values = {d, d};
  l.centre = lanes::CentreLine(fit, 0.0, 60.0);
  l.particle_samples = samples;
  return l;
}

TEST(LaneConfidence, FromObservedShareBoundsAndParticleSupport) {
  const lanes::ExplorerOptions o;
  lanes::ExplorationResult r;
  r.road_id = 4;
  r.frame = std::make_shared<lanes::FrenetFrame>(std::vector<Eigen::Vector2d>{{0, 0}, {60, 0}}, o.frame_spacing_m, 0.0);
  r.lanes = {lane(0, 1.75, 6000), lane(1, 5.25, 1500)};  // 100 and 25 particle samples per metre
  r.lanes[0].index_from_left = 1;
  r.lanes[1].index_from_left = 0;
  int b_found = 0, b_probes = 0;
  for (auto& l : r.lanes) {
    for (int k = 0; k <= 30; ++k) {
      const double s = 2.0 * k, d = l.centre.d(s);
      l.waypoint_s.push_back(s);
      l.waypoints.push_back(r.frame->toEnu(s, d));
      const bool found = l.id == 0 || k % 2 == 0;  // lane 1: every other way-point at the default width
      l.left.d.push_back(found ? d + 1.6 : d + o.default_half_width_m);
      l.right.d.push_back(found ? d - 1.7 : d - o.default_half_width_m);
      l.left.points.push_back(r.frame->toEnu(s, l.left.d.back()));
      l.right.points.push_back(r.frame->toEnu(s, l.right.d.back()));
      if (l.id == 1) {
        b_probes += 2;
        b_found += found ? 2 : 0;
      }
    }
  }
  // Drivable: lane 0 all along, lane 1 on x < 30 only.
  bev::BevGrid grid;
  for (double x = 0.05; x < 61; x += 0.1) {
    for (double y = 0.05; y < 7.0; y += 0.1) {
      if (y > 3.5 && x >= 29.95) continue;
      grid.add(grid.cellOf({x, y}), bev::Layer::kObserved, 2);
      grid.add(grid.cellOf({x, y}), bev::Layer::kDrivable, 2);
    }
  }
  const auto c = laneConfidences(grid, r, o);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_DOUBLE_EQ(c[0].observed, 1.0);
  EXPECT_DOUBLE_EQ(c[0].bounds, 1.0);
  EXPECT_DOUBLE_EQ(c[0].support, 1.0);
  EXPECT_DOUBLE_EQ(c[0].repeat, 0.5) << "one drive";
  EXPECT_DOUBLE_EQ(c[0].value(), 0.875);
  EXPECT_DOUBLE_EQ(c[1].observed, 15.0 / 31.0);  // way-points at x = 0, 2, ..., 28
  EXPECT_DOUBLE_EQ(c[1].bounds, static_cast<double>(b_found) / b_probes);
  EXPECT_DOUBLE_EQ(c[1].support, 0.25);
  EXPECT_NEAR(c[1].value(), (15.0 / 31.0 + 16.0 / 31.0 + 0.25 + 0.5) / 4.0, 1e-12);

  // Driven twice more by drives that agreed with it (correlations 1 and 0.5): every lane of the
  // road gains; a third drive merged unaligned adds nothing.
  bev::BevGrid again_grid = grid;
  again_grid.addMerge(1.0);
  again_grid.addMerge(0.5);
  again_grid.addMerge(0.0);
  const auto again = laneConfidences(again_grid, r, o);
  EXPECT_DOUBLE_EQ(again[0].repeat, 1.0 - std::pow(0.5, 2.5));
  EXPECT_DOUBLE_EQ(again[1].repeat, again[0].repeat);
  EXPECT_GT(again[1].value(), c[1].value());
  EXPECT_DOUBLE_EQ(again[0].observed, c[0].observed);

  map::LaneMap m = lanes::toLaneMap(r);
  setConfidence(m, r, c);
  int rated = 0;
  for (const auto& ll : m.lanelets) {
    if (ll.kind != map::LaneletKind::kRoad) continue;
    ASSERT_TRUE(ll.confidence.has_value()) << ll.id;
    EXPECT_DOUBLE_EQ(*ll.confidence, ll.index_from_left == 1 ? c[0].value() : c[1].value()) << ll.id;
    ++rated;
  }
  EXPECT_EQ(rated, 2);
}

// The lane's own agreement (issue 14: agreement between traversals, per lane). Two drives of a
// two-lane road, aligned: they agree on the lines of the left lane (the same cells), and on the
// right lane's left line, but put its right line 0.4 m apart (one of them saw that lane wrongly).
// The left lane's lines lie all on its bounds (agreement 1), the right lane's half of its right
// line's evidence does not (0.75 over both its bounds), and its confidence is the lower. A lane
// whose bounds are virtual has no agreement and is rated on the other four shares.
TEST(LaneConfidence, ALaneTheTraversalsDisagreeOnAgreesLess) {
  const lanes::ExplorerOptions o;
  lanes::ExplorationResult r;
  r.road_id = 4;
  r.frame = std::make_shared<lanes::FrenetFrame>(std::vector<Eigen::Vector2d>{{0, 0}, {60, 0}}, o.frame_spacing_m, 0.0);
  r.lanes = {lane(0, 1.75, 6000), lane(1, -1.75, 6000)};
  for (auto& l : r.lanes) {
    const double d = l.centre.d(0.0);
    l.left.type = map::LineType::kDashed;
    l.right.type = l.id == 0 ? map::LineType::kDashed : map::LineType::kSolid;
    for (int k = 0; k <= 30; ++k) {
      const double s = 2.0 * k;
      l.waypoint_s.push_back(s);
      l.waypoints.push_back(r.frame->toEnu(s, d));
      l.left.d.push_back(d + 1.75);
      l.right.d.push_back(d - 1.75);
      l.left.points.push_back(r.frame->toEnu(s, d + 1.75));
      l.right.points.push_back(r.frame->toEnu(s, d - 1.75));
    }
  }
  bev::BevGrid grid;
  auto paint = [&](double y, bev::Layer layer) {  // one drive's line, 0.1 m wide
    for (double x = 0.05; x < 61; x += 0.1) {
      grid.add(grid.cellOf({x, y}), bev::Layer::kObserved, 2);
      grid.add(grid.cellOf({x, y}), layer, 2);
    }
  };
  for (double y = -3.95; y < 3.96; y += 0.1) {
    for (double x = 0.05; x < 61; x += 0.1) grid.add(grid.cellOf({x, y}), bev::Layer::kObserved, 2);
  }
  for (int drive = 0; drive < 2; ++drive) {
    paint(3.55, bev::Layer::kDashedLine);
    paint(0.05, bev::Layer::kDashedLine);
    paint(drive == 0 ? -3.45 : -3.85, bev::Layer::kSolidLine);
  }
  grid.addMerge(1.0);
  const auto c = laneConfidences(grid, r, o);
  ASSERT_EQ(c.size(), 2u);
  ASSERT_TRUE(c[0].agreement && c[1].agreement);
  EXPECT_NEAR(*c[0].agreement, 1.0, 1e-9);
  EXPECT_NEAR(*c[1].agreement, 0.75, 1e-9);
  EXPECT_DOUBLE_EQ(c[0].repeat, c[1].repeat) << "the road's";
  EXPECT_NEAR(c[0].value(), (c[0].observed + c[0].bounds + c[0].support + c[0].repeat + 1.0) / 5.0, 1e-12);
  EXPECT_LT(c[1].value(), c[0].value());

  r.lanes[1].left.type = r.lanes[1].right.type = map::LineType::kVirtual;
  const auto v = laneConfidences(grid, r, o);
  EXPECT_FALSE(v[1].agreement.has_value());
  EXPECT_DOUBLE_EQ(v[1].value(), (v[1].observed + v[1].bounds + v[1].support + v[1].repeat) / 4.0);
}

}  // namespace
}  // namespace lanemap::mapping
