// The simulated car's drive: a route through the street network (atomic roads), the lanes it takes
// (lanelets of the ground-truth map, with lane changes), and its trajectory in time (position,
// orientation on the non-flat ground, speed), from which poses and sensor frames are sampled.
#pragma once

#include "core/map/lane_map.h"
#include "core/sim/world.h"
#include "core/skeleton/skeleton.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::config { class YamlReader; }

namespace lanemap::sim {

class RouteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DriveOptions {
  uint64_t seed = 1;
  double duration_s = 120.0;         // the drive stops at the end of the route or after this
  double cruise_speed_mps = 11.0;    // ~40 km/h, urban
  double max_lateral_accel = 2.0;    // m/s^2: slows down in curves and turns
  double accel = 1.5;                // m/s^2 from standstill and after turns
  double lane_change_length_m = 30.0;
  // Auto routes: chance of a lane change on a road lanelet of 40 m or more with a neighbour lane.
  // Given routes: spread of the seeded lane preferences (lanes cost 1 +- this per metre).
  double lane_change_probability = 0.35;
  // Inside an intersection the camera's lane classes follow the road lanelet the car drives into
  // next once the car heads within this of that lane's direction at its start (VehicleState::
  // label_lanelet; 180: from the intersection's entry on). Negative (the default): never, every
  // lane is background while the car is inside an intersection. Measured on the broad benchmark
  // (README, "Labels inside a junction"): no pooled gain yet with the mapper and model of today.
  double label_ahead_max_turn_deg = -1.0;
  std::vector<int64_t> route_nodes;  // intersection ids to pass through, in order; empty: auto
  // Auto routes: when no walk avoiding dead ends lasts the drive, walks that turn round at a dead
  // end (planDrive). false: the longest walk that stops at the first dead end (routes before
  // 2026-12-06; the segmentation model's frames, seg::renderSimFrames, keep those).
  bool turn_round_at_dead_ends = true;

  // Reads the keys present in a `drive` node (config/sim_drive.yaml); others keep their defaults.
  // An unknown key or a bad value throws config::ConfigError naming it.
  static DriveOptions fromYaml(const YAML::Node& node);
  static DriveOptions fromYaml(const config::YamlReader& r);  // the caller's finish() checks the keys
};

// One sample of the car's true motion. The vehicle frame: x forward, y left, z up, origin at the
// rear axle on the ground.
struct VehicleState {
  double t = 0.0;                      // seconds since the drive's start
  Eigen::Isometry3d vehicle_to_enu = Eigen::Isometry3d::Identity();
  double speed = 0.0;                  // m/s
  double yaw_rate = 0.0;               // rad/s
  int64_t lanelet = -1;                // the lanelet the car is in (ego lane)
  int64_t road_id = -1;                // the atomic road, -1 inside an intersection
  // The road lanelet the camera's lane classes are relative to: `lanelet` on a road; inside an
  // intersection -1 (every lane background), or, with DriveOptions::label_ahead_max_turn_deg set,
  // the road lanelet the car drives into next once the car heads within that of it (as BDD100K's
  // "direct" drivable area, the lane the car is on or heading into).
  int64_t label_lanelet = -1;
};

// The lanelets the car drives through and where in each it changes lane.
struct LanePlan {
  struct Leg {
    int64_t lanelet = -1;
    bool lane_change_to_next = false;  // the next leg is a neighbour lane (same road)
    // The lane ends at a dead end (an extract's edge, a cul-de-sac): the car turns round there
    // onto the next leg, a lane of the reverse road (auto routes only, where nothing else goes on).
    bool u_turn_to_next = false;
  };
  std::vector<Leg> legs;
  std::vector<int64_t> roads;          // atomic road ids in order (the route)
  std::vector<int64_t> intersections;  // intersection ids passed, in order (ends of the roads)
};

// Plans the route and its lanes. Auto (options.route_nodes empty): a seeded random walk over the
// lane graph that turns where its lane allows, changes lanes now and then, avoids U-turns, dead
// ends and roads already driven where it can, long enough for duration_s at cruise speed; where
// nothing but dead ends goes on (a small extract's edges) it drives into one and turns round at
// its end, as a mapping car at the edge of its area would. With
// route_nodes: through those intersections in order (fewest roads between consecutive ones, then
// the cheapest lanes); throws RouteError, naming where it fails, when that is impossible.
LanePlan planDrive(const skeleton::Skeleton& skeleton, const map::LaneMap& truth,
                   const DriveOptions& options);

// The car's true motion along a LanePlan on the World's surface, sampled at any time.
class Trajectory {
 public:
  Trajectory(const map::LaneMap& truth, const World& world, const LanePlan& plan,
             const DriveOptions& options);

  double duration() const { return duration_; }
  double length() const { return s_.empty() ? 0.0 : s_.back(); }
  VehicleState at(double t) const;

 private:
  struct PathPoint {
    Eigen::Vector2d p;
    int64_t lanelet;
    int64_t road_id;
    int64_t label_lanelet = -1;  // VehicleState::label_lanelet
  };
  double arcLengthAt(double t) const;
  Eigen::Isometry3d poseAt(double s) const;

  const World& world_;
  std::vector<PathPoint> path_;  // dense, ~0.5 m apart
  std::vector<double> s_;        // arc length of each path point
  std::vector<double> t_of_s_;   // time at each path point (speed profile)
  double duration_ = 0.0;
};

}  // namespace lanemap::sim
