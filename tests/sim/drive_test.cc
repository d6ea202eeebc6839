// The simulated car's route, lanes and motion over the real West Oakland network.
#include "core/osm/osm_data.h"
#include "core/sim/drive.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "processes/framework/process.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace {

using namespace lanemap;

struct Net {
  osm::OsmData osm;
  std::unique_ptr<skeleton::Skeleton> sk;
  std::unique_ptr<sim::SimWorld> world;
};

const Net& westOakland() {
  static Net* net = [] {
    auto* n = new Net;
    n->osm = osm::readOsm(lanemap::testing::dataPath("osm/west-oakland.osm"));
    n->sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(n->osm));
    sim::WorldOptions o;
    o.seed = 1;
    n->world = sim::buildWorld(*n->sk, o);
    return n;
  }();
  return *net;
}

bool isNeighbour(const map::Lanelet& a, const map::Lanelet& b) {
  return a.road_id == b.road_id && std::abs(a.index_from_left - b.index_from_left) == 1;
}

TEST(Drive, AutoRouteIsAConnectedSequenceOfAtomicRoads) {
  const Net& n = westOakland();
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    sim::DriveOptions o;
    o.seed = seed;
    o.duration_s = 60.0;
    const auto plan = sim::planDrive(*n.sk, n.world->truth(), o);
    ASSERT_FALSE(plan.roads.empty());
    for (size_t i = 0; i + 1 < plan.roads.size(); ++i) {
      const auto* a = n.sk->road(plan.roads[i]);
      const auto* b = n.sk->road(plan.roads[i + 1]);
      EXPECT_EQ(a->to, b->from) << "seed " << seed << " step " << i;
      EXPECT_NE(a->reverse_id, b->id) << "U-turn, seed " << seed;
    }
    // Every leg follows the lane graph: a successor, or a lane change to a neighbour lane.
    const auto& truth = n.world->truth();
    for (size_t i = 0; i + 1 < plan.legs.size(); ++i) {
      const auto* a = truth.lanelet(plan.legs[i].lanelet);
      const auto* b = truth.lanelet(plan.legs[i + 1].lanelet);
      ASSERT_TRUE(a && b);
      if (plan.legs[i].lane_change_to_next) {
        EXPECT_TRUE(isNeighbour(*a, *b)) << a->id << " -> " << b->id;
      } else {
        EXPECT_NE(std::find(a->successors.begin(), a->successors.end(), b->id), a->successors.end())
            << a->id << " -> " << b->id << " is not a successor";
      }
    }
  }
}

TEST(Drive, TrajectoryIsContinuousAtUrbanSpeedsOnTheGround) {
  const Net& n = westOakland();
  sim::DriveOptions o;
  o.seed = 2;
  o.duration_s = 90.0;
  const auto plan = sim::planDrive(*n.sk, n.world->truth(), o);
  const sim::Trajectory traj(n.world->truth(), *n.world, plan, o);
  ASSERT_GT(traj.duration(), 20.0);
  Eigen::Vector3d prev = traj.at(0.0).vehicle_to_enu.translation();
  double max_speed = 0.0;
  for (double t = 0.1; t <= traj.duration(); t += 0.1) {
    const auto st = traj.at(t);
    const Eigen::Vector3d p = st.vehicle_to_enu.translation();
    // At most cruise speed (11 m/s) for 0.1 s, plus a little for curvature of the sampling.
    EXPECT_LT((p - prev).head<2>().norm(), 1.2) << "jump at t=" << t;
    // The car stands on the ground.
    EXPECT_NEAR(p.z(), n.world->height(p.x(), p.y()), 1e-9);
    // Its orientation is a rotation.
    EXPECT_NEAR(st.vehicle_to_enu.linear().determinant(), 1.0, 1e-9);
    max_speed = std::max(max_speed, st.speed);
    prev = p;
  }
  EXPECT_LE(max_speed, o.cruise_speed_mps + 0.2);
  EXPECT_GT(max_speed, 0.7 * o.cruise_speed_mps);
}

TEST(Drive, EgoLaneletContainsTheCar) {
  const Net& n = westOakland();
  sim::DriveOptions o;
  o.seed = 3;
  o.duration_s = 60.0;
  const auto plan = sim::planDrive(*n.sk, n.world->truth(), o);
  const sim::Trajectory traj(n.world->truth(), *n.world, plan, o);
  int on_road = 0, inside = 0;
  for (double t = 0.0; t <= traj.duration(); t += 0.5) {
    const auto st = traj.at(t);
    if (st.road_id < 0) continue;
    ++on_road;
    const Eigen::Vector3d p = st.vehicle_to_enu.translation();
    const auto g = n.world->sample(p.x(), p.y());
    // On a road the rear axle is in the ego lanelet (a lane change hands over at its middle).
    inside += g.lanelet == st.lanelet;
  }
  ASSERT_GT(on_road, 20);
  EXPECT_GE(inside, 0.9 * on_road) << inside << " of " << on_road;
}

TEST(Drive, GivenRouteNodesAreFollowed) {
  const Net& n = westOakland();
  sim::DriveOptions o;
  o.seed = 4;
  o.duration_s = 40.0;
  const auto auto_plan = sim::planDrive(*n.sk, n.world->truth(), o);
  ASSERT_GE(auto_plan.roads.size(), 2u);
  sim::DriveOptions given = o;
  given.route_nodes = {n.sk->road(auto_plan.roads[0])->from, n.sk->road(auto_plan.roads[1])->to};
  const auto plan = sim::planDrive(*n.sk, n.world->truth(), given);
  ASSERT_FALSE(plan.roads.empty());
  EXPECT_EQ(n.sk->road(plan.roads.front())->from, given.route_nodes[0]);
  EXPECT_EQ(n.sk->road(plan.roads.back())->to, given.route_nodes[1]);
}

TEST(Drive, ImpossibleRoutesAreRejected) {
  const Net& n = westOakland();
  sim::DriveOptions o;
  o.route_nodes = {1, 2};
  EXPECT_THROW(sim::planDrive(*n.sk, n.world->truth(), o), sim::RouteError);
  o.route_nodes = {n.sk->intersections().front().id};
  EXPECT_THROW(sim::planDrive(*n.sk, n.world->truth(), o), sim::RouteError);
}

TEST(Drive, SomeSeedsChangeLanes) {
  const Net& n = westOakland();
  int changes = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    sim::DriveOptions o;
    o.seed = seed;
    o.duration_s = 120.0;
    const auto plan = sim::planDrive(*n.sk, n.world->truth(), o);
    for (const auto& leg : plan.legs) changes += leg.lane_change_to_next;
  }
  EXPECT_GT(changes, 0) << "no lane change in 10 two-minute drives";
}

}  // namespace
