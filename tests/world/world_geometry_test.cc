// Plane geometry of the world builder: the reference line (resampled, smoothed, end points kept),
// lateral offsets, and the intersection connection curves (METHOD.md section 5: quadratic Bezier
// through the tangents' intersection, a cubic when the tangents are near parallel).
#include "core/sim/world_geometry.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lanemap::sim::geom {
namespace {

TEST(RefLine, KeepsEndsAndOffsetsAlongTheNormal) {
  // An L-shaped polyline: 50 m east, then 50 m north.
  const RefLine line({{0, 0}, {50, 0}, {50, 50}}, 1.0, 5.0);
  EXPECT_LT((line.points().front() - Vector2d(0, 0)).norm(), 1e-9);
  EXPECT_LT((line.points().back() - Vector2d(50, 50)).norm(), 1e-9);
  // Smoothing cuts the corner: a bit shorter than 100 m, but not by more than the window.
  EXPECT_LT(line.length(), 100.0);
  EXPECT_GT(line.length(), 95.0);
  // On the straight part the left normal of an eastward line points north.
  const Vector2d p = line.offsetPoint(10.0, 2.0);
  EXPECT_NEAR(p.x(), 10.0, 1e-6);
  EXPECT_NEAR(p.y(), 2.0, 1e-6);
  EXPECT_NEAR(line.normalAt(90.0).x(), -1.0, 1e-6);  // northward: left is west
  // The corner is rounded to a radius of the order of the window, not a kink.
  EXPECT_GT(line.minRadius(0.0, line.length()), 3.0);
  EXPECT_LT(line.minRadius(0.0, line.length()), 20.0);
  const auto ss = line.samplesBetween(10.2, 14.7);
  ASSERT_GE(ss.size(), 5u);
  EXPECT_DOUBLE_EQ(ss.front(), 10.2);
  EXPECT_DOUBLE_EQ(ss.back(), 14.7);
  for (size_t i = 1; i < ss.size(); ++i) EXPECT_GT(ss[i], ss[i - 1]);
}

TEST(Rect, DistancesAndOverlap) {
  Rect r;
  r.c = Vector2d(0, 0);
  r.axis = Vector2d(1, 0);
  r.hl = 2.0;
  r.hw = 1.0;
  EXPECT_NEAR(rectSegmentDistance(r, {-5, 3}, {5, 3}), 2.0, 1e-12);
  EXPECT_EQ(rectSegmentDistance(r, {-5, 0}, {5, 0}), 0.0);  // crosses it
  Rect q = r;
  q.c = Vector2d(3.9, 0);
  EXPECT_TRUE(rectsOverlap(r, q));
  q.c = Vector2d(4.1, 0);
  EXPECT_FALSE(rectsOverlap(r, q));
  EXPECT_TRUE(pointInPolygon({0.5, 0.5}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}));
  EXPECT_FALSE(pointInPolygon({1.5, 0.5}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}));
}

}  // namespace
}  // namespace lanemap::sim::geom
