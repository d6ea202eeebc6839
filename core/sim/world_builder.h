// The simulator's world built from an OSM road skeleton: lanes laid out from the OSM lane tags
// (lanes, lanes:forward/backward, oneway, turn:lanes, width) with defaults by road class, seeded
// irregularities (parking and bike lanes, bus bays, turn pockets, faded and missing markings,
// crosswalks, stop lines, sidewalks), a road surface that is not flat (crown, grades, bumps),
// obstacles (parked cars, buildings) and the ground-truth lane map (map::LaneMap).
//
// SimWorld answers height() and sample() from lazily rasterised tiles kept in a bounded cache, so
// it is fast and thread-safe for the renderers and its memory stays flat on a long drive.
#pragma once

#include "core/map/lane_map.h"
#include "core/osm/osm_data.h"
#include "core/sim/world.h"
#include "core/skeleton/skeleton.h"

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace lanemap::config { class YamlReader; }

namespace lanemap::sim {

class WorldConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct WorldOptions {
  uint64_t seed = 1;
  bool flat = false;                // no grade, crown, bumps: height() == 0 everywhere
  bool right_hand_traffic = true;   // false: left-hand traffic (the layout is mirrored)
  // Roads on different OSM levels (`layer`, else bridge=* 1 and tunnel=* -1) that cross: the world
  // is one ground, painted per level, the upper level's surface and paint over the lower's; a
  // camera or LIDAR sees it from its car's level (SimWorld::sampleSeenFrom): its own level over
  // those beneath, the levels above (a bridge over its road) left out. An intersection is on the
  // lowest level of its roads. false: every road on one level, every road's kerbs and lines
  // painted over every road's lanes (a ramp's kerbs across the motorway under it).
  bool osm_layers = true;

  // Lanes. A lane's width is width/lanes when the way has `width`, else the class default (or
  // default_lane_width_m when > 0) plus a seeded per-lane variation; always clamped to the range.
  double default_lane_width_m = 0.0;
  double lane_width_jitter_m = 0.15;
  double lane_width_min_m = 2.8;
  double lane_width_max_m = 3.7;

  // Irregularities (probabilities per road side, per direction, per approach, per line, ...).
  double p_parking_lane = 0.4;     // per curb side of a residential/tertiary/unclassified road
  double p_bike_lane = 0.3;        // per curb side of a primary/secondary/tertiary road
  double p_bus_bay = 0.25;         // per direction of a primary/secondary/tertiary road
  double p_turn_pocket = 0.35;     // per approach to an intersection of a long enough road
  double p_faded_marking = 0.15;   // per marking line: one stretch where the paint is worn
  double p_missing_marking = 0.08; // per marking line: one stretch with no paint at all
  double p_crosswalk = 0.6;        // per road end at an intersection of 3+ roads
  double p_stop_line = 0.8;        // per approach to an intersection of 3+ roads
  double p_sidewalk = 0.9;         // per curb side (service roads: a third of it)
  double parked_car_occupancy = 0.6;  // fraction of parking-lane slots with a car
  double p_building = 0.7;         // per building slot behind the sidewalk

  // Surface.
  double crown_slope = 0.02;       // cross-slope from the road centre to the curb
  double max_grade = 0.08;         // bound of the smooth terrain's slope (<= 0.10)
  double bump_amplitude_m = 0.02;  // short-wavelength unevenness (a few cm peak to peak)
  double curb_height_m = 0.12;     // sidewalks are this much above the road edge

  // Raster tiles behind sample() and height().
  double tile_size_m = 64.0;
  double tile_resolution_m = 0.05;   // paint / material / lanelet id
  double height_resolution_m = 0.25; // height grid (bilinear)
  int tile_cache_size = 24;          // tiles kept; older ones are dropped (memory stays flat)

  // Reads the keys present (all optional) from a YAML map (config/sim_world.yaml); a null node
  // gives the defaults. Throws WorldConfigError on a bad value or an unknown key.
  static WorldOptions fromYaml(const YAML::Node& node);
  // The same from a config reader (the caller's finish() refuses unknown keys); throws
  // config::ConfigError naming the file and key.
  static WorldOptions fromYaml(const config::YamlReader& r);
  static WorldOptions fromYamlFile(const std::string& path);
  void validate() const;  // throws WorldConfigError
};

// Lanes per direction of one OSM way, from its tags and road class (METHOD.md section 0 goal).
struct LaneCounts {
  int forward = 1;   // along the way's node order
  int backward = 1;  // against it; 0 for a one-way road
};
// `oneway`: the way is one-way (the skeleton has no reverse road); its lanes all count as forward.
LaneCounts laneCountsFor(const osm::Tags& tags, bool oneway);
// Class default lane width (metres) before variation and clamping.
double defaultLaneWidth(const std::string& highway);

// A stretch of one marking line whose paint is worn (faded: part of the pixels remain) or absent
// (missing: none). s is arc length along the LineString's points from its first point.
struct MarkingGap {
  int64_t line_id = 0;
  double s0 = 0.0, s1 = 0.0;
  bool missing = false;
};

// Dashed lines: paint from s = k * kDashPeriod to k * kDashPeriod + kDashLength along the line.
inline constexpr double kDashLength = 3.0;
inline constexpr double kDashPeriod = 9.0;
inline constexpr double kLinePaintWidth = 0.15;      // single lines
inline constexpr double kDoubleLineOffset = 0.1;     // solid_solid: two lines at +-0.1 m (0.1 wide)

// groundtruth.osm is written simplified to this tolerance (map::simplified, metres); the world
// builder checks that its lanelets stay sound (Lanelet2-readable) once simplified.
inline constexpr double kTruthSimplifyTolerance = 0.01;

struct WorldStats {
  size_t cross_sections = 0;       // way segments between intersections (both directions)
  size_t road_lanelets = 0;
  size_t intersection_lanelets = 0;
  size_t connections_not_built = 0;  // Lanelet2 would misread them (see world_builder.cc connect)
  size_t turns_restricted = 0;       // road-to-road turns an OSM turn restriction forbids: not built
  size_t lines = 0;
  size_t parking_lanes = 0, bike_lanes = 0, bus_bays = 0, turn_pockets = 0;
  size_t crosswalks = 0, stop_lines = 0, faded = 0, missing = 0;
  size_t parked_cars = 0, buildings = 0;
  double driving_lane_km = 0.0;
};

class SimWorld : public World {
 public:
  struct Impl;
  explicit SimWorld(std::unique_ptr<Impl> impl);
  ~SimWorld() override;
  SimWorld(const SimWorld&) = delete;
  SimWorld& operator=(const SimWorld&) = delete;

  // World. height() and sample() are thread-safe.
  double height(double east, double north) const override;
  GroundSample sample(double east, double north) const override;
  void obstaclesNear(const Eigen::Vector2d& p, double radius,
                     std::vector<const Obstacle*>* out) const override;
  std::optional<int> laneOffset(int64_t ego, int64_t other) const override;

  // Ground truth (origin = the skeleton frame's origin). Road lanelets carry road_id, from_node,
  // to_node, index_from_left; intersection lanelets intersection_id and turn.
  const map::LaneMap& truth() const;
  const std::vector<Obstacle>& obstacles() const;
  const map::Lanelet* lanelet(int64_t id) const;          // O(1); nullptr if unknown
  const map::LineString* line(int64_t id) const;          // O(1); nullptr if unknown
  const std::vector<int64_t>& predecessors(int64_t lanelet_id) const;
  const map::Lanelet* laneletAt(double east, double north) const;  // road lanelet under a point
  // Roads on several OSM levels (WorldOptions::osm_layers): the ground as a car on level `level`
  // sees it where roads of different levels cross: its own level's paint over those beneath, the
  // levels above it (a bridge over it) left out; sample() is the view from above (every level, the
  // upper over the lower). levelOf: the level of a lanelet's road or intersection (a value above
  // every level for an unknown id).
  GroundSample sampleSeenFrom(double east, double north, int level) const;
  int levelOf(int64_t lanelet_id) const;
  // The smooth terrain plus bumps, without the road's own shape (crown, curbs): height() minus
  // this is the cross-section profile. 0 when flat.
  double terrainHeight(double east, double north) const;
  const std::vector<MarkingGap>& markingGaps() const;
  const WorldOptions& options() const;
  const WorldStats& stats() const;
  size_t cachedTiles() const;  // tiles currently held

 private:
  std::unique_ptr<Impl> impl_;
};

// A SimWorld as seen from one OSM level (SimWorld::sampleSeenFrom): what the simulator renders a
// camera frame or a LIDAR sweep on, the level that of the car's lanelet.
class WorldSeenFromLevel : public World {
 public:
  WorldSeenFromLevel(const SimWorld& world, int level) : w_(world), level_(level) {}
  double height(double east, double north) const override { return w_.height(east, north); }
  GroundSample sample(double east, double north) const override { return w_.sampleSeenFrom(east, north, level_); }
  void obstaclesNear(const Eigen::Vector2d& p, double radius, std::vector<const Obstacle*>* out) const override {
    w_.obstaclesNear(p, radius, out);
  }
  std::optional<int> laneOffset(int64_t ego, int64_t other) const override { return w_.laneOffset(ego, other); }

 private:
  const SimWorld& w_;
  int level_;
};

// Throws WorldConfigError on bad options, std::runtime_error if the skeleton has no road.
// `restrictions` (the OSM file's type=restriction relations): the truth builds no turn they forbid
// at the junction node they name (world_junctions.cc turnRestricted).
std::unique_ptr<SimWorld> buildWorld(const skeleton::Skeleton& skeleton, const WorldOptions& options,
                                     const std::vector<osm::Restriction>& restrictions = {});

}  // namespace lanemap::sim
