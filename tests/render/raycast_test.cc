// Tests of sim::raycast: hits on sloped / bumpy ground lie on the surface, ranges match the analytic
// plane intersection, yaw-rotated boxes give the slab-test distance and normal, the nearest of
// ground and boxes wins, rays that cannot hit return no hit.
#include "core/sim/raycast.h"
#include "tests/render/test_worlds.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

namespace lanemap::sim {
namespace {

using testing::StripedRoadWorld;
using testing::makeBox;
constexpr double kDeg = M_PI / 180.0;

Eigen::Vector3d dirFromAngles(double heading, double elevation) {
  return {std::cos(elevation) * std::cos(heading), std::cos(elevation) * std::sin(heading), std::sin(elevation)};
}

TEST(Raycast, SlopedPlaneHitsLieOnTheSurfaceAndMatchTheAnalyticRange) {
  StripedRoadWorld world;
  world.base = 3.0;
  world.grade_e = 0.10;   // the steepest grade the world builder makes
  world.grade_n = -0.02;  // plus a crown-like cross slope
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI), elev(-60 * kDeg, -0.5 * kDeg);
  const Eigen::Vector3d plane_normal(-world.grade_e, -world.grade_n, 1.0);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d o(10.0, -4.0, world.height(10.0, -4.0) + 1.5);
    const Eigen::Vector3d d = dirFromAngles(heading(rng), elev(rng));
    // Analytic: (o + t d - p0) . n = 0 with p0 = (0, 0, base).
    const double denom = d.dot(plane_normal);
    const double t_true = denom < 0 ? -(o - Eigen::Vector3d(0, 0, world.base)).dot(plane_normal) / denom : INFINITY;
    const RayHit hit = raycast(world, o, d, 500.0);
    if (!(t_true <= 500.0)) {
      EXPECT_FALSE(hit.hit);
      continue;
    }
    ASSERT_TRUE(hit.hit) << "missed a plane at " << t_true;
    ++hits;
    EXPECT_FALSE(hit.is_obstacle);
    // On the surface within 1 mm vertically (the brief); the refinement stops at 0.1 mm.
    EXPECT_LT(std::abs(hit.point.z() - world.height(hit.point.x(), hit.point.y())), 1e-3);
    // Range error = vertical error / sine of the incidence angle on the plane.
    const double incidence = std::abs(denom) / plane_normal.norm();
    EXPECT_NEAR(hit.range, t_true, 1e-3 / incidence) << "elevation " << std::asin(d.z()) / kDeg;
    EXPECT_EQ(hit.ground.surface, world.sample(hit.point.x(), hit.point.y()).surface);
  }
  EXPECT_GT(hits, 1500);
}

TEST(Raycast, BumpyCrownedGroundHitsLieOnTheSurface) {
  StripedRoadWorld world;
  world.grade_e = 0.06;
  world.bump = 0.04;  // 4 cm bumps every 4 m: slope up to 0.063
  world.bump_period = 4.0;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI), elev(-30 * kDeg, -0.3 * kDeg);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d o(0.0, 0.0, world.height(0, 0) + 1.9);
    const RayHit hit = raycast(world, o, dirFromAngles(heading(rng), elev(rng)), 300.0);
    if (!hit.hit) continue;
    EXPECT_LT(std::abs(hit.point.z() - world.height(hit.point.x(), hit.point.y())), 1e-3);
    // It is the FIRST crossing: the ray stays above the ground before the hit (checked every 5 cm).
    const Eigen::Vector3d d = (hit.point - o) / hit.range;
    for (double t = 0.05; t < hit.range - 0.05; t += 0.05) {
      const Eigen::Vector3d p = o + t * d;
      ASSERT_GT(p.z() - world.height(p.x(), p.y()), -1e-3) << "passed through the ground at " << t;
    }
  }
}

TEST(Raycast, GrazingRayOnFlatGroundIsPrecise) {
  StripedRoadWorld world;
  const Eigen::Vector3d o(0, 0, 1.45);
  for (const double deg : {0.5, 1.0, 2.0, 10.0, 89.0}) {
    const RayHit hit = raycast(world, o, dirFromAngles(0.3, -deg * kDeg), 400.0);
    ASSERT_TRUE(hit.hit);
    // Vertical tolerance 0.1 mm -> range tolerance 0.1 mm / sin(angle), plus 1 mm.
    EXPECT_NEAR(hit.range, 1.45 / std::sin(deg * kDeg), 1e-3 + 1e-4 / std::sin(deg * kDeg)) << deg;
  }
  // Level or rising rays never meet a flat world; rays ending before the ground neither.
  EXPECT_FALSE(raycast(world, o, dirFromAngles(0, 0.0), 400.0).hit);
  EXPECT_FALSE(raycast(world, o, dirFromAngles(0, 20 * kDeg), 400.0).hit);
  EXPECT_FALSE(raycast(world, o, dirFromAngles(0, -1 * kDeg), 80.0).hit);  // ground at 83.08 m
}

TEST(Raycast, YawRotatedBoxesGiveTheSlabDistanceAndNormal) {
  StripedRoadWorld world;
  world.base = -10.0;  // ground out of the way
  // Yaw 90 deg: the 2 m half length lies along north, so the box is 1 m deep along east.
  world.obstacles.push_back(makeBox({10, 0, 1}, {2, 1, 1}, M_PI / 2));
  RayHit hit = raycast(world, {0, 0, 1}, {1, 0, 0}, 100.0);
  ASSERT_TRUE(hit.hit);
  ASSERT_TRUE(hit.is_obstacle);
  EXPECT_EQ(hit.obstacle, &world.obstacles[0]);
  EXPECT_NEAR(hit.range, 9.0, 1e-9);
  EXPECT_NEAR(hit.normal.x(), -1.0, 1e-9);
  // A ray at north 1.9 still hits (half length 2 along north), at 2.1 it misses.
  EXPECT_TRUE(raycast(world, {0, 1.9, 1}, {1, 0, 0}, 100.0).is_obstacle);
  EXPECT_FALSE(raycast(world, {0, 2.1, 1}, {1, 0, 0}, 100.0).hit);
  // Over the roof (top at z = 2) it misses.
  EXPECT_FALSE(raycast(world, {0, 0, 2.05}, {1, 0, 0}, 100.0).hit);

  // A unit cube turned 45 deg at east 10: a ray along east at north 0.2 enters the face
  // y' = +1 at east = 10 - (sqrt 2 - 0.2); that face's outward normal is (-1, 1)/sqrt 2.
  world.obstacles.assign(1, makeBox({10, 0, 1}, {1, 1, 1}, M_PI / 4));
  hit = raycast(world, {0, 0.2, 1}, {1, 0, 0}, 100.0);
  ASSERT_TRUE(hit.is_obstacle);
  EXPECT_NEAR(hit.range, 10.0 - std::sqrt(2.0) + 0.2, 1e-9);
  EXPECT_NEAR(hit.normal.x(), -std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(hit.normal.y(), std::sqrt(0.5), 1e-9);
}

TEST(Raycast, NearestOfGroundAndBoxesWinsAcrossQueryChunks) {
  StripedRoadWorld world;  // flat ground at z = 0
  world.obstacles.push_back(makeBox({57, 0, 1}, {1, 1, 1}, 0.0));  // face at 56 (third 20 m chunk)
  world.obstacles.push_back(makeBox({80, 0, 1}, {1, 1, 1}, 0.0));  // behind it
  const Eigen::Vector3d o(0, 0, 1.0);
  RayHit hit = raycast(world, o, {1, 0, 0}, 150.0);
  ASSERT_TRUE(hit.is_obstacle);
  EXPECT_EQ(hit.obstacle, &world.obstacles[0]);
  EXPECT_NEAR(hit.range, 56.0, 1e-9);
  // Tilted down by 2 deg the ray meets the ground at 28.6 m, before the box.
  hit = raycast(world, o, dirFromAngles(0, -2 * kDeg), 150.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_FALSE(hit.is_obstacle);
  EXPECT_NEAR(hit.range, 1.0 / std::sin(2 * kDeg), 1e-2);
  // Beyond max_range nothing.
  EXPECT_FALSE(raycast(world, o, {1, 0, 0}, 50.0).hit);
}

TEST(Raycast, ObstacleFanGivesTheSameHitsAsTheWorldQueries) {
  StripedRoadWorld world;
  world.grade_e = 0.02;
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> pos(-60, 60), size(0.3, 6), yaw(-M_PI, M_PI);
  for (int i = 0; i < 150; ++i) {
    const double e = pos(rng), n = pos(rng), hz = size(rng);
    world.obstacles.push_back(makeBox({e, n, world.height(e, n) + hz}, {size(rng), size(rng), hz}, yaw(rng)));
  }
  // A low box 1.2 m from the centre: the centre stands in its footprint grown by the slack.
  world.obstacles.push_back(makeBox({2.2, 0.0, 0.5}, {1, 1, 0.5}, 0.0));
  const Eigen::Vector3d centre(0.0, 0.0, 1.9);
  const double slack = 1.0;  // the fan is also valid for origins up to 1 m away
  const ObstacleFan fan(world, centre, 80.0, slack);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI), elev(-0.5, 0.3), off(-0.7, 0.7);
  int obstacle_hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d o = centre + Eigen::Vector3d(off(rng), off(rng), 0.0);  // within the slack
    if (i == 0) {
      ASSERT_FALSE(raycast(world, o, {0, 0, -1}, 80.0, fan).is_obstacle);  // not inside a box
    }
    const Eigen::Vector3d d = dirFromAngles(heading(rng), elev(rng));
    const RayHit a = raycast(world, o, d, 80.0);
    const RayHit b = raycast(world, o, d, 80.0, fan);
    ASSERT_EQ(a.hit, b.hit) << i;
    ASSERT_EQ(a.obstacle, b.obstacle) << i;
    if (a.hit) {
      EXPECT_NEAR(a.range, b.range, 1e-9);
    }
    obstacle_hits += a.is_obstacle;
  }
  EXPECT_GT(obstacle_hits, 2000);  // the boxes are really in the way
}

TEST(Raycast, ABoxsBoundingSphereRejectsOnlyRaysThatMissTheBox) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> pos(-30, 30), size(0.2, 5), yaw(-M_PI, M_PI), unit(-1, 1), reach(1, 60);
  int hits = 0, rejected = 0, misses = 0;
  for (int i = 0; i < 200000; ++i) {
    const Obstacle o = makeBox({pos(rng), pos(rng), pos(rng) / 10}, {size(rng), size(rng), size(rng)}, yaw(rng));
    const PreparedBox box(o);
    const Eigen::Vector3d origin(pos(rng), pos(rng), pos(rng) / 10);
    Eigen::Vector3d d(unit(rng), unit(rng), unit(rng));
    if (d.norm() < 1e-3) continue;
    d.normalize();
    const double t_max = reach(rng);
    const bool hit = std::isfinite(intersectBox(box, origin, d, 0.0, t_max));
    const bool culled = box.missesBound(origin, d, t_max);
    ASSERT_FALSE(hit && culled) << i;  // never culls a ray that enters the box within t_max
    hits += hit;
    misses += !hit;
    rejected += culled;
  }
  EXPECT_GT(hits, 1000);
  EXPECT_GT(rejected, 0.8 * misses);  // and culls most that do not
  // Grazing: a ray along a face of a unit cube (yaw 0), 1 um outside it: the box test misses it,
  // and the sphere (radius sqrt 3) does not cull it (culling is conservative).
  const PreparedBox cube(makeBox({0, 0, 0}, {1, 1, 1}, 0.0));
  EXPECT_FALSE(cube.missesBound({-5, 1.000001, 0}, {1, 0, 0}, 10.0));
  EXPECT_FALSE(std::isfinite(intersectBox(cube, {-5, 1.000001, 0}, {1, 0, 0}, 0.0, 10.0)));
  // Behind the origin, beyond t_max, or wide of the sphere: culled.
  EXPECT_TRUE(cube.missesBound({5, 0, 0}, {1, 0, 0}, 10.0));
  EXPECT_TRUE(cube.missesBound({-5, 0, 0}, {1, 0, 0}, 2.0));
  EXPECT_TRUE(cube.missesBound({-5, 1.8, 0}, {1, 0, 0}, 10.0));
  EXPECT_FALSE(cube.missesBound({-5, 0, 0}, {1, 0, 0}, 4.5));  // the face is at 4: enters
  EXPECT_FALSE(cube.missesBound({0.5, 0, 0}, {1, 0, 0}, 1.0));  // starts inside
}

// Counts World::height calls: the cost of a real (OSM-built) world is dominated by them.
struct CountingWorld : StripedRoadWorld {
  mutable long height_calls = 0;
  double height(double e, double n) const override {
    ++height_calls;
    return StripedRoadWorld::height(e, n);
  }
};

TEST(Raycast, SpeedOfACameraFrameWorthOfRays) {
  CountingWorld world;
  world.grade_e = 0.03;
  world.bump = 0.03;
  const int n = 230400;  // 640 x 360
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> heading(-0.65, 0.65), elev(-27 * kDeg, 19 * kDeg);
  int hits = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i)
    hits += raycast(world, {0, 0, 1.45}, dirFromAngles(heading(rng), elev(rng)), 200.0).hit;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[ info ] %d camera-like rays (one thread): %.3f s, %.2f us/ray, %d hits, "
              "%.1f height() calls/ray\n", n, s, 1e6 * s / n, hits, double(world.height_calls) / n);
  EXPECT_GT(hits, n / 3);  // about half the vertical field of view looks at the ground
}

}  // namespace
}  // namespace lanemap::sim
