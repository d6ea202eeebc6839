#include "core/map/simplify.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using lanemap::map::simplifyPolyline;

double distanceToPolyline(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& line) {
  double best = 1e300;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector3d ab = line[i + 1] - line[i];
    const double u = std::clamp((p - line[i]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - (line[i] + u * ab)).norm());
  }
  return best;
}

TEST(Simplify, StraightLineKeepsOnlyItsEnds) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i <= 100; ++i) line.emplace_back(0.25 * i, 0.5 * 0.25 * i, 0.01 * i);
  const auto s = simplifyPolyline(line, 0.01);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_TRUE(s.front().isApprox(line.front()));
  EXPECT_TRUE(s.back().isApprox(line.back()));
}

TEST(Simplify, ArcStaysWithinToleranceWithFewerPoints) {
  std::vector<Eigen::Vector3d> arc;  // 90 degrees of a 20 m radius, a point every 0.1 m
  for (int i = 0; i <= 314; ++i) {
    const double a = i * 0.005;
    arc.emplace_back(20.0 * std::cos(a), 20.0 * std::sin(a), 0.0);
  }
  const auto s = simplifyPolyline(arc, 0.01);
  // A chord of length c deviates c^2 / (8 R) from the arc: 1 cm allows c <= 1.26 m, so about
  // 31.4 m / 1.26 m = 25 segments; at least that many and far fewer than the input.
  EXPECT_GE(s.size(), 26u);
  EXPECT_LE(s.size(), 60u);
  for (const auto& p : arc) EXPECT_LE(distanceToPolyline(p, s), 0.01 + 1e-12);
}

TEST(Simplify, ZeroToleranceAndShortLinesAreUntouched) {
  const std::vector<Eigen::Vector3d> line{{0, 0, 0}, {1, 0.001, 0}, {2, 0, 0}};
  EXPECT_EQ(simplifyPolyline(line, 0.0).size(), 3u);
  EXPECT_EQ(simplifyPolyline({line[0], line[2]}, 0.5).size(), 2u);
}

}  // namespace
