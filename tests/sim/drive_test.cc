// The simulated car's route, lanes and motion over the real West Oakland network.
#include "core/camera/camera_model.h"
#include "core/osm/osm_data.h"
#include "core/sim/camera_renderer.h"
#include "core/sim/drive.h"
#include "core/sim/world_builder.h"
#include "core/skeleton/skeleton.h"
#include "processes/framework/process.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

namespace {

using namespace lanemap;

struct Net {
  osm::OsmData osm;
  std::unique_ptr<skeleton::Skeleton> sk;
  std::unique_ptr<sim::SimWorld> world;
};

// The network of data/`osm_rel`, its skeleton and its world (seed 1).
Net* loadNet(const std::string& osm_rel) {
  auto* n = new Net;
  n->osm = osm::readOsm(lanemap::testing::dataPath(osm_rel));
  n->sk = std::make_unique<skeleton::Skeleton>(skeleton::Skeleton::build(n->osm));
  sim::WorldOptions o;
  o.seed = 1;
  n->world = sim::buildWorld(*n->sk, o);
  return n;
}

const Net& westOakland() {
  static Net* net = loadNet("osm/west-oakland.osm");
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
      // A U-turn only where nothing else goes on: at a dead end.
      if (a->reverse_id == b->id) {
        EXPECT_TRUE(n.sk->intersection(a->to)->dead_end) << "U-turn, seed " << seed;
      }
    }
    // Every leg follows the lane graph: a successor, a lane change to a neighbour lane, or a U-turn
    // at a dead end onto the reverse road.
    const auto& truth = n.world->truth();
    for (size_t i = 0; i + 1 < plan.legs.size(); ++i) {
      const auto* a = truth.lanelet(plan.legs[i].lanelet);
      const auto* b = truth.lanelet(plan.legs[i + 1].lanelet);
      ASSERT_TRUE(a && b);
      if (plan.legs[i].u_turn_to_next) {
        EXPECT_EQ(n.sk->road(a->road_id)->reverse_id, b->road_id);
        EXPECT_TRUE(a->successors.empty());
      } else if (plan.legs[i].lane_change_to_next) {
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

// Inside an intersection there is no road lane under the car. With label_ahead_max_turn_deg set,
// once the car heads into the road lanelet it drives into next (within that of the lane's
// direction), the labels follow that lanelet, so the road ahead is drivable in the frames taken
// while the car turns onto it rather than background until the car is on it.
TEST(Drive, InsideAnIntersectionTheLabelsFollowTheRoadAhead) {
  const Net& n = westOakland();
  const auto& truth = n.world->truth();
  sim::DriveOptions o;
  o.seed = 3;
  o.duration_s = 60.0;
  o.label_ahead_max_turn_deg = 30.0;
  const auto plan = sim::planDrive(*n.sk, truth, o);
  const sim::Trajectory traj(truth, *n.world, plan, o);
  auto headingTo = [&](const sim::VehicleState& st, const map::Lanelet& lane) {
    const Eigen::Vector2d car = st.vehicle_to_enu.linear().col(0).head<2>().normalized();
    const Eigen::Vector2d dir = (lane.centre[1] - lane.centre[0]).head<2>().normalized();
    return std::acos(std::clamp(car.dot(dir), -1.0, 1.0)) * 180.0 / M_PI;
  };
  int in_junction = 0, labelled = 0;
  // The labelled junction sample nearest its road ahead but 3 m or more before it.
  double frame_t = -1.0, frame_left = 1e9;
  for (double t = 0.0; t <= traj.duration(); t += 0.25) {
    const auto st = traj.at(t);
    const auto* ll = truth.lanelet(st.lanelet);
    ASSERT_NE(ll, nullptr);
    if (ll->kind == map::LaneletKind::kRoad) {
      EXPECT_EQ(st.label_lanelet, st.lanelet) << "t " << t;
      continue;
    }
    ++in_junction;
    if (st.label_lanelet < 0) continue;
    ++labelled;
    const auto* ahead = truth.lanelet(st.label_lanelet);
    ASSERT_NE(ahead, nullptr) << "t " << t;
    EXPECT_EQ(ahead->kind, map::LaneletKind::kRoad);
    EXPECT_NE(std::find(ll->successors.begin(), ll->successors.end(), st.label_lanelet), ll->successors.end())
        << "t " << t << ": lanelet " << st.label_lanelet << " does not follow " << st.lanelet;
    // The car heads into it (the path's heading over +-1 m and the pose's yaw differ by a few degrees).
    EXPECT_LT(headingTo(st, *ahead), o.label_ahead_max_turn_deg + 8.0) << "t " << t;
    const Eigen::Vector2d p = st.vehicle_to_enu.translation().head<2>();
    const double left = (ahead->centre.front().head<2>() - p).norm();
    if (left >= 3.0 && left < frame_left) frame_left = left, frame_t = t;
  }
  ASSERT_GT(labelled, 4) << "of " << in_junction << " samples in an intersection";
  ASSERT_GE(frame_t, 0.0);

  // That frame: the road ahead is the ego lane (and perhaps its neighbours); labelled relative to
  // the intersection lanelet the car is in, it would all be background.
  const auto st = traj.at(frame_t);
  const sim::CameraRenderer renderer(camera::CameraModel::fromYamlFile(std::string(LANEMAP_DATA_DIR) + "/../config/vehicle.yaml"));
  auto count = [](const cv::Mat& labels, bool any_lane) {
    int n = 0;
    for (int v = 0; v < labels.rows; ++v)
      for (int u = 0; u < labels.cols; ++u) {
        const auto c = static_cast<sim::LabelClass>(labels.at<uint8_t>(v, u));
        n += any_lane ? (c >= sim::LabelClass::kLaneEgo && c <= sim::LabelClass::kLaneRightRight)
                      : c == sim::LabelClass::kLaneEgo;
      }
    return n;
  };
  const cv::Mat ahead = renderer.render(*n.world, st.vehicle_to_enu, st.label_lanelet, 7).labels;
  const cv::Mat in_place = renderer.render(*n.world, st.vehicle_to_enu, st.lanelet, 7).labels;
  EXPECT_GT(count(ahead, false), 1000) << "t " << frame_t << ", " << frame_left << " m before the road ahead";
  EXPECT_EQ(count(in_place, true), 0);
}

// label_ahead_max_turn_deg bounds which samples inside an intersection carry the lane ahead's
// labels: 180 labels every one; 30 not the first part of a turn; 2 fewer still; the default
// (negative) none, as the simulator labelled before the option.
TEST(Drive, LabelAheadTurnLimitBoundsWhichJunctionSamplesAreLabelled) {
  const Net& n = westOakland();
  const auto& truth = n.world->truth();
  auto labelled = [&](double max_turn_deg) {
    sim::DriveOptions o;
    o.seed = 3;
    o.duration_s = 60.0;
    o.label_ahead_max_turn_deg = max_turn_deg;
    const auto plan = sim::planDrive(*n.sk, truth, o);
    const sim::Trajectory traj(truth, *n.world, plan, o);
    int in_junction = 0, with_label = 0;
    for (double t = 0.0; t <= traj.duration(); t += 0.25) {
      const auto st = traj.at(t);
      if (truth.lanelet(st.lanelet)->kind == map::LaneletKind::kRoad) continue;
      ++in_junction;
      with_label += st.label_lanelet >= 0;
    }
    return std::make_pair(with_label, in_junction);
  };
  const auto all = labelled(180.0), some = labelled(30.0), few = labelled(2.0);
  const auto none = labelled(sim::DriveOptions().label_ahead_max_turn_deg);
  EXPECT_EQ(none.first, 0);
  EXPECT_GT(none.second, 4);
  EXPECT_EQ(all.first, all.second);
  EXPECT_LT(some.first, all.first);
  EXPECT_GT(some.first, 0);
  EXPECT_LT(few.first, some.first);
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

// On a small extract every road out of the junction ends at the extract's edge (montlake: five
// two-way roads meeting at one roundabout, all dead ends beyond it). The car no longer stops at the
// first of them (a 46 s drive of one road that never reached the junction): it drives into one,
// turns round at its end onto the reverse road and comes back through the junction, so the drive
// lasts its duration and passes the junction several times.
TEST(Drive, AtADeadEndTheCarTurnsRoundAndDrivesOn) {
  static const Net* net = loadNet("osm/dev/montlake_roundabout.osm");
  const auto& truth = net->world->truth();
  sim::DriveOptions o;
  o.seed = 1;
  o.duration_s = 150.0;
  const auto plan = sim::planDrive(*net->sk, truth, o);
  int u_turns = 0, junctions = 0;
  for (size_t i = 0; i + 1 < plan.legs.size(); ++i) {
    const auto* a = truth.lanelet(plan.legs[i].lanelet);
    const auto* b = truth.lanelet(plan.legs[i + 1].lanelet);
    ASSERT_TRUE(a && b);
    junctions += b->kind == map::LaneletKind::kIntersection;
    if (!plan.legs[i].u_turn_to_next) continue;
    ++u_turns;
    const auto* road = net->sk->road(a->road_id);
    EXPECT_TRUE(net->sk->intersection(road->to)->dead_end);
    EXPECT_EQ(road->reverse_id, b->road_id);
    // The nearest lane back: across the road, not further.
    EXPECT_LT((b->centre.front() - a->centre.back()).head<2>().norm(), 8.0);
  }
  EXPECT_GE(u_turns, 2);
  EXPECT_GE(junctions, 3);
  const sim::Trajectory traj(truth, *net->world, plan, o);
  EXPECT_NEAR(traj.duration(), o.duration_s, 1e-6);
  // The turn is driven, slowly, with no jump; the car is on no lane while it turns.
  Eigen::Vector3d prev = traj.at(0.0).vehicle_to_enu.translation();
  int turning = 0;
  double slowest = 1e9;
  for (double t = 0.1; t <= traj.duration(); t += 0.1) {
    const auto st = traj.at(t);
    const Eigen::Vector3d p = st.vehicle_to_enu.translation();
    EXPECT_LT((p - prev).head<2>().norm(), 1.2) << "jump at t=" << t;
    prev = p;
    if (st.lanelet < 0) {
      ++turning;
      EXPECT_EQ(st.road_id, -1);
      slowest = std::min(slowest, st.speed);
    }
  }
  EXPECT_GT(turning, 10);
  EXPECT_LT(slowest, 4.0);

  // Without turning round (the routes before, kept for the segmentation model's frames): the drive
  // stops at the first dead end, well short of its duration.
  o.turn_round_at_dead_ends = false;
  const auto stopped = sim::planDrive(*net->sk, truth, o);
  for (const auto& leg : stopped.legs) EXPECT_FALSE(leg.u_turn_to_next);
  EXPECT_LT(sim::Trajectory(truth, *net->world, stopped, o).duration(), 0.5 * o.duration_s);
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
