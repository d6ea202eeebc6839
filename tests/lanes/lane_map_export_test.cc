// toLaneMap (core/lanes/explorer.h) keeps a lanelet's centre line inside it: the centre comes from
// the particles and the bounds from the probes, and where a bound was drawn in past the centre (a
// kerb probed short, a line seen on the wrong side) the exported centre point stays on the lanelet's
// edge, within 5 cm, instead of outside it (lanemap-check's centerline_inside; 2026-12-07, a lane of
// arizona seed 2 on the crowned projection). Elsewhere the centre line is the particles' one, as it was.
#include "core/lanes/explorer.h"
#include "core/lanes/frenet.h"

#include <gtest/gtest.h>

#include <memory>

namespace lanemap::lanes {
namespace {

TEST(LaneMapExport, ACentrePastADrawnInBoundStaysOnTheLaneletsEdge) {
  const ExplorerOptions o;
  ExplorationResult r;
  r.road_id = 2;
  r.frame = std::make_shared<FrenetFrame>(std::vector<Eigen::Vector2d>{{0, 0}, {60, 0}}, o.frame_spacing_m, 0.0);
  Lane l;
  l.s_begin = 0.0;
  l.s_end = 60.0;
  PiecewiseLinearFit fit;
  fit.knots = {0.0, 60.0};
  fit.values = {0.0, 0.0};
  l.centre = CentreLine(fit, 0.0, 60.0);
  for (int k = 0; k <= 30; ++k) {
    const double s = 2.0 * k;
    l.waypoint_s.push_back(s);
    l.waypoints.push_back(r.frame->toEnu(s, 0.0));
    // The left bound drawn in to 0.4 m right of the centre line from 20 to 40 m.
    const double left = s >= 20.0 && s <= 40.0 ? -0.4 : 1.75;
    l.left.d.push_back(left);
    l.right.d.push_back(-1.75);
    l.left.points.push_back(r.frame->toEnu(s, left));
    l.right.points.push_back(r.frame->toEnu(s, -1.75));
  }
  l.left.type = map::LineType::kDashed;
  l.right.type = map::LineType::kSolid;
  r.lanes = {l};
  const map::LaneMap m = toLaneMap(r);
  size_t inside_drawn_in = 0, elsewhere = 0;
  for (const auto& ll : m.lanelets) {
    for (const auto& p : ll.centre) {
      if (p.x() > 20.5 && p.x() < 39.5) {
        EXPECT_LE(p.y(), -0.4 + 0.05 + 1e-6) << "x " << p.x();
        EXPECT_GE(p.y(), -1.75) << "x " << p.x();
        ++inside_drawn_in;
      } else if (p.x() < 19.0 || p.x() > 41.0) {
        EXPECT_NEAR(p.y(), 0.0, 1e-6) << "the particles' centre where the bounds hold it: x " << p.x();
        ++elsewhere;
      }
    }
  }
  EXPECT_GT(inside_drawn_in, 5u);
  EXPECT_GT(elsewhere, 10u);
}

}  // namespace
}  // namespace lanemap::lanes
