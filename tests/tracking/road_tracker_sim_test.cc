// The road tracker on simulated drives: fed the noisy POSE messages of a lanemap-sim log, it
// reports exactly the simulator's true route, and every "reached intersection" fires within 5 m
// of where the car truly entered that intersection's ROI (from the true trajectory,
// trajectory.csv).
#include "core/osm/osm_data.h"
#include "core/skeleton/skeleton.h"
#include "core/tracking/road_tracker.h"
#include "lanemap/pose_t.hpp"
#include "processes/framework/channels.h"
#include "processes/framework/pose_conversion.h"
#include "tests/common/sim_drive.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <fstream>
#include <iostream>
#include <sstream>

namespace {

using namespace lanemap;

struct TruePoint {
  int64_t utime;
  Eigen::Vector2d p;
};

std::vector<TruePoint> readTrajectory(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);  // header
  std::vector<TruePoint> out;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    out.push_back({static_cast<int64_t>(v[1]), {v[2], v[3]}});
  }
  return out;
}

Eigen::Vector2d truePositionAt(const std::vector<TruePoint>& traj, int64_t utime) {
  for (size_t i = 1; i < traj.size(); ++i) {
    if (traj[i].utime >= utime) {
      const double u = double(utime - traj[i - 1].utime) / double(traj[i].utime - traj[i - 1].utime);
      return traj[i - 1].p + std::clamp(u, 0.0, 1.0) * (traj[i].p - traj[i - 1].p);
    }
  }
  return traj.back().p;
}

// pose_stride 1: every POSE (100 Hz); 100: one pose a second, where the event comes up to a
// second late and its estimated crossing point (interpolated) is what must be within 5 m.
void checkDrive(uint64_t seed, int pose_stride = 1) {
  const std::string dir = lanemap::testing::sharedSimDrive("osm/west-oakland.osm", 120.0, seed, "--no-lidar --camera-hz 0.1");
  nlohmann::json scenario;
  std::ifstream(dir + "/scenario.json") >> scenario;
  const auto sk = skeleton::Skeleton::build(osm::readOsm(dir + "/roads.osm"));
  const auto traj = readTrajectory(dir + "/trajectory.csv");

  tracking::RoadTracker tracker(sk);
  std::vector<tracking::RoadEvent> events;
  lcm::LogFile log(dir + "/drive.lcmlog", "r");
  ASSERT_TRUE(log.good());
  int poses = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel != channels::kPose) continue;
    if (poses++ % pose_stride != 0) continue;
    pose_t msg{};
    ASSERT_GT(msg.decode(ev->data, 0, ev->datalen), 0);
    for (auto& e : tracker.update(toPoseInput(toEnuPose(msg, sk.frame())))) events.push_back(e);
  }

  ASSERT_GT(poses, 110 * 100) << "a 120 s drive has 100 Hz poses";
  std::vector<int64_t> true_route;
  std::vector<int64_t> true_reached;  // end intersections of the roads the car drove to the end
  for (const auto& r : scenario["route"]) {
    true_route.push_back(r["road_id"].get<int64_t>());
    if (!r["left_utime"].is_null()) true_reached.push_back(r["to"].get<int64_t>());
  }
  ASSERT_GE(true_route.size(), 2u) << "seed " << seed << ": a 120 s drive crosses intersections";
  std::vector<int64_t> entered;
  for (const auto& e : events) {
    if (e.type == tracking::RoadEventType::kEnteredRoad) entered.push_back(e.road_id);
    EXPECT_NE(e.type, tracking::RoadEventType::kWrongWay) << "seed " << seed;
    EXPECT_NE(e.type, tracking::RoadEventType::kLeftMap) << "seed " << seed;
  }
  // The drive may end inside the last road: the tracker has entered every road of the route.
  EXPECT_EQ(entered, true_route) << "seed " << seed;

  std::vector<int64_t> reached_ids;
  for (const auto& e : events) {
    if (e.type != tracking::RoadEventType::kReachedIntersection) continue;
    reached_ids.push_back(e.intersection_id);
    const auto* inter = sk.intersection(e.intersection_id);
    ASSERT_NE(inter, nullptr);
    // Where the car truly entered that ROI: the first true sample, up to the event, that is inside
    // the polygon or past the ROI boundary across the closed road (s >= s_end). A car turning
    // right from the outer lane can cut the corner of a small ROI polygon without entering it.
    const auto* road = sk.road(e.road_id);
    ASSERT_NE(road, nullptr);
    std::optional<Eigen::Vector2d> entry;
    for (size_t i = 0; i < traj.size() && traj[i].utime <= e.utime + 2000000; ++i) {
      if (traj[i].utime < e.utime - 10000000) continue;
      if (skeleton::pointInPolygon(inter->roi, traj[i].p) || sk.project(road->id, traj[i].p).s >= road->s_end) {
        entry = traj[i].p;
        break;
      }
    }
    const Eigen::Vector2d at = pose_stride == 1 ? truePositionAt(traj, e.utime) : e.position;
    const double d = (at - *entry).norm();
    EXPECT_LT(d, 5.0) << "seed " << seed << " stride " << pose_stride << " intersection " << e.intersection_id;
  }
  EXPECT_EQ(reached_ids, true_reached) << "seed " << seed;
}

TEST(RoadTrackerOnSimulatedDrives, FollowsTheTrueRouteSeed1) { checkDrive(1); }
TEST(RoadTrackerOnSimulatedDrives, FollowsTheTrueRouteSeed2) { checkDrive(2); }
TEST(RoadTrackerOnSimulatedDrives, FollowsTheTrueRouteSeed3) { checkDrive(3); }
TEST(RoadTrackerOnSimulatedDrives, FollowsTheTrueRouteAtOnePoseASecond) { checkDrive(1, 100); }

}  // namespace
