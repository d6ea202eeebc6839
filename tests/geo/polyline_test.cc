// core/geo/polyline.h: a point's distance to a polyline (one helper for the map checks, the
// regulatory-element scoring and the carried lanes, which each had their own).
#include "core/geo/polyline.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lanemap::geo {
namespace {

TEST(Polyline, DistanceToItsNearestSegment) {
  const std::vector<Eigen::Vector2d> l = {{0, 0}, {10, 0}, {10, 10}};
  EXPECT_DOUBLE_EQ(distanceToPolyline(l, {5, 3}), 3.0);      // beside the first segment
  EXPECT_DOUBLE_EQ(distanceToPolyline(l, {12, 5}), 2.0);     // beside the second
  EXPECT_DOUBLE_EQ(distanceToPolyline(l, {-3, -4}), 5.0);    // beyond the first end: to it
  EXPECT_DOUBLE_EQ(distanceToPolyline(l, {10, 0}), 0.0);
  EXPECT_DOUBLE_EQ(distanceToPolyline({{1, 1}}, {4, 5}), 5.0);  // one point
  EXPECT_TRUE(std::isinf(distanceToPolyline({}, {0, 0})));
  // A 3-D polyline is measured in the plane: its heights do not count.
  const std::vector<Eigen::Vector3d> l3 = {{0, 0, 7}, {10, 0, -3}};
  EXPECT_DOUBLE_EQ(distanceToPolylineXy(l3, {5, 3}), 3.0);
  EXPECT_DOUBLE_EQ(distanceToPolylineXy({{1, 1, 9}}, {4, 5}), 5.0);
}

// Points at most `step` apart: the vertices, each segment in the fewest equal parts (shared by
// lanemap-check's shared_borders and the divider merge, so both sample a line alike).
TEST(Polyline, PointsEveryStepKeepTheVerticesAndCutEachSegmentEvenly) {
  const std::vector<Eigen::Vector2d> l = {{0, 0}, {2.5, 0}, {2.5, 1}};
  const auto p = pointsEvery(l, 1.0);
  const std::vector<Eigen::Vector2d> want = {{0, 0}, {2.5 / 3, 0}, {5.0 / 3, 0}, {2.5, 0}, {2.5, 1}};
  ASSERT_EQ(p.size(), want.size());
  for (size_t i = 0; i < p.size(); ++i) EXPECT_NEAR((p[i] - want[i]).norm(), 0.0, 1e-12) << i;
  EXPECT_EQ(pointsEvery({{3, 4}}, 1.0).size(), 1u);
  EXPECT_TRUE(pointsEvery({}, 1.0).empty());
  // A 3-D line: its xy projection, heights ignored (a 0.9 m step in height adds no point).
  const auto q = pointsEveryXy({{0, 0, 0}, {1, 0, 0.9}}, 1.0);
  ASSERT_EQ(q.size(), 2u);
  EXPECT_NEAR((q[1] - Eigen::Vector2d(1, 0)).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace lanemap::geo
