// The road tracker (LCM-free): map-matches vehicle poses to the skeleton M0 and says when the car
// enters an atomic road E_ij, reaches its end intersection I_j (which closes the road), leaves the
// map, drives the wrong way on a one-way road, or loses its pose. processes/road_tracker wraps it.
//
// How it stays robust (details in road_tracker.cc):
// - positions go through a constant-velocity Kalman filter (white GNSS noise of +-3 m shrinks to a
//   few decimetres at 100 Hz; at 1 Hz it passes the measurements nearly as they are);
// - graph continuity: on a road, the tracker stays on it until the car crosses s_end (the ROI of
//   I_j); in an intersection only its outgoing roads are candidates; another road replaces the
//   current one mid-road only when it is better by switch_margin_m for switch_time_s (hysteresis);
// - crossing times are interpolated between two poses, so 1 Hz poses give events at the place the
//   car crossed the ROI boundary, not up to a pose interval later.
#pragma once

#include "core/geo/time_order.h"
#include "core/skeleton/skeleton.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lanemap::config { class YamlReader; }

namespace lanemap::tracking {

struct PoseInput {
  int64_t utime = 0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // ENU metres in the skeleton's frame
  double heading = 0.0;  // radians, ENU, 0 = east, counter-clockwise (vehicle x axis)
  bool valid = true;     // false: the pose source has no fix (pose_t STATUS_INVALID)
  std::optional<Eigen::Vector2d> velocity;  // ENU m/s when the source gives it
};

// Values equal road_event_t's TYPE_* constants.
enum class RoadEventType : int8_t {
  kEnteredRoad = 1,
  kReachedIntersection = 2,  // closes road_id
  kLeftMap = 3,
  kWrongWay = 4,
  kPoseLost = 5,
};
const char* toString(RoadEventType type);

struct RoadEvent {
  RoadEventType type = RoadEventType::kEnteredRoad;
  int64_t utime = 0;           // utime of the pose that caused the event
  int64_t crossing_utime = 0;  // estimated time the car crossed the ROI boundary (<= utime)
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // estimated crossing point (filtered)
  int64_t road_id = -1;        // the atomic road concerned
  int64_t from_node = -1;      // its I_i
  int64_t to_node = -1;        // its I_j
  int64_t previous_road_id = -1;
  int64_t intersection_id = -1;  // intersection reached (kReachedIntersection)
  double distance_m = 0.0;       // distance from the road's polyline
  std::string detail;
};

struct RoadTrackerConfig {
  double measurement_sigma_m = 1.5;    // GNSS position noise (1 sigma) for the filter
  double acceleration_sigma = 5.0;     // m/s^2, process noise of the constant-velocity filter
  double acquire_distance_m = 8.0;     // first match / re-match: road at most this far
  double acquire_heading_rad = 0.8;    // ... and heading within this (about 45 degrees)
  double exit_distance_m = 8.0;        // leaving an intersection onto an outgoing road
  double exit_heading_rad = 1.2;       // about 70 degrees
  double u_turn_heading_rad = 0.6;     // leaving onto the reverse of the incoming road
  double exit_ambiguity_m = 2.0;       // two outgoing roads fit: wait until one is this much better
  double exit_commit_m = 15.0;         // ... or the car is this far beyond s_begin
  double switch_margin_m = 4.0;        // mid-road switch: other road's cost lower by this ...
  double switch_time_s = 1.0;          // ... for this long (and two poses at least)
  double left_map_distance_m = 25.0;   // no road this close ...
  double left_map_time_s = 1.0;        // ... for this long -> left map
  double wrong_way_heading_rad = 2.0;  // about 115 degrees against a one-way road ...
  double wrong_way_time_s = 0.5;       // ... for this long (and two poses) -> wrong way
  double pose_gap_s = 1.0;             // no valid pose for longer -> pose lost
  double max_innovation_m = 30.0;      // a jump larger than this restarts the filter
  // Poses whose time goes back by more than this (3 in a row, increasing: a log restarted, a
  // receiver's clock reset) restart the tracking: POSE_LOST for the current road, then as new.
  // A single older pose, or one less far back, is out of order and ignored.
  double time_jump_s = 1.0;

  // The keys present in `node` (config/road_tracker.yaml `tracker:`), defaults for the others; an
  // unknown key or a mistyped value throws config::ConfigError naming the key.
  static RoadTrackerConfig fromYaml(const YAML::Node& node);
  // The same from a config section (the caller's finish() refuses unknown keys).
  static RoadTrackerConfig fromYaml(const config::YamlReader& r);
};

class RoadTracker {
 public:
  enum class State { kSearching, kOnRoad, kInIntersection, kOffMap };

  // The skeleton must outlive the tracker.
  explicit RoadTracker(const skeleton::Skeleton& skeleton, RoadTrackerConfig config = {});

  // Feeds one pose (in utime order); returns the events it caused, in order.
  std::vector<RoadEvent> update(const PoseInput& pose);

  State state() const { return state_; }
  int64_t currentRoad() const { return road_; }                 // -1 when not on a road
  int64_t currentIntersection() const { return intersection_; }  // -1 when not in one
  bool wrongWay() const { return wrong_way_; }
  Eigen::Vector2d filteredPosition() const { return filter_.position(); }

  struct Stats {
    int64_t poses = 0, invalid = 0, out_of_order = 0, filter_resets = 0, events = 0, rematches = 0;
    int64_t duplicates = 0;  // same utime as the last pose: ignored
    int64_t time_jumps = 0;  // restarts after a time jump backwards
  };
  const Stats& stats() const { return stats_; }

 private:
  // Constant-velocity Kalman filter, x and y independent.
  class Filter {
   public:
    void reset(const Eigen::Vector2d& p, const std::optional<Eigen::Vector2d>& v);
    // Returns false (and changes nothing) when the innovation exceeds max_innovation.
    bool update(const Eigen::Vector2d& z, double dt, double r, double q, double max_innovation);
    Eigen::Vector2d position() const { return Eigen::Vector2d(x_(0), y_(0)); }
    Eigen::Vector2d velocity() const { return Eigen::Vector2d(x_(1), y_(1)); }

   private:
    Eigen::Vector2d x_ = Eigen::Vector2d::Zero(), y_ = Eigen::Vector2d::Zero();
    Eigen::Matrix2d px_ = Eigen::Matrix2d::Identity(), py_ = Eigen::Matrix2d::Identity();
  };

  void step(const PoseInput& pose, std::vector<RoadEvent>& events);
  bool stepSearching(const PoseInput& pose, std::vector<RoadEvent>& events);
  bool stepOnRoad(const PoseInput& pose, std::vector<RoadEvent>& events);
  bool stepInIntersection(const PoseInput& pose, std::vector<RoadEvent>& events);
  bool checkLeftMap(const PoseInput& pose, double nearest_distance, std::vector<RoadEvent>& events);
  void enterRoad(const skeleton::RoadMatch& m, const PoseInput& pose, bool wrong_way, double s_cross,
                 const std::string& detail, std::vector<RoadEvent>& events);
  void reachIntersection(int64_t intersection_id, const PoseInput& pose, double s_cross,
                         const std::string& detail, std::vector<RoadEvent>& events);
  RoadEvent makeEvent(RoadEventType type, const PoseInput& pose, int64_t road_id) const;
  // POSE_LOST for the current road (detail: why), and the tracking state back to searching.
  void losePose(const PoseInput& pose, const std::string& detail, std::vector<RoadEvent>& events);
  // Interpolates the crossing of arc length s_cross on `road` between the last and this pose.
  void interpolateCrossing(RoadEvent& e, int64_t road, double s_cross) const;

  const skeleton::Skeleton& skeleton_;
  RoadTrackerConfig config_;
  State state_ = State::kSearching;
  int64_t road_ = -1;          // current road (kOnRoad), or the road that led into the intersection
  int64_t intersection_ = -1;  // kInIntersection
  int64_t last_road_ = -1;     // the road before the current state (previous_road_id)
  bool wrong_way_ = false;
  double last_s_ = 0.0;  // arc length on the current road at the previous pose
  bool wrong_way_reported_ = false;
  double wrong_way_since_s_ = -1.0;
  int wrong_way_poses_ = 0;
  std::map<int64_t, std::pair<int64_t, Eigen::Vector2d>> exit_crossings_;  // road -> first crossing
  int64_t switch_candidate_ = -1;
  double switch_since_s_ = -1.0;
  int switch_poses_ = 0;
  double far_since_s_ = -1.0;  // time since no road is within left_map_distance_m
  bool filter_ready_ = false;
  Filter filter_;
  int64_t last_utime_ = 0;
  geo::TimeOrder order_;
  int64_t last_valid_utime_ = 0;
  bool have_last_valid_ = false;
  bool lost_reported_ = false;
  double now_s_ = 0.0;  // utime of the pose being processed, seconds
  Eigen::Vector2d prev_position_ = Eigen::Vector2d::Zero();  // filtered, at the previous pose
  int64_t prev_utime_ = 0;
  bool have_prev_ = false;
  Stats stats_;
};

}  // namespace lanemap::tracking
