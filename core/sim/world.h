// What the simulator's sensors see: a ground surface with a height and a paint/material at every
// point, obstacles (parked cars, buildings), and the ground-truth lanes. Built from OSM by
// sim::buildWorld (world_builder.h); a test can implement World with a hand-made scene.
#pragma once

#include "core/map/lane_map.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <vector>

namespace lanemap::sim {

// What the ground is at a point (the top-most paint wins).
enum class Surface : uint8_t {
  kOffRoad = 0,     // grass, dirt, building ground
  kSidewalk,
  kAsphalt,         // drivable, inside a road lane (GroundSample::lanelet says which)
  kIntersection,    // drivable asphalt inside an intersection, no lane
  kParking,         // parking lane or bus bay asphalt, not a driving lane
  kBikeLane,
  kDashedPaint,
  kSolidPaint,
  kCrosswalkPaint,
  kStopLinePaint,
  kCurb,
};

struct GroundSample {
  Surface surface = Surface::kOffRoad;
  int64_t lanelet = -1;  // the road lanelet this point lies in (-1 for none); set for paint too
};

struct Obstacle {
  enum class Kind : uint8_t { kParkedCar, kBuilding };
  Kind kind = Kind::kParkedCar;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();      // ENU; z is the box centre
  double yaw = 0.0;                                       // rotation about up
  Eigen::Vector3d half_extent = Eigen::Vector3d::Ones();  // along its own x, y, z
  Eigen::Vector3f colour = Eigen::Vector3f(0.5f, 0.5f, 0.5f);  // RGB in [0, 1]
};

class World {
 public:
  virtual ~World() = default;
  // Ground height (ENU up, metres) at (east, north).
  virtual double height(double east, double north) const = 0;
  virtual GroundSample sample(double east, double north) const = 0;
  // Obstacles whose footprint may be within `radius` of p (a superset is fine).
  virtual void obstaclesNear(const Eigen::Vector2d& p, double radius,
                             std::vector<const Obstacle*>* out) const = 0;
  // Lanes between two road lanelets of the same road cross-section, counted left to right as seen
  // from `ego` (negative: `other` is left of ego; 0: the same lane); nullopt when they are not in
  // one cross-section.
  virtual std::optional<int> laneOffset(int64_t ego, int64_t other) const = 0;
};

// Semantic classes of METHOD.md section 2 (same ids as lanemap.label_image_t).
enum class LabelClass : uint8_t {
  kBackground = 0, kLaneEgo = 1, kLaneLeft = 2, kLaneRight = 3, kLaneLeftLeft = 4,
  kLaneRightRight = 5, kDashedLine = 6, kSolidLine = 7, kCrosswalk = 8, kCurb = 9, kStopLine = 10,
};
inline constexpr int kNumLabelClasses = 11;

// The label a camera would see for a ground sample when driving in `ego_lanelet` (-1: none).
LabelClass labelFor(const World& world, const GroundSample& g, int64_t ego_lanelet);

}  // namespace lanemap::sim
