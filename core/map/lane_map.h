// The lane-level map model of lanemap: Lanelet2's vocabulary (line strings typed by marking,
// lanelets made of a left and a right boundary) in local ENU metres. The simulator's ground truth,
// the mapper's output and the evaluator's input are all a LaneMap; core/io reads and writes it as
// Lanelet2 OSM and GeoJSON.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lanemap::map {

enum class LineType : uint8_t {
  kDashed,    // Lanelet2 type=line_thin subtype=dashed
  kSolid,     // type=line_thin subtype=solid
  kSolidSolid,// type=line_thin subtype=solid_solid (e.g. the double line between directions)
  kCurb,      // type=curbstone
  kVirtual,   // type=virtual (intersection lanelets, lanes with no marking)
  kStopLine,  // type=stop_line
};

enum class LaneletKind : uint8_t { kRoad, kIntersection };
enum class TurnDirection : uint8_t { kNone, kStraight, kLeft, kRight };

struct LineString {
  int64_t id = 0;
  LineType type = LineType::kVirtual;
  std::vector<Eigen::Vector3d> points;  // ENU metres
};

// A road the drive ended on, mapped as far as it was driven (issue 14): where its lanes stop, as
// the station (arc length, m) along the atomic road's polyline the car reached, and the road's
// length there. lanemap's metadata: in the Lanelet2 sidecar and the GeoJSON properties, not tags.
struct PartialRoad {
  double station_m = 0.0;
  double road_length_m = 0.0;
};

struct Lanelet {
  int64_t id = 0;
  LaneletKind kind = LaneletKind::kRoad;
  // LineString ids of the bounds. A bound normally runs in the driving direction; a line shared
  // with a lane of the opposite direction runs against it for one of the two, as in Lanelet2
  // (whose loader aligns bounds by geometry). The centre line always gives the driving direction.
  int64_t left_id = 0;
  int64_t right_id = 0;
  std::vector<Eigen::Vector3d> centre;  // in the driving direction
  std::vector<int64_t> successors;      // lanelet ids
  TurnDirection turn = TurnDirection::kNone;  // intersection lanelets
  // Where it came from: the atomic road E_ij (OSM node ids of I_i, I_j) or the intersection.
  int64_t road_id = -1;
  int64_t from_node = -1;
  int64_t to_node = -1;
  int64_t intersection_id = -1;         // OSM node id of the intersection (intersection lanelets)
  int index_from_left = -1;             // 0 = left-most lane of its road direction
  std::optional<int64_t> stop_line_id;  // LineString at the lanelet's end, if any
  std::optional<PartialRoad> partial;   // a road lanelet of a road mapped only as far as driven
  // How sure the mapper is of this lane, 0..1 (core/mapping/lane_confidence.h); none in maps that
  // do not say (truth, foreign maps). lanemap's metadata: the sidecar and GeoJSON.
  std::optional<double> confidence;
};

// A traffic rule at a stop line (Lanelet2 regulatory elements; see core/io/lanelet2.h for how each is
// written): the OSM control of the junction approach (highway=stop / give_way / traffic_signals)
// at a stop line of the map.
enum class RegulatoryKind : uint8_t {
  kStopSign,      // Lanelet2 traffic_sign, sign_type=stop_sign, ref_line = the stop line
  kGiveWay,       // right_of_way: yield = `lanelets`, right_of_way = `priority`, ref_line = the stop line
                  // (a traffic_sign with sign_type=give_way when no lanelet has priority)
  kTrafficLight,  // traffic_light: refers = the light (`light`), ref_line = the stop line
};

struct RegulatoryElement {
  int64_t id = 0;
  RegulatoryKind kind = RegulatoryKind::kStopSign;
  int64_t stop_line_id = 0;          // LineString of type kStopLine
  std::vector<int64_t> lanelets;     // the lanelets that end at the stop line (they must obey/yield)
  std::vector<int64_t> priority;     // kGiveWay: lanelets with right of way (other approaches)
  // kTrafficLight: the light's bottom edge (2 points, ENU) and height (m). The camera does not map
  // lights: this is an estimate (light_estimated) above the middle of the stop line.
  std::vector<Eigen::Vector3d> light;
  double light_height_m = 1.0;
  bool light_estimated = true;
  int64_t osm_node = -1;             // the OSM node whose highway=* tag gave the rule, if known
};

// A pedestrian crossing (Lanelet2 lanelet subtype=crosswalk): its two edges in the walking
// direction (left edge on the walker's left), and the road lanelets it crosses.
struct Crosswalk {
  int64_t id = 0;
  std::vector<Eigen::Vector3d> left, right;  // ENU, both from one curb to the other
  std::vector<int64_t> crossing;             // road lanelet ids under it
  int64_t road_id = -1;                      // lanemap: the atomic road it lies on, if known
};

struct LaneMap {
  double origin_lat = 0.0;  // ENU origin (degrees, metres)
  double origin_lon = 0.0;
  double origin_alt = 0.0;
  std::vector<LineString> lines;
  std::vector<Lanelet> lanelets;
  std::vector<RegulatoryElement> regulatory_elements;
  std::vector<Crosswalk> crosswalks;

  const LineString* line(int64_t id) const;
  const Lanelet* lanelet(int64_t id) const;
};

const char* toString(LineType t);
const char* toString(TurnDirection t);
const char* toString(RegulatoryKind k);  // "stop_sign", "give_way", "traffic_light"

}  // namespace lanemap::map
