// The ray cast over an ObstacleFan tests the boxes first and gives up marching the ground once past
// the nearest box (the simulator's speed-up for rays into buildings). Its hits must be the hits of
// the ground-first cast over World::obstaclesNear to the bit (range, point, normal, box, surface),
// so that a drive's files stay byte-identical; and it must really march less.
#include "core/sim/raycast.h"
#include "tests/render/test_worlds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace lanemap::sim {
namespace {

using testing::StripedRoadWorld;
using testing::makeBox;

struct CountingWorld : StripedRoadWorld {
  mutable long height_calls = 0;
  double height(double e, double n) const override {
    ++height_calls;
    return StripedRoadWorld::height(e, n);
  }
};

Eigen::Vector3d dirFromAngles(double heading, double elevation) {
  return {std::cos(elevation) * std::cos(heading), std::cos(elevation) * std::sin(heading), std::sin(elevation)};
}

TEST(RaycastOrder, BoxesFirstGivesTheGroundFirstHitsToTheBitWithFewerHeightCalls) {
  CountingWorld world;
  world.grade_e = 0.03;
  world.bump = 0.03;
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> pos(-90, 90), size(0.3, 8), yaw(-M_PI, M_PI);
  for (int i = 0; i < 200; ++i) {
    const double e = pos(rng), n = pos(rng), hz = size(rng);
    world.obstacles.push_back(makeBox({e, n, world.height(e, n) + hz}, {size(rng), size(rng), hz}, yaw(rng)));
  }
  // A box whose face stands exactly where a ray meets the ground, and one standing on the ground:
  // ties and near-ties between box and ground.
  world.obstacles.push_back(makeBox({12.0, 0.0, 0.0}, {0.5, 3.0, 0.3}, 0.0));
  const Eigen::Vector3d origin(0.0, 0.0, 1.45);
  const ObstacleFan fan(world, origin, 200.0);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI), elev(-0.45, 0.25);
  long calls_ground_first = 0, calls_boxes_first = 0;
  int obstacle_hits = 0, ground_hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d d = dirFromAngles(heading(rng), elev(rng));
    world.height_calls = 0;
    const RayHit a = raycast(world, origin, d, 200.0);
    calls_ground_first += world.height_calls;
    world.height_calls = 0;
    const RayHit b = raycast(world, origin, d, 200.0, fan);
    calls_boxes_first += world.height_calls;
    ASSERT_EQ(a.hit, b.hit) << i;
    ASSERT_EQ(a.is_obstacle, b.is_obstacle) << i;
    ASSERT_EQ(a.obstacle, b.obstacle) << i;
    if (!a.hit) continue;
    EXPECT_EQ(a.range, b.range) << i;  // bitwise: no tolerance
    EXPECT_EQ(a.point, b.point) << i;
    EXPECT_EQ(a.normal, b.normal) << i;
    EXPECT_EQ(a.ground.surface, b.ground.surface) << i;
    EXPECT_EQ(a.ground.lanelet, b.ground.lanelet) << i;
    obstacle_hits += a.is_obstacle;
    ground_hits += !a.is_obstacle;
  }
  EXPECT_GT(obstacle_hits, 3000);  // the boxes are really in the way
  EXPECT_GT(ground_hits, 3000);
  // Rays into boxes no longer march the ground behind them.
  EXPECT_LT(calls_boxes_first, 0.9 * calls_ground_first)
      << calls_boxes_first << " vs " << calls_ground_first << " height() calls";
}

}  // namespace
}  // namespace lanemap::sim
